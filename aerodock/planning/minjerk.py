"""Closed-form minimum-jerk (quintic) trajectories, batch-first.

Each trial and axis gets ``p(tau) = sum_k c_k tau^k`` for ``k = 0..5`` and
``tau = t - t0 in [0, T]``, the unique minimiser of ``int jerk^2`` with fixed position,
velocity and acceleration at both ends.

The coefficients and the samples are computed by compiled kernels (the mission samples a plan
two or three times per control period, where NumPy's per-call cost dominated), operation by
operation as the NumPy expressions they replaced: ``T^2`` as ``T * T`` (NumPy's square), the
other powers by NumPy's own power loop (:func:`aerodock.jit.np_power`), the polynomial sums from
the lowest order term up, in order (``np.add.reduce`` of six terms). The same numbers, to the
bit (``tests/unit/test_minjerk.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from aerodock.jit import NUMPY_LOOPS, njit, np_power

ORDER = 5
"""The polynomials' degree: coefficients ``c_0 .. c_5``."""


@dataclass(frozen=True)
class MinJerk:
    """A batch of quintic trajectories (build with :func:`minjerk`).

    Attributes:
        coeffs: Polynomial coefficients in ``tau = t - t0``, lowest order first, ``(n, 3, 6)``.
        t0_s: Start times, ``(n,)``.
        duration_s: Durations ``T > 0``, ``(n,)``.
        p0: Start position, ``(n, 3)``.
        v0: Start velocity, ``(n, 3)``.
        a0: Start acceleration, ``(n, 3)``.
        pf: Final position, ``(n, 3)``.
        vf: Final velocity, ``(n, 3)`` (held after the end: the target keeps moving).
    """

    coeffs: np.ndarray
    t0_s: np.ndarray
    duration_s: np.ndarray
    p0: np.ndarray
    v0: np.ndarray
    a0: np.ndarray
    pf: np.ndarray
    vf: np.ndarray

    @property
    def tf_s(self) -> np.ndarray:
        """End times ``t0 + T``, ``(n,)``."""
        return self.t0_s + self.duration_s

    def sample(self, t_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Evaluate position, velocity and acceleration at absolute times.

        Before ``t0`` the start state is returned; after ``tf`` the final state is extrapolated
        at constant final velocity, ``(pf + vf (t - tf), vf, 0)``.

        Args:
            t_s: Times, ``(n,)`` or scalar.

        Returns:
            ``(pos, vel, acc)``, each ``(n, 3)``.
        """
        n = self.t0_s.shape[0]
        if isinstance(t_s, float | int):
            t_rows = np.full(1, float(t_s))  # one time for every trial
        else:
            t_rows = np.ascontiguousarray(np.broadcast_to(np.asarray(t_s, dtype=float), (n,)))
        pos, vel, acc = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        _sample_rows(NUMPY_LOOPS, self.coeffs, self.t0_s, self.duration_s, self.p0, self.v0,
                     self.a0, self.pf, self.vf, t_rows, pos, vel, acc)
        return pos, vel, acc


def minjerk(
    p0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    pf: np.ndarray,
    vf: np.ndarray,
    af: np.ndarray,
    duration_s: np.ndarray | float,
    t0_s: np.ndarray | float,
) -> MinJerk:
    """Minimum-jerk trajectories between full start and end states.

    Args:
        p0: Start position, ``(n, 3)``.
        v0: Start velocity, ``(n, 3)``.
        a0: Start acceleration, ``(n, 3)``.
        pf: End position, ``(n, 3)``.
        vf: End velocity, ``(n, 3)``.
        af: End acceleration, ``(n, 3)``.
        duration_s: Durations ``T``, ``(n,)`` or scalar, strictly positive.
        t0_s: Start times, ``(n,)`` or scalar.

    Returns:
        The :class:`MinJerk` batch.

    Raises:
        ValueError: if any duration is not strictly positive and finite.
    """
    p0, v0, a0, pf, vf, af = _state_rows(p0, v0, a0, pf, vf, af)
    n = p0.shape[0]
    dur, t0 = _time_rows(duration_s, n), _time_rows(t0_s, n)
    coeffs = np.empty((n, 3, ORDER + 1))
    if not _coefficient_rows(NUMPY_LOOPS, p0, v0, a0, pf, vf, af, dur, coeffs):
        raise ValueError(f"duration_s must be finite and > 0, got {dur}")
    return MinJerk(
        coeffs=coeffs, t0_s=t0, duration_s=dur, p0=p0.copy(), v0=v0.copy(), a0=a0.copy(),
        pf=pf.copy(), vf=vf.copy(),
    )


def _state_rows(*states: Any) -> tuple[np.ndarray, ...]:
    """The boundary states as contiguous float rows ``(n, 3)``, broadcast against each other
    (states that already are such rows, all of one ``n``, pass as they are: the mission's
    case)."""
    first = states[0]
    if all(type(s) is np.ndarray and s.dtype == np.float64 and s.shape == first.shape
           and s.ndim == 2 and s.shape[1] == 3 and s.flags.c_contiguous for s in states):
        return states
    rows = np.broadcast_arrays(*(np.atleast_2d(np.asarray(s, dtype=float)) for s in states))
    return tuple(np.ascontiguousarray(r) for r in rows)


def _time_rows(value: np.ndarray | float, n: int) -> np.ndarray:
    """A time per trial, ``(n,)`` (a fresh array: a scalar is every trial's)."""
    if isinstance(value, float | int):
        return np.full(n, float(value))
    return np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()


# -- the kernels -------------------------------------------------------------------------------
@njit
def _maximum(a: float, b: float) -> float:
    """``np.maximum(a, b)`` of two numbers: NaN if ``a`` is, ``b`` when they are equal."""
    return a if (a > b or a != a) else b


@njit
def _minimum(a: float, b: float) -> float:
    """``np.minimum(a, b)`` of two numbers: NaN if ``a`` is, ``b`` when they are equal."""
    return a if (a < b or a != a) else b


@njit
def _powers(loops: np.ndarray, x: np.ndarray, first: int, last: int) -> np.ndarray:
    """``x ** k`` for ``k = first .. last`` by NumPy's power loop, ``(last - first + 1, n)``."""
    out = np.empty((last - first + 1, x.shape[0]))
    exponent = np.empty(x.shape[0])
    for k in range(first, last + 1):
        exponent[:] = float(k)
        np_power(loops, x, exponent, out[k - first])
    return out


@njit
def _coefficient_rows(loops: np.ndarray, p0: np.ndarray, v0: np.ndarray, a0: np.ndarray,
                      pf: np.ndarray, vf: np.ndarray, af: np.ndarray, duration_s: np.ndarray,
                      coeffs: np.ndarray) -> bool:
    """The quintics' coefficients into ``coeffs`` (n, 3, 6); False (nothing written) when a
    duration is not finite and positive."""
    n = p0.shape[0]
    for i in range(n):
        big_t = duration_s[i]
        if not (big_t > 0.0 and big_t < np.inf):
            return False
    big_t_k = _powers(loops, duration_s, 3, 5)  # T^3, T^4, T^5
    for i in range(n):
        big_t = duration_s[i]
        big_t2 = big_t * big_t
        big_t3, big_t4, big_t5 = big_t_k[0, i], big_t_k[1, i], big_t_k[2, i]
        for ax in range(3):
            p_0, v_0, a_0 = p0[i, ax], v0[i, ax], a0[i, ax]
            v_f, a_f = vf[i, ax], af[i, ax]
            dp = pf[i, ax] - p_0
            c = coeffs[i, ax]
            c[0] = p_0
            c[1] = v_0
            c[2] = 0.5 * a_0
            c[3] = (20.0 * dp - (8.0 * v_f + 12.0 * v_0) * big_t
                    - (3.0 * a_0 - a_f) * big_t2) / (2.0 * big_t3)
            c[4] = (-30.0 * dp + (14.0 * v_f + 16.0 * v_0) * big_t
                    + (3.0 * a_0 - 2.0 * a_f) * big_t2) / (2.0 * big_t4)
            c[5] = (12.0 * dp - 6.0 * (v_f + v_0) * big_t - (a_0 - a_f) * big_t2) / (2.0 * big_t5)
    return True


@njit
def _sample_rows(loops: np.ndarray, coeffs: np.ndarray, t0_s: np.ndarray,
                 duration_s: np.ndarray, p0: np.ndarray, v0: np.ndarray, a0: np.ndarray,
                 pf: np.ndarray, vf: np.ndarray, t_s: np.ndarray, pos: np.ndarray,
                 vel: np.ndarray, acc: np.ndarray) -> None:
    """:meth:`MinJerk.sample` into ``pos``, ``vel``, ``acc`` (n, 3); ``t_s`` (n,), or (1,)
    for every trial."""
    n = coeffs.shape[0]
    tau = np.empty(n)
    for i in range(n):
        t = t_s[i if t_s.shape[0] > 1 else 0]
        tau[i] = _minimum(_maximum(t - t0_s[i], 0.0), duration_s[i])  # clipped to [0, T]
    tau_k = _powers(loops, tau, 0, ORDER)  # tau^0 .. tau^5
    for i in range(n):
        t = t_s[i if t_s.shape[0] > 1 else 0]
        after_s = t - (t0_s[i] + duration_s[i])
        for ax in range(3):
            c = coeffs[i, ax]
            p = c[0] * tau_k[0, i]
            v = (c[1] * 1.0) * tau_k[0, i]
            a = (c[2] * 2.0) * tau_k[0, i]
            for k in range(1, ORDER + 1):
                p = p + c[k] * tau_k[k, i]
                if k + 1 <= ORDER:
                    v = v + (c[k + 1] * float(k + 1)) * tau_k[k, i]
                if k + 2 <= ORDER:
                    a = a + (c[k + 2] * float((k + 2) * (k + 1))) * tau_k[k, i]
            # Outside [t0, tf]: the end extrapolated, or the start state.
            if after_s > 0.0:
                p = pf[i, ax] + vf[i, ax] * after_s
                v = vf[i, ax]
                a = 0.0
            if t < t0_s[i]:
                p, v, a = p0[i, ax], v0[i, ax], a0[i, ax]
            pos[i, ax], vel[i, ax], acc[i, ax] = p, v, a
