"""The controllers' estimators, compiled: per-trial arithmetic of the bias observer, Freyja's
bias estimator and state filter, and the accelerometer observer.

The one implementation of :meth:`aerodock.control.observer.BiasObserver.update`,
:meth:`aerodock.control.freyja_estimator.FreyjaBiasEstimator.measure`,
:meth:`aerodock.control.freyja_state_filter.FreyjaStateFilter.measure` and
:meth:`aerodock.control.accel_observer.AccelObserver.update` and ``commanded`` (the classes call
these kernels, and so does the controller's compiled step,
:mod:`aerodock.control.controller_kernel`). What the batch shares stays with the classes, in
Python: the Kalman gains and covariances (the bias observer's gain schedule, Freyja's
:class:`~aerodock.control.covariance_memo.CovarianceMemo`), the filters' clocks, the ramp-in.

Each kernel updates its filter's per-trial arrays in place and computes every number operation by
operation in the order the NumPy code it replaced did (elementwise products and sums, each
rounded: no fused multiply-add), so the numbers are the same to the bit
(``tests/unit/test_compiled_estimators.py`` pins them against that code's).

The filters' constants are packed in small read-only float arrays (one argument each; the
``*_CONSTS`` layouts below), built by the classes once.
"""

from __future__ import annotations

import numpy as np

from aerodock.jit import njit

# BiasObserver: the transition matrix f (row-major, 9), then the input column g (3).
BIAS_F, BIAS_G, BIAS_CONSTS = 0, 9, 12
# Freyja's estimator: A[0, 1], A[0, 2], A[1, 2], B[0], B[1], the input shaping, the bias limits.
FY_A01, FY_A02, FY_A12, FY_B0, FY_B1, FY_SHAPING, FY_LIMIT, FY_CONSTS = 0, 1, 2, 3, 4, 5, 6, 9
# Freyja's state filter: A[0, 1], A[0, 2], A[1, 2].
SF_A01, SF_A02, SF_A12, SF_CONSTS = 0, 1, 2, 3
# The accelerometer observer: beta, mass, gravity, the motor's decay over a period and the
# start's weight in the period's mean, the axes' weights (3).
AO_BETA, AO_MASS, AO_GRAVITY, AO_DECAY, AO_MEAN_START, AO_AXES, AO_CONSTS = 0, 1, 2, 3, 4, 5, 8


def packed(*values: float | np.ndarray) -> np.ndarray:
    """The numbers ``values`` (scalars and arrays, flattened in order) as one read-only float
    array: a kernel's constants."""
    out = np.concatenate([np.asarray(v, dtype=float).reshape(-1) for v in values])
    out.flags.writeable = False
    return out


@njit
def bias_observer_rows(state: np.ndarray, consts: np.ndarray, gain: np.ndarray,
                       p_meas_m: np.ndarray, v_meas_mps: np.ndarray,
                       u_applied_mps2: np.ndarray) -> None:
    """One predict-and-correct of the bias observers, ``state`` (n, 3 axes, [p, v, b]) in place:
    ``x_r = f_r0 s_0 + f_r1 s_1 + f_r2 s_2 + g_r u`` summed in that order, then ``+ k_r0 (p -
    x_0)`` and ``+ k_r1 (v - x_1)`` with the (3, 2) ``gain``; ``consts``: ``BIAS_*``."""
    for i in range(state.shape[0]):
        for c in range(3):
            s0, s1, s2 = state[i, c, 0], state[i, c, 1], state[i, c, 2]
            u = u_applied_mps2[i, c]
            x0 = consts[BIAS_F + 0] * s0
            x1 = consts[BIAS_F + 3] * s0
            x2 = consts[BIAS_F + 6] * s0
            x0 += consts[BIAS_F + 1] * s1
            x1 += consts[BIAS_F + 4] * s1
            x2 += consts[BIAS_F + 7] * s1
            x0 += consts[BIAS_F + 2] * s2
            x1 += consts[BIAS_F + 5] * s2
            x2 += consts[BIAS_F + 8] * s2
            x0 += consts[BIAS_G + 0] * u
            x1 += consts[BIAS_G + 1] * u
            x2 += consts[BIAS_G + 2] * u
            ip = p_meas_m[i, c] - x0
            iv = v_meas_mps[i, c] - x1
            x0 += gain[0, 0] * ip
            x1 += gain[1, 0] * ip
            x2 += gain[2, 0] * ip
            x0 += gain[0, 1] * iv
            x1 += gain[1, 1] * iv
            x2 += gain[2, 1] * iv
            state[i, c, 0], state[i, c, 1], state[i, c, 2] = x0, x1, x2


@njit
def _clip(x: float, low: float, high: float) -> float:
    """``np.clip(x, low, high)`` of one number (NaN stays NaN)."""
    if x != x:
        return x
    if x < low:
        return low
    if x > high:
        return high
    return x


