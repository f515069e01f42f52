"""The host's cycle counter, read from compiled code: the chip loop's own breakdown of its host time.

:func:`ticks` is LLVM's ``readcyclecounter`` (the time-stamp counter on x86-64, a read of a few
ten host cycles), callable from the kernels only; :func:`read_ticks` reads it from Python, which
calibrates ticks against ``time.perf_counter`` around a run (``robosoc bench fly --breakdown``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

if TYPE_CHECKING:

    def ticks() -> int: ...

else:

    @intrinsic
    def ticks(typingctx):
        """The host's cycle counter (compiled code only)."""
        sig = types.int64()

        def codegen(context, builder, signature, args):
            fnty = ir.FunctionType(ir.IntType(64), [])
            fn = builder.module.declare_intrinsic("llvm.readcyclecounter", fnty=fnty)
            return builder.call(fn, [])

        return sig, codegen


@njit(cache=True)
def read_ticks() -> int:
    """The host's cycle counter, as the kernels read it."""
    return ticks()


__all__ = ["read_ticks", "ticks"]
