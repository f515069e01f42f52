"""KernelEntry: a compiled kernel called by its entry point for argument objects typed once."""

import types

import numpy as np
from numba import njit

from robosoc.chip import kernel_entry
from robosoc.chip.kernel_entry import RETYPE_LIMIT, KernelEntry


@njit(cache=False)
def _weighted_sum(values, weights, scale):
    total = 0.0
    for i in range(values.shape[0]):
        total += values[i] * weights[i]
    return total * scale


def _module() -> types.ModuleType:
    module = types.ModuleType("kernels_under_test")
    module.weighted_sum = _weighted_sum  # type: ignore[attr-defined]
    return module


def test_the_same_objects_and_new_ints_give_the_kernels_results() -> None:
    module = _module()
    call = KernelEntry(module, "weighted_sum")
    values, weights = np.arange(5, dtype=np.float64), np.array([1.0, 0.5, 2.0, 0.0, 3.0])
    expected = sum(v * w for v, w in zip(values.tolist(), weights.tolist(), strict=True))
    for scale in (1, 2, -3, 7):  # typed at the first call, then by the entry point
        assert call(values, weights, scale) == expected * scale
    values[2] = 10.0  # the same array, new contents: read as they are now
    assert call(values, weights, 1) == expected + 8.0 * 2.0


def test_a_new_array_of_another_type_is_typed_again_not_misread() -> None:
    module = _module()
    call = KernelEntry(module, "weighted_sum")
    weights = np.ones(3)
    assert call(np.array([1.0, 2.0, 3.0]), weights, 1) == 6.0
    ints = np.array([4, 5, 6], dtype=np.int32)  # misread as float64 this would be garbage
    assert call(ints, weights, 1) == 15.0
    assert call(np.array([1, 2], dtype=np.int64), np.ones(2), 2) == 6.0


def test_an_argument_that_changes_at_every_call_stays_correct_past_the_retype_limit() -> None:
    module = _module()
    call = KernelEntry(module, "weighted_sum")
    for k in range(RETYPE_LIMIT + 5):
        dtype = np.float64 if k % 2 else np.int64
        assert call(np.full(4, k, dtype=dtype), np.ones(4), 1) == 4.0 * k


def test_a_wrapper_put_in_the_module_is_called_as_it_is() -> None:
    module = _module()
    call = KernelEntry(module, "weighted_sum")
    values, weights = np.ones(2), np.ones(2)
    assert call(values, weights, 1) == 2.0
    seen = []

    def wrapper(*args):  # as robosoc bench fly --breakdown times the chip loop
        seen.append(args)
        return _weighted_sum(*args)

    module.weighted_sum = wrapper  # type: ignore[attr-defined]
    assert call(values, weights, 3) == 6.0
    assert len(seen) == 1
    module.weighted_sum = _weighted_sum  # type: ignore[attr-defined]
    assert call(values, weights, 4) == 8.0 and len(seen) == 1


def test_a_firmware_run_types_its_kernels_once(monkeypatch) -> None:
    from robosoc.config.firmware import FirmwareConfig
    from robosoc.cosim.firmware_run import FirmwareRun
    from robosoc.host.scenario_image import firmware_image

    fw = FirmwareConfig()
    run = FirmwareRun(fw, firmware_image(fw))
    typed = []
    learn = kernel_entry.KernelEntry._learn
    monkeypatch.setattr(
        kernel_entry.KernelEntry, "_learn", lambda self, k, a: typed.append(k.__name__) or learn(self, k, a)
    )
    for k in range(1, 6):
        run.run_to(run.first_cycle + k * 10_000)
        assert run.cycle == run.first_cycle + k * 10_000
        run.chip.close_accounts(run._acc_tiles, run._acc_tasks, run._previous, run._close_out, run._close_routers)
    # the chip loop, the pc check and the period close, each once for the same arrays (the run's
    # first close was made at its start, before the patch)
    assert sorted(typed) == ["bad_pcs", "run_chip"]
