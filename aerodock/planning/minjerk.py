"""Closed-form minimum-jerk (quintic) trajectories, batch-first.

Each trial and axis gets ``p(tau) = sum_k c_k tau^k`` for ``k = 0..5`` and
``tau = t - t0 in [0, T]``, the unique minimiser of ``int jerk^2`` with fixed position,
velocity and acceleration at both ends.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_POWERS = np.arange(6)
# The factors of the derivatives' terms: k for the velocity's, k (k - 1) for the acceleration's.
_VEL_FACTORS = _POWERS[1:]
_ACC_FACTORS = _POWERS[2:] * _POWERS[1:-1]


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
        t = np.broadcast_to(np.asarray(t_s, dtype=float), (n,))
        # tau clipped to [0, T] (np.clip's numbers, without its wrapper's cost), (n, 1, 1)
        tau = np.minimum(np.maximum(t - self.t0_s, 0.0), self.duration_s)[:, None, None]
        c = self.coeffs
        tau_k = tau**_POWERS  # tau^0 .. tau^5, each power computed once for the three sums
        add = np.add.reduce  # np.sum's reduction, without its wrapper
        pos = add(c * tau_k, axis=-1)
        vel = add(c[..., 1:] * _VEL_FACTORS * tau_k[..., :-1], axis=-1)
        acc = add(c[..., 2:] * _ACC_FACTORS * tau_k[..., :-2], axis=-1)

        # Outside [t0, tf]: the start state, or the end extrapolated (each only where a trial is).
        before = t < self.t0_s
        after_s = t - self.tf_s
        after = after_s > 0.0
        if after.any():
            a = after[:, None]
            pos = np.where(a, self.pf + self.vf * after_s[:, None], pos)
            vel = np.where(a, self.vf, vel)
            acc = np.where(a, 0.0, acc)
        if before.any():
            b = before[:, None]
            pos, vel, acc = (np.where(b, self.p0, pos), np.where(b, self.v0, vel),
                             np.where(b, self.a0, acc))
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
    p0, v0, a0, pf, vf, af = np.broadcast_arrays(
        *(np.atleast_2d(np.asarray(x, dtype=float)) for x in (p0, v0, a0, pf, vf, af))
    )
    n = p0.shape[0]
    dur = np.broadcast_to(np.asarray(duration_s, dtype=float), (n,)).copy()
    t0 = np.broadcast_to(np.asarray(t0_s, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(dur) & (dur > 0.0)):
        raise ValueError(f"duration_s must be finite and > 0, got {dur}")
    big_t = dur[:, None]
    dp = pf - p0
    coeffs = np.empty((n, 3, 6))
    coeffs[..., 0] = p0
    coeffs[..., 1] = v0
    coeffs[..., 2] = 0.5 * a0
    coeffs[..., 3] = (20 * dp - (8 * vf + 12 * v0) * big_t - (3 * a0 - af) * big_t**2) / (
        2 * big_t**3
    )
    coeffs[..., 4] = (-30 * dp + (14 * vf + 16 * v0) * big_t + (3 * a0 - 2 * af) * big_t**2) / (
        2 * big_t**4
    )
    coeffs[..., 5] = (12 * dp - 6 * (vf + v0) * big_t - (a0 - af) * big_t**2) / (2 * big_t**5)
    return MinJerk(
        coeffs=coeffs, t0_s=t0, duration_s=dur, p0=p0.copy(), v0=v0.copy(), a0=a0.copy(),
        pf=pf.copy(), vf=vf.copy(),
    )
