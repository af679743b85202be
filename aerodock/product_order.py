"""How NumPy rounds a 3 x 3 product on this machine, read once at import.

``np.matmul`` of the world's small stacks (a row vector times a rotation, a rotation times a
column vector, a rotation times a rotation, a transposed rotation times a rotation) sums three
products per element, and the order and the rounding of that sum are not NumPy's alone: they are
the BLAS kernel's that NumPy calls, chosen by OpenBLAS for the processor at hand. On one machine
a row vector times a matrix rounds ``fma(a2, b2, fma(a1, b1, a0 b0))`` (fused multiply-adds),
on another ``((0 + a0 b0) + a1 b1) + a2 b2`` (plain sums); the last bit differs in about a third
of the elements. The compiled kernels compute these products themselves, so that their numbers
are NumPy's on the machine that runs them they take the order found here
(:func:`aerodock.jit.dot3_vecmat` and its kin), and the kernels' disk cache is kept per order.

Each candidate is computed exactly (:class:`fractions.Fraction`, rounded once to a float where
the FMA instruction rounds once) on fixed random rows and on signed zeros, and compared with
``np.matmul``'s numbers bit for bit; the first candidate that gives every one is the order.
"""

from __future__ import annotations

from fractions import Fraction
from typing import NamedTuple

import numpy as np

ORDERS = ("fma012", "fma102", "fma012_0", "fma102_0", "sum0", "sum")
"""The sums a dot product ``a . b`` of three terms can be rounded as:

- ``fma012``: ``fma(a2, b2, fma(a1, b1, a0 b0))``;
- ``fma102``: ``fma(a2, b2, fma(a0, b0, a1 b1))``;
- ``fma012_0``, ``fma102_0``: the same added to +0.0 (a BLAS that zeroes its output and adds
  the sum to it: only a sum of negative zeros differs, +0.0 instead of -0.0);
- ``sum0``: ``((0 + a0 b0) + a1 b1) + a2 b2`` (a sum started from +0.0, as NumPy's own loop);
- ``sum``: ``(a0 b0 + a1 b1) + a2 b2``."""


class ProductOrders(NamedTuple):
    """The order (one of :data:`ORDERS`, or ``"unknown"``) of each product shape."""

    vecmat: str  # a (1, 3) row times a (3, 3) matrix
    matvec: str  # a (3, 3) matrix times a (3, 1) column
    matmat: str  # a (3, 3) matrix times a (3, 3) matrix
    tmatmat: str  # a transposed (3, 3) matrix times a (3, 3) matrix

    def exact(self) -> bool:
        """Whether every shape's order was found (else the kernels' numbers may differ from
        NumPy's in the last bit of some products on this machine)."""
        return "unknown" not in self


def _fma(a: float, b: float, c: float) -> float:
    """``a * b + c`` rounded once; an exact zero signed as IEEE 754 signs it (a
    :class:`~fractions.Fraction` has no negative zero)."""
    exact = Fraction(a) * Fraction(b) + Fraction(c)
    if exact == 0:
        return a * b + c if a == 0.0 or b == 0.0 else 0.0  # zeros' sum, or x - x = +0
    return float(exact)


def dot3(order: str, a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """``a . b`` rounded in ``order`` (one of :data:`ORDERS`), computed exactly in Python."""
    a0, a1, a2 = (float(x) for x in a)
    b0, b1, b2 = (float(x) for x in b)
    if order == "fma012":
        return _fma(a2, b2, _fma(a1, b1, a0 * b0))
    if order == "fma102":
        return _fma(a2, b2, _fma(a0, b0, a1 * b1))
    if order == "fma012_0":
        return 0.0 + _fma(a2, b2, _fma(a1, b1, a0 * b0))
    if order == "fma102_0":
        return 0.0 + _fma(a2, b2, _fma(a0, b0, a1 * b1))
    if order == "sum0":
        return ((0.0 + a0 * b0) + a1 * b1) + a2 * b2
    if order == "sum":
        return (a0 * b0 + a1 * b1) + a2 * b2
    raise ValueError(f"unknown order {order!r}; one of {ORDERS}")


def _probe_rows(n: int = 12, seed: int = 20261206) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fixed test stacks: random rows and matrices, and rows of signed zeros (the sign of a
    zero sum tells ``sum0`` from ``sum``)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 3, size=(n, 1))
    m1 = rng.normal(size=(n, 3, 3))
    m2 = rng.normal(size=(n, 3, 3))
    a[0] = -0.0
    m1[0], m2[0] = 1.0, 1.0
    a[1] = (-0.0, 0.0, -0.0)
    m1[2], m2[2] = 0.0, -0.0  # products of -0.0 in every shape
    return a, m1, m2


def _first_matching(pairs: list[tuple[tuple, tuple, float]]) -> str:
    for order in ORDERS:
        if all(np.float64(dot3(order, x, y)).tobytes() == np.float64(want).tobytes()
               for x, y, want in pairs):
            return order
    return "unknown"


def probe() -> ProductOrders:
    """The order of each shape's sums in this process's ``np.matmul``."""
    a, m1, m2 = _probe_rows()
    n = a.shape[0]
    vm = np.matmul(a[:, None, :], m1)[:, 0]
    mv = np.matmul(m1, a[:, :, None])[:, :, 0]
    mm = np.matmul(m1, m2)
    tm = np.matmul(m1.transpose(0, 2, 1), m2)
    cols = range(3)
    vecmat = _first_matching([(a[i], m1[i, :, j], vm[i, j]) for i in range(n) for j in cols])
    matvec = _first_matching([(m1[i, j], a[i], mv[i, j]) for i in range(n) for j in cols])
    matmat = _first_matching([(m1[i, r], m2[i, :, j], mm[i, r, j])
                              for i in range(n) for r in cols for j in cols])
    tmatmat = _first_matching([(m1[i, :, r], m2[i, :, j], tm[i, r, j])
                               for i in range(n) for r in cols for j in cols])
    return ProductOrders(vecmat, matvec, matmat, tmatmat)


PRODUCT_ORDERS = probe()
"""This machine's :class:`ProductOrders` (read at import: a few milliseconds)."""
