"""The one clock of a flight: simulated time in integer nanoseconds, physics steps and sensor samples.

A flight's time belongs to the world, never to the host: the world advances one physics step
(:data:`PHYSICS_STEP_NS`, 1 ms) at a time, and every ``steps_per_sample`` steps the sensors give a
sample.  The lockstep flight, the host-controller flight and the decoupled physics side all walk
the same :meth:`FlightClock.samples` and :meth:`FlightClock.steps`, so a run is as fast as the host
allows and repeatable; the chip turns the same nanoseconds into its cycles.  Integer nanoseconds
do not drift: sample ``k`` is at exactly ``k * sample_period_ns``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

from robosoc.config.scenario import PHYSICS_DT_S

if TYPE_CHECKING:
    from robosoc.config.scenario import ScenarioConfig

NS_PER_S = 1_000_000_000
PHYSICS_STEP_NS = round(PHYSICS_DT_S * NS_PER_S)
"""One physics step (1 ms) in nanoseconds."""
START_TIME = "2026-01-01T00:00:00Z"
START_NS = 1_767_225_600 * 1_000_000_000
"""When a flight's time 0 is stamped in its logs (MCAP) and on ROS (``/clock``): :data:`START_TIME`
in ns since the Unix epoch.  A fixed date, so that the same flight gives the same bytes, and one
that viewers show as a date rather than as 1970 (ROS 1 also reads time 0 as "no time yet")."""


@dataclass(frozen=True)
class FlightClock:
    """The schedule of a flight: ``sample_count`` sensor samples, ``steps_per_sample`` physics steps each.

    Raises:
        ValueError: a count below 1 (no flight, or a sample period shorter than a step).
    """

    steps_per_sample: int
    sample_count: int

    def __post_init__(self) -> None:
        if self.steps_per_sample < 1:
            raise ValueError(f"steps_per_sample: must be at least 1, got {self.steps_per_sample}")
        if self.sample_count < 1:
            raise ValueError(f"sample_count: must be at least 1, got {self.sample_count}")

    @classmethod
    def of(cls, scenario: ScenarioConfig) -> FlightClock:
        """The clock of ``scenario``: its sensor period in physics steps, its number of samples."""
        return cls(scenario.sensors.period_steps, scenario.samples)

    @property
    def sample_period_ns(self) -> int:
        return self.steps_per_sample * PHYSICS_STEP_NS

    @property
    def duration_ns(self) -> int:
        """The whole flight: every sample's period."""
        return self.sample_count * self.sample_period_ns

    def sample_ns(self, k: int) -> int:
        """When sample ``k`` is taken (the start of its first step)."""
        return k * self.sample_period_ns

    def first_step(self, k: int) -> int:
        """The index of sample ``k``'s first physics step."""
        return k * self.steps_per_sample

    def samples(self) -> range:
        """The samples' indices, in order."""
        return range(self.sample_count)

    def steps(self, k: int) -> Iterator[tuple[int, int]]:
        """The physics steps of sample ``k``: (step within the sample, time at the step's end [ns])."""
        start = self.sample_ns(k)
        for s in range(self.steps_per_sample):
            yield s, start + (s + 1) * PHYSICS_STEP_NS

    def simulated_s(self, samples_done: int) -> float:
        """Seconds of flight in ``samples_done`` whole sample periods."""
        return samples_done * self.sample_period_ns / NS_PER_S


__all__ = ["NS_PER_S", "PHYSICS_STEP_NS", "START_NS", "START_TIME", "FlightClock"]
