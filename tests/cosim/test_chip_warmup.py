"""The first run's compilation: the callees compiled ahead (in a child process and in this one) are
compiled for exactly the types the chip's main loop calls them with, so numba keeps one version of
each (a second one would mean the main loop compiled its own, and the child's work was wasted)."""

from __future__ import annotations

import importlib
import pickle

from numba.core.caching import _CacheLocator

from robosoc.config.firmware import FirmwareConfig
from robosoc.cosim.chip_warmup import (
    CHILD_KERNELS,
    PARENT_KERNELS,
    kernel_signatures,
    numba_cache_dir,
    throwaway_chip,
)


def _cached_signatures(module: str, name: str) -> list[tuple[object, ...]]:
    """The argument types of every version of ``robosoc.kernels.<module>.<name>`` in numba's cache
    (its index file: a pickled version string, then the pickled (stamp, overloads) pair)."""
    # numba keeps each source folder's kernels in a sub-folder named after its path: other checkouts
    # sharing the cache have their own
    source = importlib.import_module(f"robosoc.kernels.{module}").__file__
    folder = numba_cache_dir() / _CacheLocator.get_suitable_cache_subpath(source)
    (index,) = folder.glob(f"{module}.{name}-*.nbi")
    with index.open("rb") as f:
        pickle.load(f)
        _, overloads = pickle.loads(f.read())
    return [key[0] for key in overloads]


def test_ahead_compiled_callees_have_the_main_loop_types() -> None:
    # the ordinary run path: the main loop compiles (or loads) its callees for the types it uses
    mpsoc = throwaway_chip(FirmwareConfig().seed_chip())
    mpsoc.step(10_000)
    mpsoc.finish_accounting()
    signatures = kernel_signatures(mpsoc)
    assert set(signatures) == set(CHILD_KERNELS) | set(PARENT_KERNELS)
    assert not set(CHILD_KERNELS) & set(PARENT_KERNELS)
    for (module, name), sig in signatures.items():
        assert _cached_signatures(module, name) == [tuple(sig)], f"{module}.{name}"


def test_every_ahead_compiled_callee_is_given_as_many_types_as_it_takes() -> None:
    # a callee whose arguments changed while its listed types did not fails the cold start's
    # compilation (numba: "Signature mismatch"); this holds whatever numba's cache holds
    import inspect

    signatures = kernel_signatures(throwaway_chip(FirmwareConfig().seed_chip()))
    for module, name in (*CHILD_KERNELS, *PARENT_KERNELS):
        function = getattr(importlib.import_module(f"robosoc.kernels.{module}"), name).py_func
        assert len(signatures[module, name]) == len(inspect.signature(function).parameters), f"{module}.{name}"
