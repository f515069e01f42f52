"""Table I: the energy parts add up, the orderings are judged right, the output round-trips."""

import csv
import io
import json
import math
from dataclasses import replace as dataclass_replace

import numpy as np
import pytest

from robosoc.analysis.accuracy import PwmAgreement, QuaternionError
from robosoc.records import JobRecord
from robosoc.sweep import table_one
from robosoc.sweep.table_one import ENERGY_PARTS, BuildRun, TableSpec, check_orderings, reference_figures, task_row

SEED_TABLE_I = reference_figures()  # the shipped quadrotor project's: the seed paper's Table I


def _job(k: int, parts: tuple[float, float, float, float], exec_cycles: int, response: int) -> JobRecord:
    return JobRecord(
        task="pid", tile=(1, 0), job=k, release_cycle=1000 * k, start_cycle=1000 * k + 1,
        completion_cycle=1000 * k + response, exec_cycles=exec_cycles, deadline_met=True, instructions=10,
        energy_pj=dict(zip(ENERGY_PARTS, parts, strict=True)), spans_periods=False,
    )  # fmt: skip


def test_task_row_means_and_parts_add_up_to_the_total() -> None:
    jobs = [
        _job(0, (1000.0, 100.0, 10.0, 3000.0), 250, 260),
        _job(1, (3000.0, 300.0, 30.0, 1000.0), 750, 800),
    ]
    row = task_row(jobs, "pid", "fixed+mul", "event", clock_ns=4.0)
    assert row.jobs == 2
    # hand-derived: means 2000, 200, 20, 2000 pJ = 2.0, 0.2, 0.02, 2.0 nJ
    assert (row.energy_nj_task, row.energy_nj_kernel, row.energy_nj_noc, row.energy_nj_idle) == pytest.approx(
        (2.0, 0.2, 0.02, 2.0)
    )
    assert row.energy_nj == row.energy_nj_task + row.energy_nj_kernel + row.energy_nj_noc + row.energy_nj_idle
    assert row.energy_nj == pytest.approx(sum(j.energy_total_pj for j in jobs) / 2 / 1000, rel=1e-15)
    assert row.exec_cycles_mean == 500 and row.exec_cycles_max == 750
    assert row.exec_us_mean == pytest.approx(2.0)  # 500 cycles at 4 ns
    assert row.response_us_mean == pytest.approx(530 * 4e-3) and row.response_us_max == pytest.approx(3.2)


def test_no_jobs_gives_nan_not_a_crash() -> None:
    row = task_row([], "pid", "fixed+mul", "event", 4.0)
    assert row.jobs == 0 and math.isnan(row.energy_nj)


def _run(build: str, response: dict[str, float], energy: dict[str, float]) -> BuildRun:
    nan_err = QuaternionError(0, math.nan, math.nan, math.nan, math.nan)
    tasks = {}
    for task in ("estimator", "pid"):
        r = task_row([], task, build, "event", 4.0)
        tasks[task] = r.__class__(**{**r.__dict__, "jobs": 1, "response_us_mean": response[task],
                                     "energy_nj": energy[task]})  # fmt: skip
    return BuildRun(build, "event", "replay", 1, 0, tasks, 1.0, 1.0, 0, nan_err, nan_err, nan_err,
                    PwmAgreement(0, math.nan, 0, math.nan), 0.0)  # fmt: skip


def test_orderings_are_judged_on_the_measured_figures_and_the_seeds() -> None:
    # fixed faster than float, multiplier faster than none, except one inversion: fixed-no-mul's
    # PID energy below fixed+mul's
    runs = [
        _run("float+mul", {"estimator": 4.0, "pid": 2.0}, {"estimator": 40.0, "pid": 20.0}),
        _run("float-no-mul", {"estimator": 8.0, "pid": 4.0}, {"estimator": 80.0, "pid": 40.0}),
        _run("fixed+mul", {"estimator": 1.0, "pid": 0.5}, {"estimator": 10.0, "pid": 9.0}),
        _run("fixed-no-mul", {"estimator": 2.0, "pid": 1.0}, {"estimator": 20.0, "pid": 8.0}),
    ]
    checks = {(c.task, c.metric, c.lower, c.higher): c for c in check_orderings(runs)}
    assert len(checks) == 2 * 2 * len(table_one.ORDERINGS)
    assert checks[("estimator", "response", "fixed+mul", "float+mul")].holds is True
    assert checks[("pid", "energy", "fixed+mul", "fixed-no-mul")].holds is False
    assert checks[("pid", "energy", "fixed-no-mul", "float-no-mul")].holds is True
    assert checks[("estimator", "energy", "float+mul", "fixed-no-mul")].holds is False  # 40 > 20
    # the seed's own table: every pairwise ordering holds, but its text's claim that soft-float with the
    # multiplier beats fixed point without it in energy fails for the PID (1781.1 nJ > 1776.7 nJ)
    seed = {(c.task, c.metric, c.lower, c.higher): c.seed_holds for c in checks.values()}
    assert seed[("pid", "energy", "float+mul", "fixed-no-mul")] is False
    assert SEED_TABLE_I[("pid", "float+mul")].energy_nj > SEED_TABLE_I[("pid", "fixed-no-mul")].energy_nj
    assert all(v for (t, m, lo, hi), v in seed.items() if (lo, hi) != ("float+mul", "fixed-no-mul"))


