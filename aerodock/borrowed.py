"""Borrowed views for the compiled kernels: arrays numba does not count references of.

numba counts the references of every array a compiled function holds: each array argument of
each call, each view, each variable bound to one, an atomic increment and decrement apiece
(about 9.5 ns a pair on the project's machine, and a cache line shared between threads). The
world's period made some 1,400 such pairs a physics step at a batch of one, most of its time
there (docs/performance.md, "Borrowed views"). A borrowed view is the same array (data, shape,
strides) without its memory's owner record: numba's count then sees a null owner and does
nothing, and views of it are borrowed too. It is safe only where the owner outlives every use:
a kernel's own arguments, which its Python caller holds for the call, or an allocation kept
alive to the end with :func:`keep_alive`.

``AERODOCK_JIT=0`` (plain Python, :mod:`aerodock.jit`): :func:`borrowed` returns the arrays as
they are and the scratch views are NumPy's views, laid out alike.
"""

from __future__ import annotations

from typing import Any

# isort: off
from aerodock.jit import JIT_ENABLED, njit  # first: it applies AERODOCK_JIT before numba loads
from numba.core import cgutils, types
from numba.extending import intrinsic
# isort: on


@intrinsic
def _borrowed_intrinsic(typingctx: Any, arrays: Any) -> Any:
    """A tuple's arrays as borrowed views (other items as they are)."""
    if not isinstance(arrays, types.BaseTuple):
        return None
    sig = arrays(arrays)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        items = cgutils.unpack_tuple(builder, args[0], len(arrays))
        out = []
        for ty, value in zip(arrays, items):
            if isinstance(ty, types.Array):
                src = context.make_array(ty)(context, builder, value)
                view = context.make_array(ty)(context, builder)
                view.meminfo = cgutils.get_null_value(view.meminfo.type)
                view.parent = cgutils.get_null_value(view.parent.type)
                view.nitems, view.itemsize, view.data = src.nitems, src.itemsize, src.data
                view.shape, view.strides = src.shape, src.strides
                value = view._getvalue()
            elif context.enable_nrt:
                context.nrt.incref(builder, ty, value)  # the result is a new reference
            out.append(value)
        return context.make_tuple(builder, signature.return_type, out)

    return sig, codegen


if JIT_ENABLED:
    borrowed = _borrowed_intrinsic
else:  # the plain-Python run of the kernels: nothing is counted
    def borrowed(arrays: tuple[Any, ...]) -> tuple[Any, ...]:
        """``arrays`` as they are (without the compiler)."""
        return arrays


@njit
def keep_alive(owners: Any) -> None:
    """Nothing: a use of ``owners`` that keeps them, and so the views borrowed from them, alive
    until this call (numba lets an array go right after its last use)."""


# A kernel's temporary rows as views of one scratch allocation: one allocation and no reference
# counts, instead of one of each per row. ``work`` is a borrowed (or any) contiguous float64
# array; the views are C-contiguous, borrowed, and laid out one after the other, each followed
# by SCRATCH_PAD floats (a cache line): rows of a power-of-two length back to back would sit a
# multiple of 4 KiB apart and contend for the same cache sets (a batch of 1,024 trials in two
# blocks ran a quarter slower that way).
SCRATCH_PAD = 8


@njit
def scratch_size(floats: int, views: int) -> int:
    """The floats a scratch allocation takes for ``views`` views of ``floats`` in all."""
    return floats + views * SCRATCH_PAD

@intrinsic
def _scratch_view(typingctx: Any, work: Any, at: Any, shape: Any) -> Any:
    """The C-contiguous float64 array of ``shape`` (a tuple of ints) whose first element is
    ``work[at]`` (``work``: a C-contiguous float64 row): no owner record (a borrowed view); its
    bounds are the caller's to check (the ``scratch_*`` helpers do)."""
    if not (isinstance(work, types.Array) and work.dtype == types.float64 and work.ndim == 1
            and work.layout == "C" and isinstance(shape, types.UniTuple)):
        return None  # (numba then reports no matching signature)
    ndim = shape.count
    out_ty = types.Array(types.float64, ndim, "C")

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        src = context.make_array(signature.args[0])(context, builder, args[0])
        view = context.make_array(out_ty)(context, builder)
        intp = context.get_value_type(types.intp)
        dims = [builder.sext(d, intp) if d.type.width < intp.width else d
                for d in cgutils.unpack_tuple(builder, args[2], ndim)]
        itemsize = context.get_constant(types.intp, 8)
        strides = [None] * ndim
        stride = itemsize
        for i in reversed(range(ndim)):
            strides[i] = stride
            stride = builder.mul(stride, dims[i])
        nitems = context.get_constant(types.intp, 1)
        for d in dims:
            nitems = builder.mul(nitems, d)
        view.meminfo = cgutils.get_null_value(view.meminfo.type)
        view.parent = cgutils.get_null_value(view.parent.type)
        view.nitems, view.itemsize = nitems, itemsize
        view.data = builder.gep(src.data, [args[1]])
        view.shape = cgutils.pack_array(builder, dims)
        view.strides = cgutils.pack_array(builder, strides)
        return view._getvalue()

    return out_ty(work, at, shape), codegen


@njit
def _room(work: Any, at: int, size: int) -> int:
    """``at + size``, once it is checked that ``work`` holds ``size`` floats from ``at`` (a view
    past the allocation would read and write another array's memory)."""
    end = at + size
    if at < 0 or size < 0 or end > work.shape[0]:
        raise IndexError("a scratch view reaches past its allocation (scratch_size too small)")
    return end


if JIT_ENABLED:
    @njit
    def scratch_row(work: Any, at: int, cols: int) -> tuple[Any, int]:
        """(cols,) of ``work`` from ``at``, and where the next view starts."""
        end = _room(work, at, cols)
        return _scratch_view(work, at, (cols,)), end + SCRATCH_PAD

    @njit
    def scratch_rows(work: Any, at: int, rows: int, cols: int) -> tuple[Any, int]:
        """(rows, cols) of ``work`` from ``at`` (C order), and where the next view starts."""
        end = _room(work, at, rows * cols)
        return _scratch_view(work, at, (rows, cols)), end + SCRATCH_PAD

    @njit
    def scratch_slab(work: Any, at: int, slabs: int, rows: int, cols: int) -> tuple[Any, int]:
        """(slabs, rows, cols) of ``work`` from ``at`` (C order), and where the next starts."""
        end = _room(work, at, slabs * rows * cols)
        return _scratch_view(work, at, (slabs, rows, cols)), end + SCRATCH_PAD
else:  # the plain-Python run of the kernels: NumPy's views
    def scratch_row(work: Any, at: int, cols: int) -> tuple[Any, int]:
        """(cols,) of ``work`` from ``at``, and where the next view starts."""
        end = _room(work, at, cols)
        return work[at:end], end + SCRATCH_PAD

    def scratch_rows(work: Any, at: int, rows: int, cols: int) -> tuple[Any, int]:
        """(rows, cols) of ``work`` from ``at`` (C order), and where the next view starts."""
        end = _room(work, at, rows * cols)
        return work[at:end].reshape((rows, cols)), end + SCRATCH_PAD

    def scratch_slab(work: Any, at: int, slabs: int, rows: int, cols: int) -> tuple[Any, int]:
        """(slabs, rows, cols) of ``work`` from ``at`` (C order), and where the next starts."""
        end = _room(work, at, slabs * rows * cols)
        return work[at:end].reshape((slabs, rows, cols)), end + SCRATCH_PAD
