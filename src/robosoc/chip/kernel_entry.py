"""A compiled kernel called without numba's typing of its arguments at every call.

numba's dispatcher works out the type of every argument at every call to pick the compiled
version: for the chip loop's some thirty arrays (in named bundles) and a typed list that costs
about 5 µs a call, the compiled code's own unboxing 2 µs.  A lockstep flight calls the chip loop
and the period close once per sensor sample, and there, with the chip's work between two calls
pushing Python's data out of the host's caches, the typing cost the fixed + multiplier flight
about 3 µs per physics step (5 % of its host time).

:class:`KernelEntry` calls a kernel through numba's dispatcher while it learns the argument
types, then through the compiled entry point of those types directly, as long as every argument
that is not a Python ``int`` is the very object it was typed with (an array's dtype, rank and
layout cannot change while it is the same object, and nothing clears the writeable flag of the
chip's arrays; a named bundle of arrays is a tuple, which cannot change at all; an ``int`` is a
64-bit integer to numba, and one too large for it is refused by the compiled code's unboxing).  Any other object
goes through the dispatcher, which types it, and the entry is looked up again for the new
objects; a caller that hands a new object at every call gets the dispatcher's speed, no less:
after :data:`RETYPE_LIMIT` such changes the entry stops looking.  The kernel is looked up in its
module at every call, so a wrapper put there (``robosoc bench fly --breakdown`` times the chip
loop so) is called as it is.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

from numba.core.dispatcher import Dispatcher

__all__ = ["RETYPE_LIMIT", "KernelEntry"]

#: How many times an entry looks up the compiled version for new argument objects before it leaves
#: every further call to the dispatcher.
RETYPE_LIMIT = 8


class KernelEntry:
    """Calls kernel ``name`` of ``module`` (a numba dispatcher) with the compiled version for its
    arguments' types, typed once for the same argument objects.

    Args:
        module: the module the kernel is an attribute of (looked up at each call).
        name: the kernel's name there.
    """

    def __init__(self, module: ModuleType, name: str) -> None:
        self._module = module
        self._name = name
        #: the kernel, the number of arguments, the places of those that were not ints and those
        #: objects, which the entry was found for
        self._kernel: object = None
        self._count = -1
        self._places: tuple[int, ...] = ()
        self._objects: tuple[Any, ...] = ()
        self._ints: tuple[int, ...] = ()
        self._entry: Callable[..., Any] | None = None
        self._lookups = 0

    def __call__(self, *args: Any) -> Any:
        kernel = getattr(self._module, self._name)
        if kernel is self._kernel and len(args) == self._count and self._entry is not None and self._known(args):
            return self._entry(*args)
        result = kernel(*args)
        if isinstance(kernel, Dispatcher) and self._lookups < RETYPE_LIMIT:
            self._lookups += 1
            self._learn(kernel, args)
        return result

    def _known(self, args: tuple[Any, ...]) -> bool:
        """Whether ``args`` are the objects the entry was found for, ints where ints were."""
        for i, known in zip(self._places, self._objects, strict=True):
            if args[i] is not known:
                return False
        for i in self._ints:  # noqa: SIM110 - a loop: all() of a generator takes twice as long here
            if type(args[i]) is not int:
                return False
        return True

    def _learn(self, kernel: Dispatcher, args: tuple[Any, ...]) -> None:
        """Keep the compiled version the dispatcher just called for ``args``' types, if it has one."""
        types = tuple(kernel.typeof_pyval(a) for a in args)
        compiled: Any = kernel.overloads.get(types)  # numba's CompileResult: its entry_point is the compiled call
        self._kernel = kernel
        self._entry = None if compiled is None else compiled.entry_point
        self._count = len(args)
        self._ints = tuple(i for i, a in enumerate(args) if type(a) is int)
        self._places = tuple(i for i, a in enumerate(args) if type(a) is not int)
        self._objects = tuple(args[i] for i in self._places)