def test_an_unmeasured_build_leaves_the_ordering_open() -> None:
    runs = [_run("fixed+mul", {"estimator": 1.0, "pid": 1.0}, {"estimator": 1.0, "pid": 1.0})]
    assert all(c.holds is None for c in check_orderings(runs))


def test_spec_is_checked() -> None:
    with pytest.raises(ValueError, match="iterations"):
        TableSpec(iterations=0)
    with pytest.raises(ValueError, match="releases"):
        TableSpec(releases=("sometimes",))
    with pytest.raises(ValueError, match="workers"):
        TableSpec(workers=0)
    # the window follows the take-off: 3 s of calibration, then the samples measured
    assert TableSpec(iterations=100).scenario().duration_s == pytest.approx(4.0)


@pytest.fixture(scope="module")
def small_table() -> table_one.TableResult:
    return table_one.measure_table(TableSpec(iterations=4, releases=("event",), workers=1))


def test_measured_table_has_every_build_and_its_parts_add_up(small_table: table_one.TableResult) -> None:
    runs = {r.build: r for r in small_table.runs}
    assert set(runs) == {"float+mul", "float-no-mul", "fixed+mul", "fixed-no-mul"}
    for run in runs.values():
        assert run.samples == 4 and run.samples_without_command == 0
        for row in run.tasks.values():
            assert row.jobs == 4  # event release: one job per sample and task
            assert row.deadline_misses == 0
            assert row.energy_nj == row.energy_nj_task + row.energy_nj_kernel + row.energy_nj_noc + row.energy_nj_idle
            assert row.energy_nj_task > 0 and row.energy_nj_kernel > 0 and row.energy_nj_idle > 0
            assert row.exec_us_mean <= row.response_us_mean <= row.response_us_max
        # the end-to-end latency covers both tasks' execution
        assert run.latency_us_mean > run.tasks["estimator"].exec_us_mean + run.tasks["pid"].exec_us_mean
        assert run.pwm.within_one == 1.0  # the firmware follows the golden model on the same samples
    # the work itself orders as the seed's: fixed < float, multiplier < none
    est = {b: r.tasks["estimator"].exec_cycles_mean for b, r in runs.items()}
    assert est["fixed+mul"] < est["fixed-no-mul"] < est["float+mul"] < est["float-no-mul"]
    assert set(small_table.fixed_vs_float) == {("event", True), ("event", False)}
    assert small_table.fixed_vs_float[("event", True)].mean_component < table_one.SEED_MEAN_ERROR_FIXED_FLOAT


def test_json_and_csv_round_trip(small_table: table_one.TableResult) -> None:
    data = json.loads(json.dumps(table_one.to_json(small_table), allow_nan=False))
    assert data["schema"] == 1 and len(data["runs"]) == 4
    for run in data["runs"]:
        for task in run["tasks"].values():
            parts = [task[f"energy_nj_{p}"] for p in ENERGY_PARTS]
            assert task["energy_nj"] == parts[0] + parts[1] + parts[2] + parts[3]
    buffer = io.StringIO()
    csv.writer(buffer).writerows([table_one.CSV_FIELDS, *table_one.csv_rows(small_table)])
    rows = list(csv.DictReader(io.StringIO(buffer.getvalue())))
    assert len(rows) == 8
    for row in rows:
        total = sum(float(row[f"energy_nj_{p}"]) for p in ENERGY_PARTS)
        assert float(row["energy_nj"]) == pytest.approx(total, rel=1e-12)
    text = "\n".join(table_one.format_table(small_table))
    assert "Table I" in text and "[87,500.0]" in text  # the seed's EKF response for fixed+mul, in us


def _without_host_time(result: table_one.TableResult) -> dict:
    data = table_one.to_json(result)
    for run in data["runs"]:
        run.pop("host_seconds")
    data.pop("spec")
    return data


