"""Compiled kernels' common parts: numba's ``njit`` as the project uses it, and the sums NumPy's
small matrix products round with.

Every kernel is compiled with ``cache=True`` (the machine code is kept on disk, in
:func:`cache_dir`, and loaded in a fraction of a second by later processes) and without
fast-math: LLVM then neither reorders sums nor fuses a product into an addition on its own, so a
kernel's numbers follow its source operation by operation, as NumPy's do. Where NumPy's numbers
come from the BLAS kernel (``np.matmul`` of 3 x 3 stacks), the kernels sum each element as that
kernel does on the machine at hand (:func:`dot3_vecmat` and its kin, bound to the order
:mod:`aerodock.product_order` reads at import: fused multiply-adds through :func:`fma`, one
rounding for ``a * b + c``, or plain sums), so the compiled step gives NumPy's numbers to the bit
(``tests/unit/test_compiled_step.py``, ``tests/unit/test_product_order.py``).

``AERODOCK_JIT=0`` in the environment runs the same kernels as plain Python (numba's
``NUMBA_DISABLE_JIT``): slow, for a debugger or a coverage run, with the same numbers except
where :func:`fma` is involved (plain Python rounds twice there).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import Any

if os.environ.get("AERODOCK_JIT", "1") == "0":  # before numba reads its configuration
    os.environ.setdefault("NUMBA_DISABLE_JIT", "1")

from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402
from llvmlite import ir  # noqa: E402
from numba.core import caching, cgutils, types  # noqa: E402
from numba.core.compiler_lock import global_compiler_lock  # noqa: E402
from numba.core.typeconv import Conversion  # noqa: E402
from numba.extending import intrinsic  # noqa: E402

from aerodock.product_order import PRODUCT_ORDERS  # noqa: E402
from aerodock.sources import sources_digest  # noqa: E402

JIT_ENABLED = not numba.config.DISABLE_JIT


def _kernel_sources_digest() -> str:
    """A digest of every package module that holds compiled code (and of numba's version).

    numba keeps a kernel's machine code keyed by its own file only: a kernel that inlines a
    helper from another module would go on running the helper's old code after the helper
    changed. So the cache lives in a folder named by this digest, and any change to any
    kernel's source starts a fresh one. The 3 x 3 products' order on this machine
    (:mod:`aerodock.product_order`) is part of the compiled code, so it is in the digest too."""
    return sources_digest(b"njit", [numba.__version__.encode(),
                                    ",".join(PRODUCT_ORDERS).encode()])[:16]


def cache_dir() -> Path:
    """Where the compiled kernels are kept: ``$AERODOCK_CACHE_DIR`` (default: the user's cache,
    ``~/.cache/aerodock``), in a folder per version of the kernels' sources."""
    base = os.environ.get("AERODOCK_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "aerodock")
    return Path(base) / f"kernels-{_kernel_sources_digest()}"


if "NUMBA_CACHE_DIR" not in os.environ:  # the user's own choice stands
    numba.config.CACHE_DIR = str(cache_dir())


# -- one cache for every copy of the same sources ----------------------------------------------
# numba files a kernel's machine code under a hash of its source file's absolute folder, so two
# copies of the same sources (a second clone, a reinstalled wheel, a CI checkout) compile every
# kernel again (8 minutes here) and keep a copy each. The folder named by the kernels' digest
# (cache_dir) already says which sources the code was compiled from, and numba checks each file's
# bytes (its source stamp is a hash of the file's contents), so aerodock's kernels are filed
# under their path inside the package instead: every copy of the same sources loads the same
# machine code. Other packages' kernels are filed as numba files them (and a user's own
# NUMBA_CACHE_LOCATOR_CLASSES or NUMBA_CACHE_DIR replaces this).
class _PackageCacheLocator(caching.UserProvidedCacheLocator):
    """numba's cache locator for aerodock's own modules: ``CACHE_DIR/<folder in the package>``
    (``aerodock/world/vehicles``) in place of numba's hash of the absolute folder."""

    def __init__(self, py_func: Any, py_file: str) -> None:
        super().__init__(py_func, py_file)
        inside = package_folder(py_file)
        assert inside is not None  # from_function only builds it for the package's files
        self._cache_path = os.path.join(numba.config.CACHE_DIR, inside)

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> Any:
        if package_folder(py_file) is None:
            return None  # not aerodock's: numba's own locators file it
        return super().from_function(py_func, py_file)


_PACKAGE_PARENT = Path(__file__).resolve().parent.parent


def package_folder(py_file: str) -> str | None:
    """The folder of ``py_file`` as a path inside aerodock's parent folder
    (``aerodock/world/vehicles``), or None for a file outside the package."""
    try:
        inside = Path(py_file).resolve().parent.relative_to(_PACKAGE_PARENT)
    except ValueError:
        return None
    return inside.as_posix() if inside.parts[:1] == ("aerodock",) else None


if "NUMBA_CACHE_DIR" not in os.environ:  # numba's own locators file the user's cache folder
    caching.CacheImpl._locator_classes.insert(0, _PackageCacheLocator)


def njit(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``numba.njit`` as every kernel uses it: cached on disk, no fast-math, errors on the
    first call rather than a silent fall back to object mode."""
    return numba.njit(cache=True, fastmath=False, nogil=True)(fn)


def njit_parallel(fn: Callable[..., Any]) -> Callable[..., Any]:
    """:func:`njit` with numba's ``parallel``: its ``numba.prange`` loops run across numba's
    threads (``NUMBA_NUM_THREADS``, default the CPU count; :func:`numba.set_num_threads`).
    Only the loops written as ``prange`` are split, and only over iterations that write apart,
    so the numbers do not depend on the number of threads."""
    return numba.njit(cache=True, fastmath=False, nogil=True, parallel=True)(fn)


# -- one signature for every layout ------------------------------------------------------------
# numba compiles a kernel anew for every combination of its arrays' layouts (C, Fortran, strided)
# and writability it is called with: the world's vehicle kernel (49 arguments) met 27 of them in
# one run of the test suite, each some seconds of compiling, and a user's new configuration (a
# frozen array here, a transposed one there) pays the same. A kernel marked with ``any_layout``
# compiles (or loads from the cache) its first signature as before; when a call then meets a
# second one, the kernel is sealed instead of compiling it: one more signature is added that
# takes every array in any layout, and every array the kernel does not write read-only (so
# writable and read-only ones alike), and compiling stops. That call and every later one of other
# layouts or flags run the general signature (numba's dispatcher picks it in C, converting the
# arguments' types, at the cost of an exact call), with the same numbers: the same source,
# compiled without fast-math, reads the same elements and computes them in the same order. A
# process that only ever meets one signature (a docking run) loads nothing more; a process whose
# first call meets layouts no process compiled loads the general signature if one is cached.


def any_layout(*writes: str, contiguous: tuple[str, ...] = (),
               general_only: bool = False) -> Callable[[Any], Any]:
    """Decorator (above :func:`njit`): the kernel is sealed to one general signature when a call
    meets a signature other than its first (:func:`general_signature`). ``writes`` names the
    array arguments it writes (they stay writable in the general signature; the others become
    read-only); ``contiguous`` those that must stay C-contiguous (the kernel reshapes them).
    ``general_only``: sealed at the first call (a kernel that takes half a minute to compile
    is compiled once, in its general form, rather than first for the first call's layouts).

    Raises:
        ValueError: a name is not one of the kernel's arguments.
    """
    def mark(kernel: Any) -> Any:
        if not JIT_ENABLED:
            return kernel
        import inspect

        names = list(inspect.signature(kernel.py_func).parameters)
        unknown = sorted(set(writes + contiguous) - set(names))
        if unknown:
            raise ValueError(f"{kernel.py_func.__name__} has no argument(s) {unknown}")
        kinds = tuple((name in writes, name in contiguous) for name in names)
        _MARKED.append((kernel, kinds))
        # numba's dispatcher calls this (from C) for a call no compiled signature takes
        kernel._compile_for_args = _SealOnSecondSignature(kernel, kinds,
                                                          kernel._compile_for_args,
                                                          general_only)
        return kernel

    return mark


_MARKED: list[tuple[Any, tuple[tuple[bool, bool], ...]]] = []


def compile_general_signatures() -> int:
    """Compile (into numba's cache) the general signature of every :func:`any_layout` kernel
    this process has met, without sealing it: the install's warm-up calls it, so that a later
    process sealing one of them loads it instead of compiling it. The number compiled."""
    count = 0
    for kernel, kinds in _MARKED:
        general = general_signature(kernel.signatures[0], kinds) if kernel.overloads else None
        if general is not None and general not in kernel.overloads:  # else sealed already
            kernel.compile(general)
            count += 1
    return count


def general_signature(first: tuple[Any, ...],
                      kinds: tuple[tuple[bool, bool], ...]) -> tuple[Any, ...]:
    """``first`` (a compiled signature's argument types) with every array of any layout (C for
    those marked contiguous) and read-only unless written (``kinds``: (written, contiguous) per
    argument), and literal constants as their plain types."""
    out = []
    for typ, (written, contiguous) in zip(first, kinds, strict=True):
        typ = types.unliteral(typ)
        if isinstance(typ, types.Array):
            typ = types.Array(typ.dtype, typ.ndim, "C" if contiguous else "A",
                              readonly=not written)
        out.append(typ)
    return tuple(out)


class _SealOnSecondSignature:
    """A marked kernel's handler of a call that no compiled signature takes: the first
    signature loaded from numba's cache, or, when only the general signature is cached (another
    process compiled it), that one; else compiled as numba does. A later signature
    seals the kernel (its general signature, compiled once and then loaded from numba's cache,
    and no more compiling) when the call's arguments convert to it without loss (a float where
    the first call had an integer does not: it is compiled as numba does, not truncated). Once
    sealed, numba's dispatcher converts a later call's types to the general signature itself,
    as it does for any kernel whose compiling is disabled: the kernels are called with the
    dtypes of their first call."""

    def __init__(self, kernel: Any, kinds: tuple[tuple[bool, bool], ...],
                 compile_for_args: Callable[..., Any], general_only: bool = False) -> None:
        self.kernel, self.kinds, self.compile_for_args = kernel, kinds, compile_for_args
        self.general_only = general_only

    def __call__(self, *args: Any, **kws: Any) -> Any:
        kernel = self.kernel
        if kws or len(args) != len(self.kinds):
            return self.compile_for_args(*args, **kws)
        if kernel.overloads or self.general_only:
            first = (kernel.signatures[0] if kernel.overloads
                     else tuple(kernel.typeof_pyval(a) for a in args))
            general = general_signature(first, self.kinds)
            if all(_converts_safely(kernel, kernel.typeof_pyval(a), t)
                   for a, t in zip(args, general, strict=True)):
                # under numba's lock: another thread sealing the kernel meanwhile has left the
                # general signature installed, and a sealed kernel compiles nothing more
                with global_compiler_lock:
                    entry = _load_cached(kernel, general)
                    if entry is None:
                        entry = kernel.compile(general)
                    kernel.disable_compile()
                return entry  # numba calls it with these arguments
        if not kernel.overloads:
            entry = self._first_from_the_cache(args)
            if entry is not None:
                return entry
        return self.compile_for_args(*args, **kws)

    def _first_from_the_cache(self, args: tuple[Any, ...]) -> Any:
        """A process's first call: its exact signature from numba's disk cache, else the
        general one (another process compiled it for other layouts) when every argument
        converts to it without loss (a Fortran array where the kernel wants C order, or a
        read-only one where it writes, does not), else None (numba compiles the exact one, as
        before). Nothing is sealed here: the next signature the process meets seals the kernel
        as before. Without this, every process whose first call met layouts no earlier process
        had met compiled them again, with the general code cached."""
        kernel = self.kernel
        try:
            exact = tuple(kernel.typeof_pyval(a) for a in args)
            general = general_signature(exact, self.kinds)
        except Exception:  # noqa: BLE001 (a type numba cannot read: numba says so below)
            return None
        entry = _load_cached(kernel, exact)
        if entry is None and general != exact and all(
                _converts_safely(kernel, a, t) for a, t in zip(exact, general, strict=True)):
            entry = _load_cached(kernel, general)
        return entry


def _converts_safely(kernel: Any, actual: Any, wanted: Any) -> bool:
    """Whether numba converts an argument of type ``actual`` to ``wanted`` without loss (exact,
    promoted or safe: not a narrowing, and not at all where the layouts or writability do not
    allow it)."""
    kind = kernel.typingctx.can_convert(actual, wanted)
    return kind is not None and kind <= Conversion.safe


def _load_cached(kernel: Any, signature: tuple[Any, ...]) -> Any:
    """``kernel``'s machine code for ``signature``: already installed, or loaded from numba's
    disk cache and installed as numba's own ``Dispatcher.compile`` installs a cache hit; None
    when it is neither (nothing is compiled)."""
    with global_compiler_lock:
        existing = kernel.overloads.get(signature)
        if existing is not None:
            return existing.entry_point
        cres = kernel._cache.load_overload(signature, kernel.targetctx)
        if cres is None:
            return None
        if not cres.objectmode:
            kernel.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
        kernel.add_overload(cres)
        return cres.entry_point


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


# -- a 3 x 3 product's element, summed as np.matmul sums it on this machine ------------------
# (aerodock.product_order: the order is the BLAS kernel's, found at import; the kernels call
# dot3_vecmat, dot3_matvec, dot3_matmat and dot3_tmatmat, each bound to one of these)
@njit
def _dot3_fma012(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    return fma(a2, b2, fma(a1, b1, a0 * b0))


@njit
def _dot3_fma102(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    return fma(a2, b2, fma(a0, b0, a1 * b1))


@njit
def _dot3_fma012_0(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    return 0.0 + fma(a2, b2, fma(a1, b1, a0 * b0))


@njit
def _dot3_fma102_0(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    return 0.0 + fma(a2, b2, fma(a0, b0, a1 * b1))


@njit
def _dot3_sum0(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    s = 0.0 + a0 * b0
    s += a1 * b1
    return s + a2 * b2


@njit
def _dot3_sum(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    s = a0 * b0 + a1 * b1
    return s + a2 * b2


_DOT3 = {"fma012": _dot3_fma012, "fma102": _dot3_fma102, "fma012_0": _dot3_fma012_0,
         "fma102_0": _dot3_fma102_0, "sum0": _dot3_sum0, "sum": _dot3_sum,
         "unknown": _dot3_fma012}
dot3_vecmat = _DOT3[PRODUCT_ORDERS.vecmat]
"""An element of a row vector ``a`` times a matrix (``a^T R``, ``b`` a column of ``R``), as
``np.matmul`` rounds it here (an order not found: OpenBLAS's usual ``fma012``)."""
dot3_matvec = _DOT3[PRODUCT_ORDERS.matvec]
"""An element of a matrix times a column vector (``R f``: ``a`` a row of ``R``, ``b`` = f)."""
dot3_matmat = _DOT3[PRODUCT_ORDERS.matmat]
"""An element of a matrix times a matrix (``a`` a row of the first, ``b`` a column of the
second)."""
dot3_tmatmat = _DOT3[PRODUCT_ORDERS.tmatmat]
"""An element of a transposed matrix times a matrix (``R_d^T R``: ``a`` a column of ``R_d``,
``b`` a column of ``R``)."""


# -- NumPy's own elementwise loops, called from compiled code ----------------------------------
# NumPy computes exp, log, power, arctan2, arcsin and arccos with its own SIMD code (AVX-512 where
# the processor has it), whose last bit differs from the C library's in a few per cent of arguments.
# So that a kernel's numbers equal NumPy's, kernels call NumPy's inner loops themselves: the loop of
# each ufunc for float64 is read from the ufunc object (``PyUFuncObject.functions``, NumPy's public
# C struct) and called through its address, over a whole row of the batch at a time. The addresses
# are checked against the ufuncs' own results when this module loads; should a NumPy release lay the
# struct out otherwise, the kernels use the C library's functions instead (the same numbers to the
# last bit or two; ``NUMPY_LOOPS_OK`` says which).

LOOP_EXP, LOOP_LOG, LOOP_POWER, LOOP_ARCTAN2, LOOP_ARCSIN, LOOP_ARCCOS = 0, 1, 2, 3, 4, 5


def _ufunc_loop(ufunc: Any, types_: str) -> int:
    """The address of ``ufunc``'s inner loop for the type characters ``types_`` (e.g. 'dd'
    followed by the output's 'd'), 0 when it cannot be read."""
    import ctypes

    import numpy as np

    try:
        addr = id(ufunc)
        ptr = ctypes.c_void_p.from_address
        functions = ptr(addr + 32).value  # PyObject_HEAD, then nin, nout, nargs, identity
        ntypes = ctypes.c_int.from_address(addr + 48).value
        names = ptr(addr + 64).value
        nargs = ufunc.nargs
        if not functions or not names or nargs != len(types_) or not 0 < ntypes < 256:
            return 0
        raw = ctypes.string_at(names, ntypes * nargs)
        want = bytes(np.dtype(c).num for c in types_)
        for i in range(ntypes):
            if raw[i * nargs:(i + 1) * nargs] == want:
                return int(ptr(functions + 8 * i).value or 0)
    except (ValueError, OSError):  # pragma: no cover - a NumPy without the legacy struct
        return 0
    return 0


@intrinsic
def _call_loop(typingctx: Any, fn: Any, args: Any, dims: Any, steps: Any) -> Any:
    """Call a NumPy inner loop ``void loop(char **args, npy_intp *dims, npy_intp *steps,
    void *data)`` at the address ``fn``, with the addresses of its three arrays."""
    sig = types.void(types.intp, types.intp, types.intp, types.intp)

    def codegen(context: Any, builder: Any, signature: Any, llargs: Any) -> Any:
        i8p = ir.IntType(8).as_pointer()
        i64p = ir.IntType(64).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [i8p.as_pointer(), i64p, i64p, i8p])
        fnptr = builder.inttoptr(llargs[0], fnty.as_pointer())
        builder.call(fnptr, [builder.inttoptr(llargs[1], i8p.as_pointer()),
                             builder.inttoptr(llargs[2], i64p),
                             builder.inttoptr(llargs[3], i64p), ir.Constant(i8p, None)])
        return context.get_dummy_value()

    return sig, codegen


def _numpy_loops() -> tuple[Any, bool]:
    import numpy as np

    loops = np.array([_ufunc_loop(np.exp, "dd"), _ufunc_loop(np.log, "dd"),
                      _ufunc_loop(np.power, "ddd"), _ufunc_loop(np.arctan2, "ddd"),
                      _ufunc_loop(np.arcsin, "dd"), _ufunc_loop(np.arccos, "dd")],
                     dtype=np.int64)
    return loops, bool(loops.all())


def _check_loops(loops: Any) -> bool:
    """Whether each address gives its ufunc's numbers (called through ctypes on test rows)."""
    import ctypes

    import numpy as np

    proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_void_p)
    x = np.linspace(-7.3, 9.1, 101)
    y = np.linspace(0.01, 5.3, 101)
    u = np.linspace(-1.0, 1.0, 101)  # arcsin's and arccos's domain, both ends included
    for addr, ufunc, args in ((loops[LOOP_EXP], np.exp, (x,)), (loops[LOOP_LOG], np.log, (y,)),
                              (loops[LOOP_POWER], np.power, (y, x / 7.0)),
                              (loops[LOOP_ARCTAN2], np.arctan2, (x, y - 2.0)),
                              (loops[LOOP_ARCSIN], np.arcsin, (u,)),
                              (loops[LOOP_ARCCOS], np.arccos, (u,))):
        if not addr:
            return False
        out = np.empty_like(x)
        arrays = [*args, out]
        ptrs = np.array([a.ctypes.data for a in arrays], dtype=np.intp)
        dims = np.array([x.size], dtype=np.intp)
        steps = np.array([a.strides[0] for a in arrays], dtype=np.intp)
        proto(int(addr))(ptrs.ctypes.data, dims.ctypes.data, steps.ctypes.data, None)
        if not np.array_equal(out, ufunc(*args)):
            return False
    return True


NUMPY_LOOPS, NUMPY_LOOPS_OK = _numpy_loops()
if NUMPY_LOOPS_OK and not _check_loops(NUMPY_LOOPS):  # pragma: no cover - another NumPy layout
    NUMPY_LOOPS_OK = False
if not NUMPY_LOOPS_OK or not JIT_ENABLED:  # pragma: no cover - plain Python calls no loop
    NUMPY_LOOPS[:] = 0
NUMPY_LOOPS.flags.writeable = False
"""The loops' addresses, (6,) int64 (``LOOP_*`` index them), passed to every kernel that calls
them (an address is data, not code: the compiled kernels stay cacheable); zeros when NumPy's
loops could not be read (the kernels then use the C library's functions)."""


@njit
def np_exp(loops: Any, x: Any, out: Any) -> None:
    """``np.exp(x, out=out)`` on 1-D float64 rows, from compiled code."""
    fn = loops[LOOP_EXP]
    if fn == 0:
        for i in range(x.shape[0]):
            out[i] = math.exp(x[i])
        return
    _unary(fn, x, out)


@njit
def np_log(loops: Any, x: Any, out: Any) -> None:
    """``np.log(x, out=out)`` on 1-D float64 rows, from compiled code."""
    fn = loops[LOOP_LOG]
    if fn == 0:
        for i in range(x.shape[0]):
            out[i] = math.log(x[i]) if x[i] > 0 else (-math.inf if x[i] == 0 else math.nan)
        return
    _unary(fn, x, out)


@njit
def _unary(fn: int, x: Any, out: Any) -> None:
    """Call the one-input loop at ``fn`` over the rows ``x`` into ``out``."""
    buf = np.empty(5, np.intp)  # the two arrays' addresses, the length, their strides
    buf[0], buf[1], buf[2] = x.ctypes.data, out.ctypes.data, x.shape[0]
    buf[3], buf[4] = x.strides[0], out.strides[0]
    a = buf.ctypes.data
    _call_loop(fn, a, a + 16, a + 24)


@njit
def _binary(fn: int, x: Any, y: Any, out: Any) -> None:
    """Call the two-input loop at ``fn`` over the rows ``x`` and ``y`` into ``out``."""
    buf = np.empty(7, np.intp)
    buf[0], buf[1], buf[2], buf[3] = x.ctypes.data, y.ctypes.data, out.ctypes.data, x.shape[0]
    buf[4], buf[5], buf[6] = x.strides[0], y.strides[0], out.strides[0]
    a = buf.ctypes.data
    _call_loop(fn, a, a + 24, a + 32)


@njit
def np_power(loops: Any, x: Any, y: Any, out: Any) -> None:
    """``np.power(x, y, out=out)`` on 1-D float64 rows, from compiled code."""
    fn = loops[LOOP_POWER]
    if fn == 0:
        for i in range(x.shape[0]):
            out[i] = x[i] ** y[i]
        return
    _binary(fn, x, y, out)


@njit
def np_arctan2(loops: Any, y: Any, x: Any, out: Any) -> None:
    """``np.arctan2(y, x, out=out)`` on 1-D float64 rows, from compiled code."""
    fn = loops[LOOP_ARCTAN2]
    if fn == 0:
        for i in range(x.shape[0]):
            out[i] = math.atan2(y[i], x[i])
        return
    _binary(fn, y, x, out)


@njit
def np_arcsin(loops: Any, x: Any, out: Any) -> None:
    """``np.arcsin(x, out=out)`` on 1-D float64 rows, from compiled code (NaN outside [-1, 1],
    without NumPy's warning)."""
    fn = loops[LOOP_ARCSIN]
    if fn == 0:
        for i in range(x.shape[0]):
            out[i] = math.asin(x[i]) if -1.0 <= x[i] <= 1.0 else math.nan
        return
    _unary(fn, x, out)


@njit
def np_arccos(loops: Any, x: Any, out: Any) -> None:
    """``np.arccos(x, out=out)`` on 1-D float64 rows, from compiled code (NaN outside [-1, 1],
    without NumPy's warning)."""
    fn = loops[LOOP_ARCCOS]
    if fn == 0:
        for i in range(x.shape[0]):
            out[i] = math.acos(x[i]) if -1.0 <= x[i] <= 1.0 else math.nan
        return
    _unary(fn, x, out)
