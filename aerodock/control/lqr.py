"""Infinite-horizon LQR on the paper's feed-forward-linearised model (Eq. lin-model).

State ``x = [p_n, p_e, p_d, v_n, v_e, v_d, psi]`` (NED, metres, m/s, radians) and input
``u = [a_n, a_e, a_d, psi_dot]`` (m/s^2, rad/s). The model is three decoupled double
integrators plus a single integrator for yaw; the gain comes from the continuous algebraic
Riccati equation. The command adds reference-acceleration (and yaw-rate) feed-forward:
``u = -K (x - x_ref) + [a_ref, psi_dot_ref]``.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np

from aerodock.control import command_kernel
from aerodock.control.command_kernel import rows1, rows3

N_STATE, N_INPUT, YAW_INDEX = (command_kernel.N_STATE, command_kernel.N_INPUT,
                               command_kernel.YAW_INDEX)


def lin_model() -> tuple[np.ndarray, np.ndarray]:
    """The linear model ``x' = A x + B u`` of the paper's Eq. lin-model.

    Returns:
        ``(A, B)`` with shapes ``(7, 7)`` and ``(7, 4)``: ``p' = v``, ``v' = a``,
        ``psi' = psi_dot``.
    """
    a_mat = np.zeros((N_STATE, N_STATE))
    a_mat[0:3, 3:6] = np.eye(3)
    b_mat = np.zeros((N_STATE, N_INPUT))
    b_mat[3:6, 0:3] = np.eye(3)
    b_mat[6, 3] = 1.0
    return a_mat, b_mat


def lqr_gain(q_diag: Sequence[float], r_diag: Sequence[float]) -> np.ndarray:
    """Infinite-horizon continuous-time LQR gain for :func:`lin_model`.

    Solves ``A'P + PA - P B R^-1 B' P + Q = 0`` and returns ``K = R^-1 B' P``.

    Args:
        q_diag: 7 non-negative state weights ``[p_n, p_e, p_d, v_n, v_e, v_d, psi]``. The
            position and yaw weights must be positive (otherwise the integrators are
            undetectable and no stabilising solution exists).
        r_diag: 4 positive input weights ``[a_n, a_e, a_d, psi_dot]``.

    Returns:
        Gain ``K`` of shape ``(4, 7)`` such that ``u = -K x`` is optimal.

    Raises:
        ValueError: on wrong lengths, non-finite or negative Q, non-positive R, or a Riccati
            equation without a stabilising solution.
    """
    q = np.asarray(q_diag, dtype=float).reshape(-1)
    r = np.asarray(r_diag, dtype=float).reshape(-1)
    if q.shape != (N_STATE,):
        raise ValueError(f"q_diag needs {N_STATE} entries [p(3), v(3), psi], got {q.size}")
    if r.shape != (N_INPUT,):
        raise ValueError(f"r_diag needs {N_INPUT} entries [a(3), psi_dot], got {r.size}")
    if not np.all(np.isfinite(q)) or np.any(q < 0.0):
        raise ValueError(f"q_diag must be finite and non-negative, got {q.tolist()}")
    if not np.all(np.isfinite(r)) or np.any(r <= 0.0):
        raise ValueError(f"r_diag must be finite and strictly positive, got {r.tolist()}")
    if np.any(q[[0, 1, 2, YAW_INDEX]] <= 0.0):
        raise ValueError(
            f"position and yaw weights in q_diag must be positive (detectability), got {q.tolist()}"
        )
    # the same weights give the same gain: solved once per process (a solve costs about 16 ms,
    # and every controller, and every trial's batch, asks for its two)
    return _care_gain(q.tobytes(), r.tobytes()).copy()


@functools.lru_cache(maxsize=64)
def _care_gain(q_bytes: bytes, r_bytes: bytes) -> np.ndarray:
    """:func:`lqr_gain` for the checked weights (their float64 bytes: a key that tells -0.0
    from 0.0), read-only."""
    q, r = np.frombuffer(q_bytes), np.frombuffer(r_bytes)
    a_mat, b_mat = lin_model()
    try:
        import scipy.linalg  # here, not at the top: the CLI starts 0.2 s sooner
        p_mat = scipy.linalg.solve_continuous_are(a_mat, b_mat, np.diag(q), np.diag(r))
    except (np.linalg.LinAlgError, ValueError) as exc:  # pragma: no cover - guarded above
        raise ValueError(f"no stabilising Riccati solution for Q={q}, R={r}: {exc}") from exc
    gain = (b_mat.T @ p_mat) / r[:, None]
    gain.flags.writeable = False
    return gain


def lqr_command(
    gain: np.ndarray,
    pos_m: np.ndarray,
    vel_mps: np.ndarray,
    yaw_rad: np.ndarray,
    ref_pos_m: np.ndarray,
    ref_vel_mps: np.ndarray,
    ref_accel_mps2: np.ndarray,
    ref_yaw_rad: np.ndarray | float,
    ref_yaw_rate_radps: np.ndarray | float,
) -> tuple[np.ndarray, np.ndarray]:
    """LQR feedback plus reference feed-forward, batch-first.

    ``u = -K (x - x_ref) + [a_ref, psi_dot_ref]`` with the yaw error wrapped to ``[-pi, pi)``.
    The acceleration is the *net* desired acceleration (gravity excluded); feed it to
    :func:`aerodock.control.inversion.accel_to_attitude_thrust` after subtracting any
    disturbance estimate. No saturation is applied here.

    Args:
        gain: ``(4, 7)`` shared gain or ``(n, 4, 7)`` per-trial gains (gain scheduling).
        pos_m: Position, ``(n, 3)``.
        vel_mps: Velocity, ``(n, 3)``.
        yaw_rad: Yaw, ``(n,)``.
        ref_pos_m: Reference position, ``(n, 3)`` (or broadcastable).
        ref_vel_mps: Reference velocity, ``(n, 3)`` (or broadcastable).
        ref_accel_mps2: Reference acceleration feed-forward, ``(n, 3)`` (or broadcastable).
        ref_yaw_rad: Reference yaw, ``(n,)`` or scalar.
        ref_yaw_rate_radps: Reference yaw-rate feed-forward, ``(n,)`` or scalar.

    Returns:
        ``(accel_mps2, yaw_rate_radps)`` with shapes ``(n, 3)`` and ``(n,)``.
    """
    pos = rows3(pos_m)
    n = pos.shape[0]
    k = np.asarray(gain, dtype=float)
    if k.shape[-2:] != (N_INPUT, N_STATE) or k.ndim not in (2, 3):
        raise ValueError(f"gain must be (4, 7) or (n, 4, 7), got {k.shape}")
    gains, which = ((k[None], np.zeros(n, dtype=np.int64)) if k.ndim == 2
                    else (np.broadcast_to(k, (n, N_INPUT, N_STATE)), np.arange(n)))
    accel, yaw_rate = np.empty((n, 3)), np.empty(n)
    command_kernel.lqr_rows(np.ascontiguousarray(gains), which, pos, rows3(vel_mps, n),
                            rows1(yaw_rad, n), rows3(ref_pos_m, n), rows3(ref_vel_mps, n),
                            rows3(ref_accel_mps2, n), rows1(ref_yaw_rad, n),
                            rows1(ref_yaw_rate_radps, n), accel, yaw_rate)
    return accel, yaw_rate