def test_builds_measured_in_worker_processes_equal_those_measured_in_turn() -> None:
    seen: list[tuple[str, int, int]] = []
    spec = dict(iterations=2, releases=("event",))
    parallel = table_one.measure_table(TableSpec(**spec, workers=2), lambda *a: seen.append(a))
    serial = table_one.measure_table(TableSpec(**spec, workers=1))
    assert json.dumps(_without_host_time(parallel)) == json.dumps(_without_host_time(serial))
    assert [r.build for r in parallel.runs] == ["float+mul", "float-no-mul", "fixed+mul", "fixed-no-mul"]
    # every build reports its progress from its worker, and ends reported whole
    finals = [a for a in seen if a[1:] == (1, 1)]
    assert finals[-4:] == [(f"{b} event", 1, 1) for b in ("float+mul", "float-no-mul", "fixed+mul", "fixed-no-mul")]
    assert {key for key, _, _ in seen} >= {f"{b} event" for b in ("float+mul", "fixed-no-mul")}
    # and each build's worker sent samples done on the way (every tenth), read while the builds ran
    for b in ("float+mul", "float-no-mul", "fixed+mul", "fixed-no-mul"):
        steps = [(k, total) for key, k, total in seen if key == f"{b} event" and (k, total) != (1, 1)]
        assert steps and all(k % 10 == 0 or k == total for k, total in steps), b
        assert steps[0][0] < steps[0][1] and len({total for _, total in steps}) == 1, b
    assert parallel.run("fixed+mul", "event") is parallel.runs[2]
    assert parallel.run("fixed+mul", "periodic") is None and parallel.run("fixed", "event") is None


def test_default_workers_are_the_cores_up_to_the_four_builds(monkeypatch) -> None:
    for cores, workers in ((None, 1), (1, 1), (2, 2), (4, 4), (64, 4)):
        monkeypatch.setattr(table_one.os, "cpu_count", lambda c=cores: c)
        assert table_one.default_workers() == workers


def test_first_armed_is_the_take_off_sample() -> None:
    from robosoc.control.flight import ROW_FIELDS

    rows = np.zeros((6, len(ROW_FIELDS)))
    assert table_one.first_armed(rows) == 6
    rows[3:, ROW_FIELDS.index("armed")] = 1.0
    rows[1, ROW_FIELDS.index("armed")] = 0.5  # not above one half
    assert table_one.first_armed(rows) == 3


def _summarise_case(armed_from: int):
    """Eight samples 1000 cycles apart (at 4 ns), armed from ``armed_from``; measured over 4 iterations."""
    from robosoc.analysis.accuracy import GoldenRun
    from robosoc.control.flight import ROW_FIELDS
    from robosoc.cosim.firmware_run import ReplayResult, TelemetryRead
    from robosoc.host.telemetry import ESTIMATE_QUATERNION
    from robosoc.records import PwmCommand, SampleInput

    n = 8
    rows = np.zeros((n, len(ROW_FIELDS)))
    rows[armed_from:, ROW_FIELDS.index("armed")] = 1.0
    rows[:, ROW_FIELDS.index("qw")] = 1.0  # truth: level all along
    golden_q = np.tile([0.0, 1.0, 0.0, 0.0], (n, 1))  # outside the window: far from everything
    golden_q[2:6] = [1.0, 0.0, 0.0, 0.0]
    golden_q[2] = [0.0, 0.0, 0.0, 1.0]
    golden = GoldenRun(golden_q, np.zeros(n), np.zeros(n), np.zeros((n, 4), dtype=np.int64), np.ones(n, bool))
    samples = [SampleInput(k, k * 0.01, 1000 * k + 100, b"") for k in range(n)]
    pwm = {1: (9, 9, 9, 9), 2: (1, 1, 1, 1), 3: (5, 0, 0, 0), 5: (0, 0, 0, 0), 6: (9, 9, 9, 9)}
    delay = {1: 10, 2: 250, 3: 500, 5: 750, 6: 99_000}  # cycles from the sample to its command
    commands = [PwmCommand(k, pwm[k], samples[k].cycle + delay[k]) for k in pwm]
    parts = dict(zip(ENERGY_PARTS, (1.0, 2.0, 3.0, 4.0), strict=True))
    jobs = []
    for k in (5, 1, 3, 2, 0, 4, 6):  # out of order; estimator job k released at sample k + 1
        release = samples[k + 1].cycle
        jobs.append(
            JobRecord("estimator", (0, 1), k, release, release + 1, release + 300 + k, 300, True, 10, parts, False)
        )
    pid = _job(0, (1.0, 1.0, 1.0, 1.0), 100, 200)
    jobs.append(dataclass_replace(pid, release_cycle=samples[3].cycle, completion_cycle=samples[3].cycle + 200))
    quaternions = {1: (0, 1, 0, 0), 2: (1, 0, 0, 0), 3: (0.6, 0.8, 0, 0), 5: (1, 0, 0, 0), 7: (0, 1, 0, 0)}
    estimates = [TelemetryRead(k, dict(zip(ESTIMATE_QUATERNION, q, strict=True))) for k, q in quaternions.items()]
    fw = table_one.build_config("fixed", True, "periodic")
    result = ReplayResult(fw, 4.0, samples, commands, jobs, {}, {}, {}, {}, 9100, 1.25, telemetry=estimates)
    return table_one.summarise(result, rows, golden, 4, "replay")


