"""Block translation: guest code regions compiled to native code with llvmlite (docs/translation.md).

The interpreter (:mod:`robosoc.kernels.core`) stays the reference and the fallback; this package
only finds regions (:mod:`~robosoc.jit.regions`), writes their LLVM IR
(:mod:`~robosoc.jit.emit_ir`) for a core's build (:mod:`~robosoc.jit.target`), compiles and caches
them (:mod:`~robosoc.jit.compiler`) and keeps the tables the compiled dispatch loop
(:mod:`robosoc.kernels.jit_dispatch`) reads (:mod:`~robosoc.jit.engine`).
"""
