"""Compiled kernels' common parts: numba's ``njit`` as the project uses it, and the fused
multiply-add that NumPy's small matrix products round with.

Every kernel is compiled with ``cache=True`` (the machine code is kept beside the source, in
``__pycache__``, and loaded in a fraction of a second by later processes) and without fast-math:
LLVM then neither reorders sums nor fuses a product into an addition on its own, so a kernel's
numbers follow its source operation by operation, as NumPy's do. Where NumPy's numbers come from
OpenBLAS (``np.matmul`` of 3 x 3 stacks), the kernel writes OpenBLAS's order out with
:func:`fma` (one rounding for ``a * b + c``), so the compiled step gives NumPy's numbers to the
bit (``tests/unit/test_compiled_step.py``).

``AERODOCK_JIT=0`` in the environment runs the same kernels as plain Python (numba's
``NUMBA_DISABLE_JIT``): slow, for a debugger or a coverage run, with the same numbers except
where :func:`fma` is involved (plain Python rounds twice there).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

if os.environ.get("AERODOCK_JIT", "1") == "0":  # before numba reads its configuration
    os.environ.setdefault("NUMBA_DISABLE_JIT", "1")

import numba  # noqa: E402
from llvmlite import ir  # noqa: E402
from numba.core import cgutils, types  # noqa: E402
from numba.extending import intrinsic  # noqa: E402

JIT_ENABLED = not numba.config.DISABLE_JIT


def njit(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``numba.njit`` as every kernel uses it: cached on disk, no fast-math, errors on the
    first call rather than a silent fall back to object mode."""
    return numba.njit(cache=True, fastmath=False, nogil=True)(fn)


@intrinsic
def _fma_intrinsic(typingctx: Any, a: Any, b: Any, c: Any) -> Any:
    """LLVM's ``llvm.fma.f64``: ``a * b + c`` rounded once (the FMA instruction)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        fnty = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * 3)
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.fma.f64")
        return builder.call(fn, args)

    return sig, codegen


if JIT_ENABLED:
    fma = _fma_intrinsic
else:  # the plain-Python run of the kernels: a * b + c, rounded twice
    def fma(a: float, b: float, c: float) -> float:
        """``a * b + c`` (rounded twice without the compiler)."""
        return a * b + c