def test_summarise_measures_the_window_after_take_off_by_hand() -> None:
    run = _summarise_case(armed_from=2)
    assert (run.build, run.release, run.source) == ("fixed+mul", "periodic", "replay")
    assert (run.samples, run.first_sample, run.host_seconds) == (4, 2, 1.25)
    # commands of samples 2, 3 and 5 (sample 4 has none): 250, 500, 750 cycles of 4 ns
    assert run.latency_us_mean == pytest.approx(2.0) and run.latency_us_max == pytest.approx(3.0)
    assert run.samples_without_command == 1
    # estimator jobs released from the window's first sample on (k = 1.. at samples 2..), the first four
    est = run.tasks["estimator"]
    assert (est.task, est.build, est.release, est.jobs) == ("estimator", "fixed+mul", "periodic", 4)
    assert est.response_us_max == pytest.approx((300 + 4) * 4 / 1000)  # jobs k = 1..4
    assert est.response_us_mean == pytest.approx((300 + 2.5) * 4 / 1000)
    assert run.tasks["pid"].jobs == 1 and run.tasks["pid"].task == "pid"
    # estimates at samples 2, 3, 5: (1,0,0,0), (0.6,0.8,0,0), (1,0,0,0)
    assert sorted(run.estimates) == [2, 3, 5]
    truth = run.estimator_vs_truth
    assert truth.samples == 3 and truth.mean_component == pytest.approx(1.2 / 12) and truth.max_component == 0.8
    assert run.estimator_vs_golden.mean_component == pytest.approx((2 + 1.2) / 12)  # golden at 2 is (0,0,0,1)
    assert run.golden_vs_truth.samples == 4 and run.golden_vs_truth.mean_component == pytest.approx(2 / 16)
    assert run.estimator_vs_golden.mean_percent == pytest.approx(100 * 3.2 / 12)
    # PWM of samples 2, 3, 5 against the golden zeros
    assert (run.pwm.samples, run.pwm.within_one, run.pwm.max_diff) == (3, pytest.approx(2 / 3), 5)
    assert run.pwm.mean_abs_diff == pytest.approx(9 / 12)


def test_summarise_of_a_flight_that_never_took_off_is_empty_not_a_crash() -> None:
    run = _summarise_case(armed_from=8)
    assert (run.samples, run.first_sample, run.samples_without_command) == (8 - 8, 8, 0)
    assert math.isnan(run.latency_us_mean) and math.isnan(run.latency_us_max)
    assert run.tasks["estimator"].jobs == 0 and run.estimator_vs_truth.samples == 0
    assert run.pwm.samples == 0


class _Queue:
    def __init__(self) -> None:
        self.items: list[tuple[str, int, int]] = []

    def put(self, item: tuple[str, int, int]) -> None:
        self.items.append(item)


def test_a_replayed_build_reports_every_sample_or_every_tenth_to_its_worker_queue(monkeypatch) -> None:
    from robosoc.analysis.accuracy import golden_replay
    from robosoc.cosim.replay import built_in_rows

    spec = TableSpec(iterations=3, releases=("periodic",), workers=1)
    scenario = spec.scenario()
    rows = built_in_rows(scenario.duration_s, spec.seed)
    golden = golden_replay(rows, scenario)
    total = len(rows)
    assert total == 303  # 3 s of calibration and the 3 measured samples at 100 Hz
    fw = table_one.build_config("fixed", True, "periodic")
    seen: list[tuple[str, int, int]] = []
    run = table_one.measure_build(fw, spec, rows, golden, lambda *a: seen.append(a))
    assert seen == [("fixed+mul periodic", k, total) for k in range(1, total + 1)]
    assert (run.source, run.samples, run.release) == ("replay", 3, "periodic")

    queue = _Queue()
    monkeypatch.setattr(table_one, "_progress", queue)
    again = table_one.measure_build(fw, spec, rows, golden)
    assert queue.items == [("fixed+mul periodic", k, total) for k in (*range(10, total, 10), total)]
    assert again.tasks["pid"].response_us_mean == run.tasks["pid"].response_us_mean


