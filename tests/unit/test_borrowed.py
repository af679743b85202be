"""Borrowed views and scratch views (:mod:`aerodock.borrowed`: ``borrowed``, ``scratch_row``,
``scratch_rows``, ``scratch_slab``): the same elements as the arrays they borrow from, written
through to them, in any layout; the scratch views laid out one after the other in their owner,
C-contiguous; and the plain-Python forms (``AERODOCK_JIT=0``) giving the same layout."""

from __future__ import annotations

import os
import subprocess
import sys

import numba
import numpy as np
import pytest

from aerodock import borrowed as views
from aerodock import jit

pytestmark = pytest.mark.skipif(not jit.JIT_ENABLED, reason="the compiled forms")


@numba.njit
def _double_through_borrowed(a, b, flags, scale):
    """Every array borrowed, then written through views of the views."""
    a, b, flags, scale = views.borrowed((a, b, flags, scale))
    for i in range(a.shape[0]):
        row = a[i]
        row *= scale
    b[1:, 0] = -b[1:, 0]
    flags[:] = ~flags
    return a.sum() + b.sum()


def test_borrowed_views_read_and_write_the_callers_arrays():
    a = np.arange(12.0).reshape(4, 3)
    wide = np.arange(40.0).reshape(5, 8)
    b = wide[:, ::3]  # strided: another layout
    flags = np.array([True, False, True])
    a0, b0 = a.copy(), b.copy()
    total = _double_through_borrowed(a, b, flags, 2.0)
    np.testing.assert_array_equal(a, 2.0 * a0)
    expected = b0.copy()
    expected[1:, 0] *= -1
    np.testing.assert_array_equal(b, expected)
    np.testing.assert_array_equal(wide[:, ::3], expected)  # written into the wider array
    np.testing.assert_array_equal(flags, [False, True, False])
    assert total == pytest.approx(a.sum() + b.sum())


@numba.njit
def _carve(owner, n):
    (work,) = views.borrowed((owner,))
    row, at = views.scratch_row(work, 0, n)
    rows, at = views.scratch_rows(work, at, 2, n)
    slab, at = views.scratch_slab(work, at, 2, 3, n)
    empty, at2 = views.scratch_row(work, at, 0)
    for i in range(n):
        row[i] = 1.0 + i
        for r in range(2):
            rows[r, i] = 10.0 * (r + 1) + i
        for s in range(2):
            for r in range(3):
                slab[s, r, i] = 100.0 * (s + 1) + 10.0 * r + i
    views.keep_alive(owner)
    return at, at2, empty.shape[0], rows.strides, slab.strides, slab.flags.c_contiguous


@pytest.mark.parametrize("n", [1, 3, 7])
def test_scratch_views_are_consecutive_c_contiguous_rows_of_their_owner(n):
    pad = views.SCRATCH_PAD
    size = views.scratch_size(9 * n, 4)
    assert size == 9 * n + 4 * pad
    owner = np.full(size + 2, np.nan)
    at, at2, empty, row_strides, slab_strides, c_contiguous = _carve(owner, n)
    assert at == 9 * n + 3 * pad and at2 == size and empty == 0
    assert row_strides == (8 * n, 8) and slab_strides == (24 * n, 8 * n, 8) and c_contiguous
    i = np.arange(n)
    np.testing.assert_array_equal(owner[:n], 1.0 + i)
    start = n + pad
    np.testing.assert_array_equal(owner[start:start + 2 * n].reshape(2, n),
                                  [10.0 + i, 20.0 + i])
    start += 2 * n + pad
    slab = owner[start:start + 6 * n].reshape(2, 3, n)
    np.testing.assert_array_equal(slab[1, 2], 220.0 + i)
    np.testing.assert_array_equal(slab[0, 1], 110.0 + i)
    written = np.zeros(owner.size, dtype=bool)
    written[:n] = written[n + pad:3 * n + pad] = written[start:start + 6 * n] = True
    assert np.isnan(owner[~written]).all()  # the pads and the tail untouched


def test_plain_python_scratch_views_have_the_same_layout():
    code = ("import numpy as np\nfrom aerodock import borrowed as views\n"
            "from aerodock.jit import JIT_ENABLED\nassert not JIT_ENABLED\n"
            "w = np.arange(80.0)\nr, at = views.scratch_row(w, 0, 3)\n"
            "m, at = views.scratch_rows(w, at, 2, 3)\ns, at = views.scratch_slab(w, at, 2, 2, 3)\n"
            "(b,) = views.borrowed((w,))\nassert b is w\n"
            "print(at, r.tolist(), m[1].tolist(), s[1, 1].tolist())")
    env = {**os.environ, "AERODOCK_JIT": "0"}
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=True).stdout.split(maxsplit=1)
    pad = views.SCRATCH_PAD
    assert int(out[0]) == 21 + 3 * pad
    first, second, third = 0, 3 + pad, 9 + 2 * pad
    assert out[1].strip() == (f"{np.arange(first, first + 3.0).tolist()} "
                              f"{np.arange(second + 3, second + 6.0).tolist()} "
                              f"{np.arange(third + 9, third + 12.0).tolist()}")


@numba.njit
def _too_far(owner, n):
    (work,) = views.borrowed((owner,))
    row, at = views.scratch_row(work, 0, n)
    rows, at = views.scratch_rows(work, at, 2, n)  # needs n + pad + 2n floats
    views.keep_alive(owner)
    return at


def test_a_scratch_view_past_its_allocation_is_refused():
    n = 4
    assert _too_far(np.empty(views.scratch_size(3 * n, 2)), n) == 3 * n + 2 * views.SCRATCH_PAD
    with pytest.raises(IndexError, match="past its allocation"):
        _too_far(np.empty(3 * n + views.SCRATCH_PAD - 1), n)
