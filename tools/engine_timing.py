"""End-to-end time of ``robosoc run`` with each engine on the suite's test programs, cold translation cache.

Usage::

    python tools/engine_timing.py [--repeats 3] [--engines interp,auto] [--iterations 2,30,300,3000]

Every program of ``tests/programs/program_list.py`` (with and without the multiplier) and the matrix
benchmark at several lengths is built once, then run by ``robosoc run --engine E`` in a fresh
process, engines alternating, ``--repeats`` times each. Before each run the translation cache
(``$ROBOSOC_CACHE/jit``, or ``~/.cache/robosoc/jit``: its entries are lost) is emptied, so ``auto``
and ``jit`` compile everything they translate; numba's cache of the simulator itself stays warm (it
is the same for every engine and is filled by the first command after installing). The table gives
the median wall time per engine and the ratio to the first engine; the last line the worst ratio.
Timing only: the engines' results are compared by the test suite
(tests/programs/test_programs_engines.py).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "programs"))


def _builds(iterations: list[int]) -> list[tuple[str, Path]]:
    from program_list import PROGRAMS

    from robosoc.firmware import MATRIX_BENCH_SOURCE
    from robosoc.toolchain import build_elf

    builds = []
    for name in sorted(PROGRAMS):
        sources, defines, _ = PROGRAMS[name]
        for mul in (False, True):
            builds.append((f"{name} {'mul' if mul else 'no-mul'}", build_elf(sources, mul=mul, defines=defines)))
    for n in iterations:
        defines = {"BENCH_ITERATIONS": n, "BENCH_QUIET": None}
        builds.append((f"matrix_bench x{n} mul", build_elf([MATRIX_BENCH_SOURCE], mul=True, defines=defines)))
    return builds


def _run(elf: Path, engine: str, no_mul: bool) -> float:
    from robosoc.cache import cache_root

    shutil.rmtree(cache_root() / "jit", ignore_errors=True)
    command = [sys.executable, "-m", "robosoc", "run", str(elf), "--engine", engine, "--max-cycles", str(10**11)]
    if no_mul:
        command.append("--no-mul")
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, env=dict(os.environ))
    seconds = time.perf_counter() - start
    if done.returncode not in (0, 4):
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}): {done.stderr.decode()[-400:]}")
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--engines", default="interp,auto")
    parser.add_argument("--iterations", default="2,30,300,3000")
    args = parser.parse_args()
    from robosoc.config.chip import ENGINE_CHOICES as ENGINES

    engines = args.engines.split(",")
    if args.repeats < 1:
        parser.error(f"--repeats: at least 1, got {args.repeats}")
    if len(engines) < 2 or any(e not in ENGINES for e in engines):
        parser.error(f"--engines: two or more of {', '.join(ENGINES)}, comma-separated; got {args.engines!r}")
    try:
        iterations = [int(n) for n in args.iterations.split(",")]
    except ValueError:
        iterations = [0]
    if any(n < 1 for n in iterations):
        parser.error(f"--iterations: positive whole numbers, comma-separated; got {args.iterations!r}")
    builds = _builds(iterations)
    for engine in engines:  # numba's cache filled before anything is timed
        _run(builds[0][1], engine, False)
    print(f"{'program':28} " + " ".join(f"{e:>9}" for e in engines) + "   ratio to " + engines[0])
    worst = (0.0, "")
    for label, elf in builds:
        times: dict[str, list[float]] = {e: [] for e in engines}
        for _ in range(args.repeats):
            for engine in engines:
                times[engine].append(_run(elf, engine, label.endswith("no-mul")))
        med = {e: statistics.median(t) for e, t in times.items()}
        ratios = [med[e] / med[engines[0]] for e in engines[1:]]
        print(f"{label:28} " + " ".join(f"{med[e]:8.2f}s" for e in engines) + "   "
              + " ".join(f"{r:.2f}x" for r in ratios), flush=True)  # fmt: skip
        worst = max(worst, (max(ratios, default=1.0), label))
    print(f"worst: {worst[0]:.2f}x ({worst[1]})")


if __name__ == "__main__":
    main()