def test_a_closed_loop_build_flies_the_spec_scenario_and_reports_each_sample() -> None:
    spec = TableSpec(iterations=2, closed_loop=True, seed=3, workers=1)
    seen: list[tuple[str, int, int]] = []
    # not the default firmware (fixed+mul): the build flown is the one asked for
    run = table_one.measure_build(
        table_one.build_config("fixed", False, "event"), spec, None, None, lambda *a: seen.append(a)
    )
    total = round(spec.scenario().duration_s * 100)
    assert total == 302
    assert seen == [("fixed-no-mul event", k, total) for k in range(1, total + 1)]
    assert (run.source, run.build, run.release, run.samples) == ("closed-loop", "fixed-no-mul", "event", 2)
    assert run.first_sample == 300  # take-off at 3 s
    assert run.tasks["estimator"].jobs == 2 and run.pwm.samples == 2


def test_an_ordering_of_equal_figures_does_not_hold_and_one_of_a_missing_figure_is_open() -> None:
    runs = [
        _run("fixed+mul", {"estimator": 2.0, "pid": math.nan}, {"estimator": 5.0, "pid": 1.0}),
        _run("fixed-no-mul", {"estimator": 2.0, "pid": 3.0}, {"estimator": 6.0, "pid": 2.0}),
    ]
    runs[1] = dataclass_replace(runs[1], release="periodic")
    runs.append(dataclass_replace(runs[1], release="event"))
    checks = check_orderings(runs)
    assert {c.release for c in checks} == {"event", "periodic"}
    key = {(c.task, c.metric, c.name, c.lower, c.higher, c.release): c for c in checks}
    name = next(n for n, lo, hi in table_one.ORDERINGS if (lo, hi) == ("fixed+mul", "fixed-no-mul"))
    assert key[("estimator", "response", name, "fixed+mul", "fixed-no-mul", "event")].holds is False  # 2 vs 2
    assert key[("estimator", "energy", name, "fixed+mul", "fixed-no-mul", "event")].holds is True
    assert key[("pid", "response", name, "fixed+mul", "fixed-no-mul", "event")].holds is None  # NaN
    assert key[("pid", "energy", name, "fixed+mul", "fixed-no-mul", "periodic")].holds is None  # not measured


def _with_estimates(run: BuildRun, release: str, source: str, estimates: dict[int, tuple]) -> BuildRun:
    return dataclass_replace(run, release=release, source=source, estimates=estimates)


def test_fixed_builds_are_compared_with_their_float_twin_on_the_samples_both_estimated() -> None:
    base = _run("x", {"estimator": 1.0, "pid": 1.0}, {"estimator": 1.0, "pid": 1.0})
    level, tilted = (1.0, 0.0, 0.0, 0.0), (0.6, 0.8, 0.0, 0.0)
    runs = [
        # a fixed build without its twin in its release mode comes first: the others are still compared
        _with_estimates(dataclass_replace(base, build="fixed+mul"), "periodic", "replay", {1: level}),
        _with_estimates(dataclass_replace(base, build="float+mul"), "event", "replay", {1: level, 2: level, 3: level}),
        _with_estimates(dataclass_replace(base, build="float-no-mul"), "event", "replay", {1: tilted, 2: tilted}),
        _with_estimates(dataclass_replace(base, build="fixed+mul"), "event", "replay", {1: tilted, 2: level, 9: level}),
        _with_estimates(dataclass_replace(base, build="fixed-no-mul"), "event", "replay", {2: tilted, 3: level}),
        _with_estimates(dataclass_replace(base, build="fixed-no-mul"), "closed", "closed-loop", {2: level}),
    ]
    runs.append(_with_estimates(dataclass_replace(base, build="float-no-mul"), "closed", "closed-loop", {2: tilted}))
    out = table_one.fixed_against_float(runs)
    assert set(out) == {("event", True), ("event", False)}
    # fixed+mul against float+mul on samples 1, 2: one tilted against level (|0.4|+|0.8|), one equal
    assert out[("event", True)].samples == 2
    assert out[("event", True)].mean_component == pytest.approx(1.2 / 8)
    # fixed-no-mul against float-no-mul on sample 2 only: equal
    assert out[("event", False)].samples == 1 and out[("event", False)].mean_component == 0.0


