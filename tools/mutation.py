"""Mutation testing of robosoc's pure-Python layers with mutmut, one layer at a time (on demand, not CI).

Usage::

    python tools/mutation.py LAYER [LAYER ...]   # config, control, physics, analysis, cli
    python tools/mutation.py --list              # the layers, their sources and test subsets
    python tools/mutation.py --score LAYER       # re-read the score of a finished run
    python tools/mutation.py --survivors LAYER   # after adding tests: check the survivors (and unchecked) again
    python tools/mutation.py cli --only options files   # only these modules of the layer (run and score)

The layers and their test subsets live in ``pyproject.toml`` under ``[tool.robosoc-mutation.layers]``;
the mutmut settings shared by every layer under ``[tool.mutmut]``.  For each layer the script copies
``src/``, ``tests/`` and ``pyproject.toml`` into ``$ROBOSOC_MUTATION_DIR/<layer>`` (default
``/tmp/robosoc-mutation``), writes that layer's ``only_mutate`` and test selection into the copy's
``[tool.mutmut]``, and runs ``nice -n 10 mutmut run --max-children N`` there (N from
``ROBOSOC_MUTATION_JOBS``, default 1: the machine is shared), with its own ``ROBOSOC_CACHE`` so
numba compiles each kernel once per layer directory and not per mutant.  The repository itself is
never modified.  Each run starts from fresh mutants (``--resume`` keeps the previous ``mutants/``, and
mutmut then checks again only what changed); mutmut's output goes to ``<layer dir>/mutmut.log``.

mutmut maps a function to the tests that called it during its stats run, so a function a shared
(module- or session-scoped) fixture calls would be mapped to the first test using the fixture only;
the copy's ``tests/conftest.py`` gets the hooks of ``tools/mutation_fixture_map.py``, which map it
to every test sharing that fixture.

Score = killed / (mutants - skipped): mutants no selected test reaches ("no tests") and survivors
both count against it.  A mutant whose test process dies of a signal (SIGABRT, SIGSEGV) counts as
killed and is shown as "of which crashed".  The survivors are listed (``mutmut show NAME`` in the layer directory shows
a diff).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import os
import shutil
import subprocess
import sys
import tomllib
from collections import Counter
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
KILLED = {1, 3, 36, 37, -24, 24, 152, 255}  # mutmut's killed, timeout and type-check exit codes
# A test process killed by a signal (SIGABRT, SIGSEGV: e.g. an OpenGL library aborting) failed too:
# mutmut calls it "suspicious", here it counts as killed and is reported as "crashed".
CRASHED = {-6, -11}
STATUS = {0: "survived", 33: "no tests", 5: "no tests", 34: "skipped", None: "not checked"}


def _layers() -> dict[str, dict[str, Any]]:
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    return data["tool"]["robosoc-mutation"]["layers"]


def _toml_list(values: list[str]) -> str:
    return "[" + ", ".join(json.dumps(v) for v in values) + "]"


def prepare(spec: dict[str, Any], workdir: Path, resume: bool) -> None:
    """Copy the tree into ``workdir`` with the layer's settings."""
    workdir.mkdir(parents=True, exist_ok=True)
    if not resume and (workdir / "mutants").exists():
        shutil.rmtree(workdir / "mutants")
    for name in ("src", "tests"):
        target = workdir / name
        if target.exists():
            shutil.rmtree(target)
        shutil.copytree(ROOT / name, target, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    # map what shared fixtures call to every test sharing them (see tools/mutation_fixture_map.py)
    conftest = workdir / "tests" / "conftest.py"
    conftest.write_text(conftest.read_text() + "\n\n" + (ROOT / "tools" / "mutation_fixture_map.py").read_text())
    text = (ROOT / "pyproject.toml").read_text()
    head, sep, rest = text.partition("[tool.mutmut]\n")
    if not sep:
        raise SystemExit("pyproject.toml has no [tool.mutmut] table")
    settings = (
        f"only_mutate = {_toml_list(spec['mutate'])}\n"
        f"pytest_add_cli_args_test_selection = {_toml_list(spec['tests'])}\n"
    )
    for key, value in spec.get("settings", {}).items():  # the layer's own mutmut settings
        settings += f"{key} = {json.dumps(value)}\n"
    (workdir / "pyproject.toml").write_text(head + sep + settings + rest)


def _patterns(layer: str, spec: dict[str, Any], modules: list[str]) -> list[str]:
    """mutmut's mutant-name globs for ``modules`` of the layer (``options`` -> ``robosoc.cli.options.*``)."""
    package = spec["mutate"][0].removeprefix("src/").rsplit("/", 1)[0].replace("/", ".")
    return [f"{package}.{module}.*" for module in modules]


def score(workdir: Path, patterns: list[str] | None = None) -> tuple[Counter[str], list[str]]:
    counts: Counter[str] = Counter()
    survivors = []
    for meta in sorted((workdir / "mutants").rglob("*.meta")):
        for name, code in json.loads(meta.read_text())["exit_code_by_key"].items():
            if patterns and not any(fnmatch.fnmatch(name, p) for p in patterns):
                continue
            status = "killed" if code in KILLED | CRASHED else STATUS.get(code, "suspicious")
            counts[status] += 1
            counts["of which crashed"] += code in CRASHED
            if status in ("survived", "no tests", "suspicious", "not checked"):
                survivors.append(f"{status:9} {name}")
    return counts, survivors


def report(layer: str, workdir: Path, patterns: list[str] | None = None) -> float:
    counts, survivors = score(workdir, patterns)
    total = sum(counts.values()) - counts["skipped"] - counts["of which crashed"]
    value = 100.0 * counts["killed"] / total if total else float("nan")
    detail = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
    if patterns:
        layer += " (" + ", ".join(p.rsplit(".", 2)[-2] for p in patterns) + ")"
    print(f"\n{layer}: mutation score {value:.1f} % ({counts['killed']} of {total} killed; {detail})")
    for line in survivors:
        print("   ", line)
    return value


def run(layer: str, spec: dict[str, Any], workdir: Path, resume: bool, survivors: bool, patterns: list[str]) -> int:
    names: list[str] = list(patterns)
    if survivors:
        names = [line.split()[-1] for line in score(workdir, patterns)[1]]
        if not names:
            print(f"[{layer}] no survivors to check again")
            return 0
        (workdir / "mutants" / "mutmut-stats.json").unlink(missing_ok=True)  # map the new tests too
    prepare(spec, workdir, resume or survivors)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # mutmut puts mutants/src first
    env["ROBOSOC_CACHE"] = str(workdir / "cache")  # numba and firmware builds, kept between runs
    env.update({k: str(v) for k, v in spec.get("env", {}).items()})  # the layer's own (e.g. no browser)
    # mutmut forks a worker per mutant: a BLAS thread pool started before the fork deadlocks the child
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        env[name] = "1"
    jobs = os.environ.get("ROBOSOC_MUTATION_JOBS", "1")
    mutmut = shutil.which("mutmut") or f"{sys.executable} -m mutmut"
    cmd = ["nice", "-n", "10", *mutmut.split(), "run", "--max-children", jobs, *names]
    shown = " ".join(cmd[: len(cmd) - len(names)]) + (
        f" <{len(names)} survivors>" if survivors else (" " + " ".join(names) if names else "")
    )
    print(f"[{layer}] in {workdir}: {shown} > mutmut.log", flush=True)
    with open(workdir / "mutmut.log", "w") as log:
        return subprocess.run(cmd, cwd=workdir, env=env, stdout=log, stderr=subprocess.STDOUT, check=False).returncode


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("layers", nargs="*", help="layers to mutate (see --list)")
    parser.add_argument("--list", action="store_true", help="show the layers and their test subsets")
    parser.add_argument("--score", action="store_true", help="only report the score of a finished run")
    parser.add_argument("--resume", action="store_true", help="keep the previous run's mutants and results")
    parser.add_argument("--survivors", action="store_true", help="check only the previous run's survivors again")
    parser.add_argument("--only", nargs="+", default=[], metavar="MODULE", help="only these modules of the layer")
    args = parser.parse_args()
    layers = _layers()
    if args.list or not args.layers:
        for name, spec in layers.items():
            print(f"{name:9} mutate {' '.join(spec['mutate'])}\n{'':9} tests  {' '.join(spec['tests'])}")
        return 0
    unknown = sorted(set(args.layers) - set(layers))
    if unknown:
        parser.error(f"unknown layer(s) {', '.join(unknown)}; known: {', '.join(layers)}")
    base = Path(os.environ.get("ROBOSOC_MUTATION_DIR", "/tmp/robosoc-mutation"))
    status = 0
    for layer in args.layers:
        workdir = base / layer
        if not args.score:
            patterns = _patterns(layer, layers[layer], args.only)
            code = run(layer, layers[layer], workdir, args.resume, args.survivors, patterns)
            if code != 0:
                print(f"[{layer}] mutmut exited with {code}", file=sys.stderr)
                status = code
        report(layer, workdir, _patterns(layer, layers[layer], args.only))
    return status


if __name__ == "__main__":
    raise SystemExit(main())
