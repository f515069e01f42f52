"""A sampling profiler: where a program spends its cycles, by function.

The run is cut into slices of pseudo-random length (mean ``interval`` cycles, uniform between
half and one and a half times that, drawn from a seeded generator so that loops cannot alias
with the sampling and the result is reproducible); at the end of each slice the function
containing the pc is counted.  A function's share of the samples estimates its share of the
cycles; the fast kernel runs unchanged between samples.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from robosoc.chip.single import SingleCoreSoC


@dataclass
class Profile:
    interval: int
    samples: Counter[str] = field(default_factory=Counter)

    @property
    def total(self) -> int:
        return sum(self.samples.values())

    def shares(self) -> list[tuple[str, float]]:
        """(function, fraction of samples), largest first."""
        n = self.total or 1
        return [(name, count / n) for name, count in self.samples.most_common()]

    def table(self, cycles: int, top: int = 15) -> str:
        lines = [f"{'share':>7}  {'cycles (est.)':>14}  function   ({self.total} samples, mean every {self.interval})"]
        for name, share in self.shares()[:top]:
            lines.append(f"{share:7.1%}  {round(share * cycles):>14}  {name}")
        return "\n".join(lines)


class Sampler:
    """The hook for :meth:`SingleCoreSoC.run` that fills a :class:`Profile`."""

    def __init__(self, soc: SingleCoreSoC, profile: Profile, seed: int = 0) -> None:
        self.soc = soc
        self.profile = profile
        self.rng = np.random.default_rng(seed)
        self.lo = max(1, profile.interval // 2)
        self.hi = profile.interval * 3 // 2 + 1

    def first(self) -> int:
        """Cycles to the first sample."""
        return int(self.rng.integers(self.lo, self.hi))

    def __call__(self) -> int:
        """Count the function the core is in; returns the cycles to the next sample."""
        pc = self.soc.state.pc
        sym = self.soc.program.symbol_at(pc) if self.soc.program is not None else None
        self.profile.samples[sym.name if sym is not None else f"0x{pc:08x}"] += 1
        return self.first()