def test_the_table_runs_builds_in_workers_only_when_there_are_several_of_each(monkeypatch) -> None:
    calls: list[str] = []
    rows_seen: list[tuple] = []

    progress_seen: list[object] = []

    def fake_build(fw, spec, rows, golden, on_progress=None):
        calls.append("here")
        rows_seen.append((rows, golden))
        progress_seen.append(on_progress)
        return _run(fw.label, {"estimator": 1.0, "pid": 1.0}, {"estimator": 1.0, "pid": 1.0})

    def fake_workers(configs, spec, rows, golden, on_progress):
        calls.append(f"workers {len(configs)}")
        return [fake_build(fw, spec, rows, golden) for fw in configs]

    def fake_rows(seconds, seed):
        return ("rows", seconds, seed)

    def fake_golden(rows, scenario):
        return ("golden", rows, scenario.duration_s)

    from robosoc.analysis import accuracy
    from robosoc.cosim import replay

    monkeypatch.setattr(table_one, "measure_build", fake_build)
    monkeypatch.setattr(table_one, "_in_workers", fake_workers)
    monkeypatch.setattr(table_one, "golden_replay", fake_golden)
    monkeypatch.setattr(replay, "built_in_rows", fake_rows)
    monkeypatch.setattr(accuracy, "golden_replay", fake_golden)

    def report(*args):  # type: ignore[no-untyped-def]
        return None

    table_one.measure_table(TableSpec(iterations=1, workers=1, seed=7), report)
    assert calls == ["here"] * 4 and progress_seen == [report] * 4  # in turn, each build reports its samples
    seconds = TableSpec(iterations=1).scenario().duration_s
    assert rows_seen[0] == (("rows", seconds, 7), ("golden", ("rows", seconds, 7), seconds))
    calls.clear()
    table_one.measure_table(TableSpec(iterations=1, workers=2))
    assert calls == ["workers 4"] + ["here"] * 4
    calls.clear()
    rows_seen.clear()
    table_one.measure_table(TableSpec(iterations=1, workers=2, closed_loop=True))
    assert calls == ["workers 4"] + ["here"] * 4
    assert rows_seen[0] == (None, None)  # each build flies its own flight


def _full_run(build: str, release: str, base: float) -> BuildRun:
    """A run whose every figure differs (so a figure printed in the wrong place shows)."""
    tasks = {
        task: table_one.TaskRow(task, build, release, int(base) + k, base + 0.11 + k, base + 0.22 + k, base + 0.33 + k,
                                10.0, 20, base + 0.44 + k, base + 0.55 + k, base + 0.66 + k, base + 0.77 + k,
                                base + 0.88 + k, k + 2)
        for k, task in enumerate(("estimator", "pid"))
    }  # fmt: skip
    err = QuaternionError(5, 0.0012345, 0.01, 0.12345, 0.5)
    truth = QuaternionError(5, 0.02, 0.05, 1.5, 3.25)
    return BuildRun(build, release, "replay", 7, 300, tasks, base + 0.99, base + 5.0, 3, err, truth,
                    QuaternionError(5, 0.0044, 0.01, 0.25, 0.75), PwmAgreement(5, 0.9, 2, 0.3), 1.0)  # fmt: skip


