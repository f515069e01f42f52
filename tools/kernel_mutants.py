"""Hand-written mutants of the numba kernels: every one must be killed by the tests named with it.

Usage::

    python tools/kernel_mutants.py            # every mutant, one at a time
    python tools/kernel_mutants.py NAME ...   # some of them (see --list)
    python tools/kernel_mutants.py --list

A mutation tool would recompile the kernels for every one of thousands of mutants; these are a few
plausible single-line bugs, each a (file, original line, mutated line) triple with the tests that
must catch it.  The script copies ``src/``, ``tests/`` and ``pyproject.toml`` to a temporary folder
with its own ``ROBOSOC_CACHE`` (numba's cache folder is named after a digest of the kernel sources,
so each mutant compiles afresh and no stale kernel can hide it), checks that the tests pass on the
unmutated copy, then applies one mutant at a time, runs its tests (``pytest -x``, niced), restores
the file and reports killed or SURVIVED.  The repository is never modified.  Exit status 1 if a
mutant survived.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
K = "src/robosoc/kernels/"

CORE_TESTS = ("tests/chip/test_core_timing.py", "tests/chip/test_self_modifying_code.py",
              "tests/chip/test_instruction_semantics.py")  # fmt: skip
IRQ_TESTS = (
    "tests/chip/test_interrupt_rules.py",
    "tests/chip/test_interrupts.py",
    "tests/chip/test_irq_differential.py",
)
TIMER_TESTS = ("tests/chip/test_timers.py", "tests/chip/test_timer_cause_edges.py")
NOC_TESTS = ("tests/noc/test_route.py", "tests/noc/test_arbitration_edges.py", "tests/noc/test_hermes.py",
             "tests/noc/test_latency.py", "tests/noc/test_wormhole.py")  # fmt: skip
CHIP_TESTS = ("tests/chip/test_quanta_vs_lockstep.py", "tests/chip/test_mpsoc.py")


@dataclass(frozen=True)
class Mutant:
    name: str
    file: str
    original: str  # one whole line of the file, indentation included
    mutated: str
    tests: tuple[str, ...]
    occurrence: int = 0  # 0: the line must be unique in the file; n: its n-th occurrence (1-based)


MUTANTS = [
    # core timing and branches (platform.md §1)
    Mutant("taken-branch-2-cycles", K + "core.py",
           "    return target, cyc + BRANCH_TAKEN_CYCLES, n_taken + 1, 0, 0",
           "    return target, cyc + BRANCH_TAKEN_CYCLES - 1, n_taken + 1, 0, 0", CORE_TESTS),
    Mutant("untaken-branch-3-cycles", K + "core.py",
           "        return pc + 4, cyc + BRANCH_NOT_TAKEN_CYCLES, n_taken, 0, 0",
           "        return pc + 4, cyc + BRANCH_TAKEN_CYCLES, n_taken, 0, 0", CORE_TESTS),
    Mutant("bge-as-bgt", K + "core.py",
           "                    regs_t[rs1] >= regs_t[rs2], pc, imm, cyc, n_taken, base, code, size",
           "                    regs_t[rs1] > regs_t[rs2], pc, imm, cyc, n_taken, base, code, size", CORE_TESTS),
    Mutant("bltu-signed", K + "core.py",
           "                    (regs_t[rs1] & M32) < (regs_t[rs2] & M32), pc, imm, cyc, n_taken, base, code, size",
           "                    regs_t[rs1] < regs_t[rs2], pc, imm, cyc, n_taken, base, code, size", CORE_TESTS),
    Mutant("jump-2-cycles", K + "core.py",
           "                cyc += JUMP_CYCLES",
           "                cyc += JUMP_CYCLES - 1", CORE_TESTS),
    Mutant("mul-latency-off-by-one", K + "core.py",
           "    return MUL_BASE_CYCLES + steps + (31 - c) + 1",
           "    return MUL_BASE_CYCLES + steps + (31 - c)", CORE_TESTS),
    # stores into code must invalidate the predecoded row
    Mutant("sw-keeps-stale-decode", K + "core.py",
           "                        dec_t[wi << U1] = 0  # the word may be code: decode it again",
           "                        pass", CORE_TESTS, occurrence=1),
    Mutant("sb-sh-keep-stale-decode", K + "core.py",
           "                        dec_t[wi << U1] = 0  # the word may be code: decode it again",
           "                        pass", CORE_TESTS, occurrence=2),
    Mutant("sb-sh-invalidate-wrong-word", K + "core.py",
           "                    wi = np.uint64(off) >> U2",
           "                    wi = np.uint64(off) >> U1", CORE_TESTS, occurrence=2),
    # interrupt controller (platform.md §2-§3)
    Mutant("irq-epc-plus-4", K + "dev_irq.py",
           "    st[S_IRQ_EPC] = epc & M32",
           "    st[S_IRQ_EPC] = (epc + 4) & M32", IRQ_TESTS),
    Mutant("irq-entry-one-cycle-late", K + "dev_irq.py",
           "    if t < 0 or cyc < t + ENTRY_DELAY:",
           "    if t < 0 or cyc < t + ENTRY_DELAY + 1:", IRQ_TESTS),
    Mutant("irq-vector-bubble-extra", K + "dev_irq.py",
           "    return vector, cyc + VECTOR_BUBBLES",
           "    return vector, cyc + VECTOR_BUBBLES + 1", IRQ_TESTS),
    Mutant("irq-reenable-delay", K + "dev_irq.py",
           "                st[S_IRQ_IDLE] = s + IDLE_DELAY",
           "                st[S_IRQ_IDLE] = s + IDLE_DELAY + 1", IRQ_TESTS),
    # timers
    Mutant("timer0-off-by-one", K + "dev_timer.py",
           "        return x & 0xFFFFFFFF, True",
           "        return (x + 1) & 0xFFFFFFFF, True", TIMER_TESTS),
    Mutant("timercause-bit1-from-bit17", K + "dev_timer.py",
           "    cause |= ((x >> 18) & 1) << 1",
           "    cause |= ((x >> 17) & 1) << 1", TIMER_TESTS),
    Mutant("timer1-below-ocr-inclusive", K + "dev_timer.py",
           "    cause |= (1 if v < _ocr_at(st, x) else 0) << 3",
           "    cause |= (1 if v <= _ocr_at(st, x) else 0) << 3", TIMER_TESTS),
    # NoC routing and arbitration (docs/noc.md)
    Mutant("yx-routing-eastwards", K + "noc.py",
           "    if dx > x:",
           "    if dx > x and dy == y:", NOC_TESTS),
    Mutant("yx-routing-westwards", K + "noc.py",
           "    if dx < x:",
           "    if dx < x and dy == y:", NOC_TESTS),
    Mutant("hermes-request-one-cycle-late", K + "noc.py",
           "                    if port[t, p, P_HREQ] <= cycle:",
           "                    if port[t, p, P_HREQ] < cycle:", NOC_TESTS),
    Mutant("hermes-release-one-cycle-early", K + "noc.py",
           "HERMES_RELEASE = 2  # an output whose tail crossed in cycle c is free for a new connection from c + 2",
           "HERMES_RELEASE = 1  # an output whose tail crossed in cycle c is free for a new connection from c + 2",
           NOC_TESTS),
    Mutant("per-output-round-robin-stuck", K + "noc.py",
           "                        port[t, o, P_RR] = p + 1 if p + 1 < NPORTS else 0",
           "                        port[t, o, P_RR] = first", (*NOC_TESTS, "tests/noc/test_traffic.py")),
    Mutant("credit-not-spent", K + "noc.py",
           "                port[t, o, P_CREDIT] -= 1",
           "                pass", NOC_TESTS),
    # chip quanta (kernels/chip.py): a quantum longer than the lookahead must change results
    Mutant("send-does-not-shrink-quantum", K + "chip.py",
           "                    H = s0 + look_idle",
           "                    H = H", CHIP_TESTS),
    # per-task accounting (kernels/chip.py): the last tile's time since its last TASK_ID store unattributed
    Mutant("account-all-skips-last-tile", K + "chip.py",
           "    for t in range(cst.shape[0]):",
           "    for t in range(cst.shape[0] - 1):", ("tests/chip/test_chip_totals.py",)),
]  # fmt: skip

#: Open: mutants the tests do not catch yet (``--open`` runs them).  Each is a quantum longer than the
#: lookahead that docs/platform.md derives; the lockstep comparisons' traffic never meets that margin.
OPEN_MUTANTS = [
    Mutant("active-quantum-too-long", K + "chip.py",
           "                H = T + look_active",
           "                H = T + look_active + 4", CHIP_TESTS),
    Mutant("idle-quantum-past-the-noc", K + "chip.py",
           "                    H = nxt",
           "                    H = H", CHIP_TESTS),
]  # fmt: skip


def _replace(text: str, m: Mutant) -> str:
    lines = text.split("\n")
    hits = [i for i, line in enumerate(lines) if line == m.original]
    if m.occurrence == 0 and len(hits) != 1:
        raise SystemExit(f"{m.name}: the original line occurs {len(hits)} times in {m.file}, expected once")
    if m.occurrence > len(hits):
        raise SystemExit(f"{m.name}: the original line occurs {len(hits)} times, not {m.occurrence}")
    lines[hits[max(m.occurrence, 1) - 1]] = m.mutated
    return "\n".join(lines)


def _pytest(work: Path, tests: tuple[str, ...], env: dict[str, str], timeout: int) -> tuple[int, str]:
    cmd = ["nice", "-n", "10", sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", *tests]
    try:
        proc = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return -1, "timeout"
    lines = [line for line in proc.stdout.splitlines() if line.strip()]
    return proc.returncode, lines[-1] if lines else proc.stderr.strip()[-200:]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("names", nargs="*", help="mutants to run (default: all)")
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--timeout", type=int, default=1800, help="seconds per pytest run")
    parser.add_argument("--open", action="store_true", help="run the open mutants (not caught yet) instead")
    args = parser.parse_args()
    mutants = OPEN_MUTANTS if args.open else MUTANTS
    for m in mutants:  # every triple must apply to today's source before anything runs
        _replace((ROOT / m.file).read_text(), m)
    if args.list:
        for m in mutants:
            print(f"{m.name:34} {m.file.removeprefix(K)}: {m.original.strip()}  ->  {m.mutated.strip()}")
        return 0
    by_name = {m.name: m for m in mutants}
    unknown = [n for n in args.names if n not in by_name]
    if unknown:
        parser.error(f"unknown mutant(s): {', '.join(unknown)}")
    chosen = [by_name[n] for n in args.names] or mutants

    with tempfile.TemporaryDirectory(prefix="robosoc-kernel-mutants-") as tmp:
        work = Path(tmp)
        for name in ("src", "tests"):
            shutil.copytree(ROOT / name, work / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        shutil.copy2(ROOT / "pyproject.toml", work / "pyproject.toml")
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env["PYTHONPATH"] = str(work / "src")
        env["ROBOSOC_CACHE"] = str(work / "cache")
        all_tests = tuple(dict.fromkeys(t for m in chosen for t in m.tests))
        start = time.monotonic()
        code, summary = _pytest(work, all_tests, env, args.timeout)
        print(f"baseline (unmutated): {summary} [{time.monotonic() - start:.0f} s]", flush=True)
        if code != 0:
            print("the tests fail without any mutant: fix that first", file=sys.stderr)
            return 2
        baseline_numba = set((work / "cache" / "numba").iterdir())
        survived = []
        for m in chosen:
            path = work / m.file
            text = path.read_text()
            path.write_text(_replace(text, m))
            start = time.monotonic()
            try:
                code, summary = _pytest(work, m.tests, env, args.timeout)
            finally:
                path.write_text(text)
                for folder in set((work / "cache" / "numba").iterdir()) - baseline_numba:
                    shutil.rmtree(folder, ignore_errors=True)  # this mutant's compiled kernels
            verdict = {1: "killed", 0: "SURVIVED", -1: "killed (timeout)"}.get(code, f"killed (exit {code})")
            if code == 0:
                survived.append(m.name)
            print(f"{verdict:10} {m.name:34} {summary} [{time.monotonic() - start:.0f} s]", flush=True)
    print(f"\n{len(chosen) - len(survived)} of {len(chosen)} kernel mutants killed"
          + (f"; survived: {', '.join(survived)}" if survived else ""))  # fmt: skip
    return 1 if survived else 0


if __name__ == "__main__":
    raise SystemExit(main())
