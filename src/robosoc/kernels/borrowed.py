"""Arrays that hold no reference, for the hot paths of the kernels: ``borrow(a)`` is ``a``,
``row(a, t)`` is ``a[t]`` and ``item(tables, t)`` is ``tables[t]`` (a typed list of named tuples of
arrays, such as the chip's translation tables).

numba counts references to arrays with atomic instructions: every array a function receives (also
inside a named tuple such as :class:`~robosoc.kernels.core.CoreArrays`), every view it takes and
every local that holds one costs a locked increment and decrement.  On a chip whose cores wake for
a few hundred instructions per timer tick, they were half the host time (``perf`` on a sleeping
16x16 chip, 2026-11-27).  An array from :func:`borrow` or :func:`row` has no reference count
(numba skips a null one), so it must not outlive the array it was made from: the kernels borrow
only their own arguments, which their caller holds for the whole call, and pass the borrowed
arrays down to the functions they call.

A null count is still a call: numba calls ``NRT_incref`` and ``NRT_decref`` for every array a
function binds (each argument, each array of a named tuple it unpacks), and they return at once.
The functions the chip calls per instruction stop or device access -- the interpreter
(``run_cores``), the dispatch loop (``run_translated``), the devices (``dev_irq``,
``dev_timer``, ``dev_output``, ``soc_bus``), the stop queue and the chip's network-interface,
sleep and wake functions -- are compiled with ``_nrt=False`` (numba counts no reference in them;
they make no array and keep none), which removed about 40 such calls per interpreter call: a
fifth of a sleeping 16x16 chip's time (``perf``, 2026-11-28).  They are compiled with ``njit(**UNCOUNTED)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic
from numba.typed.typedobjectutils import _container_get_data

#: the njit options of the kernels' functions compiled without reference counts (see the module doc;
#: numba's typing stubs do not list ``_nrt``)
UNCOUNTED: dict[str, Any] = {"cache": True, "_nrt": False}

if TYPE_CHECKING:
    # what a kernel sees; numba's stubs type the call of an @intrinsic as taking the typing context
    # too and as never returning (so every line after it would be unreachable to the checker)
    _ArrayT = TypeVar("_ArrayT", bound=np.ndarray)

    def borrow(a: _ArrayT) -> _ArrayT: ...

    def row(a: np.ndarray, t: int | np.integer) -> np.ndarray: ...

    _ItemT = TypeVar("_ItemT")

    def item(items: Sequence[_ItemT], i: int | np.integer) -> _ItemT: ...

else:

    @intrinsic
    def borrow(typingctx, a):
        """``a`` (any array), borrowed (see the module doc)."""
        if not isinstance(a, types.Array):
            return None

        def codegen(context, builder, signature, args):
            src = context.make_array(a)(context, builder, args[0])
            view = context.make_array(a)(context, builder)
            context.populate_array(
                view, data=src.data, shape=src.shape, strides=src.strides, itemsize=src.itemsize, meminfo=None
            )
            return view._getvalue()

        return a(a), codegen

    @intrinsic
    def row(typingctx, a, t):
        """``a[t]`` of a C-contiguous 2-D array ``a``, borrowed (see the module doc)."""
        if not isinstance(a, types.Array) or a.ndim != 2 or a.layout != "C" or not isinstance(t, types.Integer):
            return None
        row_type = a.copy(ndim=1, layout="C")

        def codegen(context, builder, signature, args):
            src = context.make_array(a)(context, builder, args[0])
            index = context.cast(builder, args[1], t, types.intp)
            cols = builder.extract_value(src.shape, 1)
            data = builder.gep(src.data, [builder.mul(index, cols)])
            view = context.make_array(row_type)(context, builder)
            itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(a.dtype)))
            context.populate_array(
                view,
                data=data,
                shape=cgutils.pack_array(builder, [cols]),
                strides=cgutils.pack_array(builder, [itemsize]),
                itemsize=itemsize,
                meminfo=None,
            )
            return view._getvalue()

        return row_type(a, t), codegen

    @intrinsic
    def item(typingctx, items, i):
        """``items[i]`` of a numba typed list of named tuples of arrays, each array borrowed (see the
        module doc), without bounds check: the list's own ``items[i]`` counts a reference to every
        array of the tuple (atomic, as the tuple is shared), and every function it is passed to
        counts them again."""
        if not isinstance(items, types.ListType) or not isinstance(i, types.Integer):
            return None
        ty = items.item_type
        if not isinstance(ty, types.BaseNamedTuple) or not all(isinstance(m, types.Array) for m in ty.types):
            return None

        def codegen(context, builder, signature, args):
            fnty = ir.FunctionType(ir.IntType(8).as_pointer(), [ir.IntType(8).as_pointer()])
            base_fn = cgutils.get_or_insert_function(builder.module, fnty, "numba_list_base_ptr")
            base = builder.call(base_fn, [_container_get_data(context, builder, items, args[0])])
            ptr = builder.bitcast(base, context.get_data_type(ty).as_pointer())
            index = context.cast(builder, args[1], i, types.intp)
            value = context.data_model_manager[ty].load_from_data_pointer(builder, cgutils.gep(builder, ptr, index))
            members = []
            for k, a in enumerate(ty.types):
                src = context.make_array(a)(context, builder, builder.extract_value(value, k))
                view = context.make_array(a)(context, builder)
                context.populate_array(
                    view, data=src.data, shape=src.shape, strides=src.strides, itemsize=src.itemsize, meminfo=None
                )
                members.append(view._getvalue())
            return context.make_tuple(builder, ty, members)

        return ty(items, i), codegen


__all__ = ["UNCOUNTED", "borrow", "item", "row"]