def test_table_text_puts_every_figure_in_its_row_and_column() -> None:
    runs = [_full_run("float+mul", "periodic", 1000.0), _full_run("fixed-no-mul", "periodic", 3.0)]
    orderings = [
        table_one.OrderingCheck("estimator", "energy", "x", "a", "b", "event", True, False),  # another release
        table_one.OrderingCheck("pid", "energy", "fixed < float (with multiplier)", "fixed+mul", "float+mul",
                                "periodic", True, None),
        table_one.OrderingCheck("estimator", "response", "multiplier < none (fixed)", "fixed+mul", "fixed-no-mul",
                                "periodic", False, True),
        table_one.OrderingCheck("pid", "response", "fixed < float (no multiplier)", "fixed-no-mul", "float-no-mul",
                                "periodic", True, False),
    ]  # fmt: skip
    fixed_vs_float = {
        ("event", True): QuaternionError(4, 0.5, 0.5, 5.0, 5.0),
        ("periodic", False): QuaternionError(4, 0.001, 0.002, 0.1, 0.2),
        ("periodic", True): QuaternionError(4, 0.0025, 0.003, 0.3, 0.4),
    }
    result = table_one.TableResult(TableSpec(releases=("event", "periodic")), runs, orderings, fixed_vs_float)
    lines = table_one.format_table(result)
    # the table's rows: a 30-character label, then four right-aligned 24-character cells
    rows = [
        ("", ["float+mul", "float-no-mul", "fixed+mul", "fixed-no-mul"]),
        ("EKF jobs", ["1,000", "-", "-", "3"]),
        ("EKF response mean (us)", ["1,000.1 [107,010.0]", "- [196,500.0]", "- [87,500.0]", "3.1 [173,000.0]"]),
        ("EKF response max (us)", ["1,000.2", "-", "-", "3.2"]),
        ("EKF execution mean (us)", ["1,000.3", "-", "-", "3.3"]),
        ("EKF energy per job (nJ)", ["1,000.9 [7,252.7]", "- [13,761.6]", "- [6,460.3]", "3.9 [11,776.9]"]),
        ("EKF   task (nJ)", ["1,000.4", "-", "-", "3.4"]),
        ("EKF   kernel (nJ)", ["1,000.5", "-", "-", "3.5"]),
        ("EKF   NoC (nJ)", ["1,000.7", "-", "-", "3.7"]),
        ("EKF   idle (nJ)", ["1,000.8", "-", "-", "3.8"]),
        ("EKF deadline misses", ["2", "-", "-", "2"]),
        ("PID jobs", ["1,001", "-", "-", "4"]),
        ("PID response mean (us)", ["1,001.1 [25,500.0]", "- [34,000.0]", "- [20,000.0]", "4.1 [27,000.0]"]),
        ("PID response max (us)", ["1,001.2", "-", "-", "4.2"]),
        ("PID execution mean (us)", ["1,001.3", "-", "-", "4.3"]),
        ("PID energy per job (nJ)", ["1,001.9 [1,781.1]", "- [2,517.4]", "- [1,480.0]", "4.9 [1,776.7]"]),
        ("PID   task (nJ)", ["1,001.4", "-", "-", "4.4"]),
        ("PID   kernel (nJ)", ["1,001.5", "-", "-", "4.5"]),
        ("PID   NoC (nJ)", ["1,001.7", "-", "-", "4.7"]),
        ("PID   idle (nJ)", ["1,001.8", "-", "-", "4.8"]),
        ("PID deadline misses", ["3", "-", "-", "3"]),
        ("sample -> PWM mean (us)", ["1,001.0", "-", "-", "4.0"]),
        ("samples without a command", ["3", "-", "-", "3"]),
    ]
    assert (
        lines[0] == "Table I — periodic release, replay, 7 samples from take-off per build (seed's figure in brackets)"
    )
    assert lines[1] == (
        "conditions: scenario built-in (sensor noise on), 2x2 mesh, estimator on (0, 1), pid on (1, 0); Q16.16 "
        "multiply without the multiplier: shift-and-add (fix16_mul64_soft, robosoc's)"
    )
    del lines[1]
    for line, (label, cells) in zip(lines[1:], rows, strict=False):
        assert len(line) == 30 + 4 * 24, line
        assert line[:30].rstrip() == label and line[len(label) : 30].strip() == "", line
        for k, cell in enumerate(cells):
            text = line[30 + 24 * k : 54 + 24 * k]
            assert text.strip() == cell and not text.endswith(" "), (line, k)
    assert lines[1 + len(rows) :] == [
        "orderings (lower is better; seed: holds in the seed's Table I; ours: holds here):",
        "  PID energy   fixed < float (with multiplier)              seed yes  ours -",
        "  EKF response multiplier < none (fixed)                    seed NO   ours yes",
        "  PID response fixed < float (no multiplier)                seed yes  ours NO",
        "accuracy (mean error per quaternion component in %, the seed's terms; mean / max angle):",
        "  float+mul     EKF vs float64 golden 0.1234 % (0.1235° / 0.5000°); vs truth 2.000 % (1.500° / 3.250°);"
        " PWM within 1 count of golden 90.0 % (max diff 2)",
        "  fixed-no-mul  EKF vs float64 golden 0.1234 % (0.1235° / 0.5000°); vs truth 2.000 % (1.500° / 3.250°);"
        " PWM within 1 count of golden 90.0 % (max diff 2)",
        "  golden        float64 EKF vs truth 0.440 % (0.250° / 0.750°); seed: EKF vs truth 0.44 %",
        "  fixed vs float (no multiplier): 0.1000 % (0.1000° / 0.2000°); seed: 0.19 %",
        "  fixed vs float (with multiplier): 0.2500 % (0.3000° / 0.4000°); seed: 0.19 %",
        "",
    ]  # the event release has no run: no section


def test_the_release_modes_of_a_table_are_distinct() -> None:
    with pytest.raises(ValueError, match="releases"):
        TableSpec(releases=("event", "event"))


