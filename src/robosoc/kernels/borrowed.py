"""Arrays that hold no reference, for the hot paths of the kernels: ``borrow(a)`` is ``a`` and
``row(a, t)`` is ``a[t]``.

numba counts references to arrays with atomic instructions: every array a function receives (also
inside a named tuple such as :class:`~robosoc.kernels.core.CoreArrays`), every view it takes and
every local that holds one costs a locked increment and decrement.  On a chip whose cores wake for
a few hundred instructions per timer tick, they were half the host time (``perf`` on a sleeping
16x16 chip, 2026-11-27).  An array from :func:`borrow` or :func:`row` has no reference count
(numba skips a null one), so it must not outlive the array it was made from: the kernels borrow
only their own arguments, which their caller holds for the whole call, and pass the borrowed
arrays down to the functions they call.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

if TYPE_CHECKING:
    # what a kernel sees; numba's stubs type the call of an @intrinsic as taking the typing context
    # too and as never returning (so every line after it would be unreachable to the checker)
    _ArrayT = TypeVar("_ArrayT", bound=np.ndarray)

    def borrow(a: _ArrayT) -> _ArrayT: ...

    def row(a: np.ndarray, t: int | np.integer) -> np.ndarray: ...

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


__all__ = ["borrow", "row"]
