"""``robosoc bench physics``: real-time factor of the quadrotor physics alone.

One default vehicle hovering: spawned 2 m up with its rotors already at the steady speed of
the hover command (the byte nearest to the hover PWM, 121, which carries 99.6 % of the weight,
so it sinks about 1 m in 10 s and stays airborne), no controller and no rendering; sensors,
wind and drag run as in a flight.  Each run resets the world and steps ``seconds`` of simulated
time.  A vehicle resting on the ground costs more per step (MuJoCo solves four contacts), so the
benchmark also prints that case once, for information.  Prints every run, the median and
spread, and last the line ``physics: <median>x real time``.
"""

from __future__ import annotations

import statistics
import time

from rich.console import Console
from rich.progress import Progress

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import default_vehicle
from robosoc.physics import World
from robosoc.physics.mjcf import GRAVITY
from robosoc.physics.propulsion import hover_pwm, steady_state


def measure_physics(seconds: float, runs: int, seed: int = 0, airborne: bool = True) -> list[float]:
    """Real-time factors (simulated seconds per wall second) of ``runs`` timed runs.

    ``airborne = False`` leaves the vehicle at its default spawn, where it drops onto its skids
    and stays there (the hover byte carries slightly less than its weight).
    """
    vehicle = default_vehicle(spawn_position=(0.0, 0.0, 2.0) if airborne else (0.0, 0.0, 0.3))
    scenario = ScenarioConfig()
    world = World([vehicle], scenario.sensors, scenario.wind)
    pwm = round(hover_pwm(vehicle.motor, vehicle.mass, GRAVITY))
    omega = steady_state(vehicle.motor, pwm)[0] if airborne else 0.0
    factors = []
    for _ in range(runs):
        world.reset(seed)
        quad = world.quadrotors[0]
        quad.propulsion.reset([omega] * 4)
        quad.apply_pwm([pwm] * 4)
        start = time.perf_counter()
        world.advance(seconds)
        factors.append(seconds / (time.perf_counter() - start))
    return factors


def run_physics_benchmark(seconds: float, runs: int, console: Console | None = None) -> None:
    """Measure and print the physics real-time factor (median and spread over ``runs``).

    Raises:
        ValueError: ``seconds`` not a finite number of at least one 1 ms step, or ``runs`` below 1.
    """
    from robosoc.config.ranges import check_float, check_int

    check_float("seconds", seconds, 0.001, unit="s")
    check_int("runs", runs, 1)
    console = console or Console()
    console.print(
        f"physics alone: 1 default quadrotor hovering at fixed PWM, 1 ms steps, {seconds:g} s per run, {runs} runs"
    )
    factors = []
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("physics", total=runs)
        for _ in range(runs):
            factors.extend(measure_physics(seconds, 1))
            progress.advance(task)
    for i, factor in enumerate(factors):
        console.print(f"  run {i}: {factor:.1f}x real time ({factor * 1000:.0f} steps/s)")
    ground = measure_physics(seconds, 1, airborne=False)[0]
    console.print(f"  (resting on the ground instead: {ground:.1f}x real time)")
    median = statistics.median(factors)
    console.print(f"  min {min(factors):.1f}x, max {max(factors):.1f}x, spread {max(factors) - min(factors):.1f}x")
    print(f"physics: {median:.1f}x real time")