def test_no_jobs_gives_a_row_named_for_its_task_and_build_with_nan_figures() -> None:
    row = task_row([], "estimator", "float-no-mul", "periodic", 4.0)
    assert (row.task, row.build, row.release, row.jobs, row.exec_cycles_max, row.deadline_misses) == (
        "estimator",
        "float-no-mul",
        "periodic",
        0,
        0,
        0,
    )
    floats = ("response_us_mean", "response_us_max", "exec_us_mean", "exec_cycles_mean", "energy_nj_task",
              "energy_nj_kernel", "energy_nj_noc", "energy_nj_idle", "energy_nj")  # fmt: skip
    assert all(math.isnan(getattr(row, name)) for name in floats)
    full = task_row([_job(0, (1.0, 2.0, 3.0, 4.0), 10, 20)], "pid", "fixed+mul", "event", 4.0)
    assert (full.task, full.build, full.release) == ("pid", "fixed+mul", "event")


def test_spec_bounds_are_inclusive() -> None:
    for ok in ({"iterations": 1}, {"iterations": 10_000}, {"workers": 1}, {"workers": 64}):
        TableSpec(**ok)
    for bad, message in (
        ({"iterations": 10_001}, "iterations: must be between 1 and 10000, got 10001"),
        ({"workers": 65}, "workers: must be between 1 and 64, got 65"),
        ({"releases": ("often",)}, "releases: each must be one of event, periodic, got ('often',)"),
        ({"releases": ()}, "releases: each must be one of event, periodic, got ()"),
    ):
        with pytest.raises(ValueError) as info:
            TableSpec(**bad)
        assert str(info.value) == message


def test_table_json_holds_each_run_with_the_seed_figures_and_null_for_nan() -> None:
    run = _full_run("fixed+mul", "event", 5.0)
    run = dataclass_replace(run, latency_us_max=math.nan, estimates={3: (1.0, 0.0, 0.0, 0.0)})
    orderings = [table_one.OrderingCheck("pid", "energy", "n", "fixed+mul", "float+mul", "event", True, None)]
    err = QuaternionError(4, 0.001, 0.002, 0.1, 0.2)
    spec = TableSpec(iterations=7, releases=("event",), workers=1)
    data = table_one.to_json(table_one.TableResult(spec, [run], orderings, {("event", True): err}))
    assert json.loads(json.dumps(data, allow_nan=False)) == data  # plain JSON, no NaN
    assert data["schema"] == 1 and data["clock_ns"] == 4.0
    assert data["spec"] == {"iterations": 7, "releases": ["event"], "closed_loop": False, "seed": 1, "workers": 1}
    (got,) = data["runs"]
    assert "estimates" not in got
    assert got["latency_us_max"] is None and got["latency_us_mean"] == 5.99
    assert got["estimator_vs_golden"]["mean_percent"] == pytest.approx(0.12345)
    assert got["estimator_vs_truth"]["mean_percent"] == pytest.approx(2.0)
    pid = got["tasks"]["pid"]
    assert pid["seed_response_ms"] == SEED_TABLE_I[("pid", "fixed+mul")].response_ms == 20.0
    assert pid["seed_energy_nj"] == SEED_TABLE_I[("pid", "fixed+mul")].energy_nj
    assert pid["response_us_mean"] == 6.11 and pid["deadline_misses"] == 3
    assert data["orderings"] == [
        {"task": "pid", "metric": "energy", "name": "n", "lower": "fixed+mul", "higher": "float+mul",
         "release": "event", "seed_holds": True, "holds": None}
    ]  # fmt: skip
    assert data["fixed_vs_float"] == [
        {"release": "event", "multiplier": True, "samples": 4, "mean_component": 0.001, "max_component": 0.002,
         "mean_deg": 0.1, "max_deg": 0.2, "mean_percent": pytest.approx(0.1)}
    ]  # fmt: skip
    seed = data["seed"]
    assert seed["mean_error_fixed_float"] == table_one.SEED_MEAN_ERROR_FIXED_FLOAT
    assert seed["mean_error_truth"] == table_one.SEED_MEAN_ERROR_TRUTH
    assert len(seed["table_i"]) == 8
    entries = {(e["task"], e["build"]): e for e in seed["table_i"]}
    assert set(entries) == set(SEED_TABLE_I)
    assert entries[("pid", "fixed+mul")]["response_ms"] == 20.0
    assert entries[("estimator", "float+mul")]["energy_nj"] == SEED_TABLE_I[("estimator", "float+mul")].energy_nj