@njit
def freyja_measure_rows(state: np.ndarray, input_mps2: np.ndarray, consts: np.ndarray,
                        propagations: int, clear_input: bool, gain: np.ndarray,
                        p_meas_m: np.ndarray, v_meas_mps: np.ndarray) -> None:
    """One state message of Freyja's bias estimators, ``state`` (n, 3 axes, [p, v, b]) in place:
    ``propagations`` propagations with the shaped input (``x <- A x + B (shaping u)``, the bias
    then clipped), the input cleared when ``clear_input`` (a stale one), then the update with the
    (3, 2) ``gain``: ``x_r <- x_r + G_r0 (p - x_0) + G_r1 (v - x_1)``; ``consts``: ``FY_*``."""
    a01, a02, a12 = consts[FY_A01], consts[FY_A02], consts[FY_A12]
    b0, b1, shaping = consts[FY_B0], consts[FY_B1], consts[FY_SHAPING]
    for i in range(state.shape[0]):
        for c in range(3):
            s0, s1, s2 = state[i, c, 0], state[i, c, 1], state[i, c, 2]
            limit = consts[FY_LIMIT + c]
            for _ in range(propagations):
                u = shaping * input_mps2[i, c]
                n0 = s0 + a01 * s1 + a02 * s2 + b0 * u
                n1 = s1 + a12 * s2 + b1 * u
                s0, s1, s2 = n0, n1, _clip(s2, -limit, limit)
            if clear_input:
                input_mps2[i, c] = 0.0
            ip = p_meas_m[i, c] - s0
            iv = v_meas_mps[i, c] - s1
            state[i, c, 0] = s0 + gain[0, 0] * ip + gain[0, 1] * iv
            state[i, c, 1] = s1 + gain[1, 0] * ip + gain[1, 1] * iv
            state[i, c, 2] = s2 + gain[2, 0] * ip + gain[2, 1] * iv


@njit
def state_filter_rows(state: np.ndarray, consts: np.ndarray, propagations: int,
                      gain: np.ndarray, p_meas_m: np.ndarray) -> None:
    """One motion-capture message of Freyja's state filters, ``state`` (n, 3 axes, [p, v, a]) in
    place: ``propagations`` propagations ``x <- A x`` (no input), then the update on the position
    with the (3,) ``gain``: ``x_r <- x_r + G_r (p - x_0)``; ``consts``: ``SF_*``."""
    a01, a02, a12 = consts[SF_A01], consts[SF_A02], consts[SF_A12]
    for i in range(state.shape[0]):
        for c in range(3):
            s0, s1, s2 = state[i, c, 0], state[i, c, 1], state[i, c, 2]
            for _ in range(propagations):
                s0, s1 = s0 + a01 * s1 + a02 * s2, s1 + a12 * s2
            innov = p_meas_m[i, c] - s0
            state[i, c, 0] = s0 + gain[0] * innov
            state[i, c, 1] = s1 + gain[1] * innov
            state[i, c, 2] = s2 + gain[2] * innov


@njit
def accel_update_rows(residual_mps2: np.ndarray, consts: np.ndarray, thrust_mean_n: np.ndarray,
                      ff_mps2: np.ndarray, accel_mps2: np.ndarray, body_z: np.ndarray,
                      hold: np.ndarray, has_hold: bool) -> None:
    """Fold the accelerometer's reading into the accelerometer observers' ``residual_mps2`` (n, 3)
    in place: ``raw = a - g e3 + z_body (T_mean / m) - ff``, ``r <- r + beta (raw - r) w`` per
    axis (``w`` the axes' weights), the trials with ``hold`` (when ``has_hold``) kept as they are.
    ``body_z`` (n, 3) is the third column of the measured attitude; ``consts``: ``AO_*``."""
    beta, mass, gravity = consts[AO_BETA], consts[AO_MASS], consts[AO_GRAVITY]
    for i in range(residual_mps2.shape[0]):
        if has_hold and hold[i]:
            continue
        scale = thrust_mean_n[i] / mass
        for c in range(3):
            measured = accel_mps2[i, c] - (gravity if c == 2 else 0.0) + body_z[i, c] * scale
            raw = measured - ff_mps2[i, c]
            r = residual_mps2[i, c]
            residual_mps2[i, c] = r + beta * (raw - r) * consts[AO_AXES + c]


@njit
def accel_commanded_rows(thrust_state_n: np.ndarray, thrust_mean_n: np.ndarray,
                         ff_state_mps2: np.ndarray, consts: np.ndarray, has_start: bool,
                         thrust_n: np.ndarray, ff_mps2: np.ndarray, has_ff: bool) -> None:
    """The next period's command into the accelerometer observers' motor model, in place: the
    modelled thrust's mean over the period and its end (``T + (start - T) w``, the start the
    model's thrust, or the command itself when not ``has_start``), and the feed-forward flown
    (zeros when not ``has_ff``); ``consts``: ``AO_*``."""
    decay, mean_start = consts[AO_DECAY], consts[AO_MEAN_START]
    for i in range(thrust_n.shape[0]):
        t = thrust_n[i]
        start = thrust_state_n[i] if has_start else t
        thrust_mean_n[i] = t + (start - t) * mean_start
        thrust_state_n[i] = t + (start - t) * decay
        for c in range(3):
            ff_state_mps2[i, c] = ff_mps2[i, c] if has_ff else 0.0
