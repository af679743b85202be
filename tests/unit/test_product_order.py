"""The kernels' 3 x 3 products are summed as this machine's ``np.matmul`` sums them
(:mod:`aerodock.product_order`): the order is found at import and each shape's compiled sum
gives ``np.matmul``'s bits on rows the probe never saw, signed zeros included."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock import jit
from aerodock.product_order import ORDERS, PRODUCT_ORDERS, dot3, probe


def _stacks(seed: int, n: int = 200) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-4, 4, size=(n, 1))
    m1, m2 = rng.normal(size=(n, 3, 3)), rng.normal(size=(n, 3, 3))
    a[:4] = [(-0.0, -0.0, -0.0), (0.0, -0.0, 0.0), (-0.0, 1.0, -1.0), (1e-300, -1e-300, 0.0)]
    m1[:2], m2[:2] = 1.0, -1.0
    m1[4], m2[4] = -0.0, 0.0  # products of -0.0 in every shape
    return a, m1, m2


def test_every_shape_has_an_order_here():
    assert PRODUCT_ORDERS.exact(), PRODUCT_ORDERS
    assert probe() == PRODUCT_ORDERS  # the same answer every time


@pytest.mark.parametrize("seed", [1, 2])
def test_the_compiled_sums_are_np_matmuls(seed):
    a, m1, m2 = _stacks(seed)
    vm = np.matmul(a[:, None, :], m1)[:, 0]
    mv = np.matmul(m1, a[:, :, None])[:, :, 0]
    mm = np.matmul(m1, m2)
    tm = np.matmul(m1.transpose(0, 2, 1), m2)
    for i in range(a.shape[0]):
        for j in range(3):
            assert jit.dot3_vecmat(*a[i], *m1[i, :, j]).hex() == vm[i, j].hex()
            assert jit.dot3_matvec(*m1[i, j], *a[i]).hex() == mv[i, j].hex()
            for r in range(3):
                assert jit.dot3_matmat(*m1[i, r], *m2[i, :, j]).hex() == mm[i, r, j].hex()
                assert jit.dot3_tmatmat(*m1[i, :, r], *m2[i, :, j]).hex() == tm[i, r, j].hex()


@pytest.mark.parametrize("order", ORDERS)
def test_the_compiled_candidates_are_the_exact_ones(order):
    """Each compiled candidate rounds as its exact definition (one rounding per FMA)."""
    a, m1, _ = _stacks(3)
    fn = jit._DOT3[order]
    for i in range(a.shape[0]):
        for j in range(3):
            x, y = tuple(a[i]), tuple(m1[i, :, j])
            assert fn(*x, *y).hex() == dot3(order, x, y).hex()


def test_an_unknown_order_is_refused():
    with pytest.raises(ValueError, match="unknown order"):
        dot3("fma210", (1.0, 2.0, 3.0), (4.0, 5.0, 6.0))
