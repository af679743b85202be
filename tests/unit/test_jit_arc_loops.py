"""The compiled kernels' arcsine and arccosine are NumPy's own loops (``aerodock.jit.np_arcsin``,
``np_arccos``): NumPy's numbers to the bit (the C library's differ in the last bit in several per
cent of arguments), on random arguments, the domain's ends and just past them (NaN), signed
zeros, NaN and infinities, in any stride and in place."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock import jit


def _arguments() -> np.ndarray:
    rng = np.random.default_rng(38)
    special = [1.0, -1.0, np.nextafter(1.0, 2.0), np.nextafter(-1.0, -2.0),
               np.nextafter(1.0, 0.0), np.nextafter(-1.0, 0.0), 0.0, -0.0, np.nan, -np.nan,
               np.inf, -np.inf, 5e-324, -5e-324, 1e-300, 0.5, -0.5, 2.0, -3.5, 1e300]
    return np.concatenate([rng.uniform(-1.0, 1.0, 20000), rng.normal(0.0, 1e-8, 500),
                           1.0 - rng.exponential(1e-9, 500), rng.uniform(-1.5, 1.5, 500),
                           special, rng.permutation(special)])


def _bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a).tobytes()


@pytest.mark.parametrize(("name", "ufunc"), [("np_arcsin", np.arcsin), ("np_arccos", np.arccos)])
def test_arc_loops_are_numpys(name, ufunc):
    assert jit.NUMPY_LOOPS_OK
    kernel = getattr(jit, name)
    x = _arguments()
    with np.errstate(invalid="ignore"):
        for rows in (x, x[::3], x[::-1], x[:1], x[:7], x[:0]):
            out = np.empty_like(rows)
            kernel(jit.NUMPY_LOOPS, rows, out)
            assert _bits(out) == _bits(ufunc(rows))
        strided = np.empty((3, x.size))
        kernel(jit.NUMPY_LOOPS, x, strided[1])  # a row of a wider array
        assert _bits(strided[1]) == _bits(ufunc(x))
        column = np.repeat(x[:, None], 3, axis=1)  # a column, in place
        kernel(jit.NUMPY_LOOPS, column[:, 1], column[:, 1])
        assert _bits(column[:, 1]) == _bits(ufunc(x))


def test_arc_loops_are_checked_at_import():
    assert jit.NUMPY_LOOPS.shape == (6,)
    assert jit.NUMPY_LOOPS[jit.LOOP_ARCSIN] and jit.NUMPY_LOOPS[jit.LOOP_ARCCOS]
    assert jit._check_loops(jit.NUMPY_LOOPS)
    swapped = jit.NUMPY_LOOPS.copy()
    swapped[[jit.LOOP_ARCSIN, jit.LOOP_ARCCOS]] = swapped[[jit.LOOP_ARCCOS, jit.LOOP_ARCSIN]]
    assert not jit._check_loops(swapped)  # a wrong address is caught


@pytest.mark.parametrize(("name", "ufunc"), [("np_arcsin", np.arcsin), ("np_arccos", np.arccos)])
def test_fallback_without_numpys_loops(name, ufunc):
    """With no address (another NumPy's layout) the C library's functions: NaN where NumPy
    gives NaN, and within a last bit elsewhere."""
    x = _arguments()
    out = np.empty_like(x)
    getattr(jit, name)(np.zeros_like(jit.NUMPY_LOOPS), x, out)
    with np.errstate(invalid="ignore"):
        want = ufunc(x)
    assert np.array_equal(np.isnan(out), np.isnan(want))
    np.testing.assert_allclose(out, want, rtol=4e-16, atol=0)
