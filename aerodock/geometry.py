"""Rotations, SO(2) helpers and thrust/gravity kinematics, batch-first. Rotations are built here.

Conventions: world frame NED (z down); ``R`` maps body to world; Euler angles are ZYX
(yaw, pitch, roll) applied as ``R = Rz(yaw) Ry(pitch) Rx(roll)``; quaternions are ``[w, x, y, z]``.
The log readers and the simulator's recorder share :func:`thrust_accel` and :data:`GRAVITY_MPS2`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

E3 = np.array([0.0, 0.0, 1.0])
# Standard gravity, as ``sim.gravity_mps2`` in aerodock/defaults.toml and the Crazyflie firmware.
GRAVITY_MPS2 = 9.81


def rpy_to_rotmat(rpy: np.ndarray) -> np.ndarray:
    """(n, 3) ZYX roll, pitch, yaw to (n, 3, 3) rotations (the hot path: one ``cos`` and one
    ``sin`` call for all three angles)."""
    c = np.cos(rpy)
    s = np.sin(rpy)
    return _rotmat_zyx(c[:, 0], s[:, 0], c[:, 1], s[:, 1], c[:, 2], s[:, 2])


def euler_to_rotmat(roll_rad: np.ndarray, pitch_rad: np.ndarray, yaw_rad: np.ndarray) -> np.ndarray:
    """ZYX Euler angles (any matching shapes ``S``) to rotation matrices ``S + (3, 3)``."""
    return _rotmat_zyx(np.cos(roll_rad), np.sin(roll_rad), np.cos(pitch_rad), np.sin(pitch_rad),
                       np.cos(yaw_rad), np.sin(yaw_rad))


def _rotmat_zyx(cr: np.ndarray, sr: np.ndarray, cp: np.ndarray, sp: np.ndarray, cy: np.ndarray,
                sy: np.ndarray) -> np.ndarray:
    """The one place a rotation is built from Euler angles: ``Rz(yaw) Ry(pitch) Rx(roll)`` from
    the angles' cosines and sines, the nine entries written in place."""
    rot = np.empty(np.broadcast_shapes(np.shape(cr), np.shape(cp), np.shape(cy)) + (3, 3))
    mul = np.multiply
    cysp = cy * sp
    sysp = sy * sp
    mul(cy, cp, out=rot[..., 0, 0])
    np.subtract(cysp * sr, sy * cr, out=rot[..., 0, 1])
    np.add(cysp * cr, sy * sr, out=rot[..., 0, 2])
    mul(sy, cp, out=rot[..., 1, 0])
    np.add(sysp * sr, cy * cr, out=rot[..., 1, 1])
    np.subtract(sysp * cr, cy * sr, out=rot[..., 1, 2])
    np.negative(sp, out=rot[..., 2, 0])
    mul(cp, sr, out=rot[..., 2, 1])
    mul(cp, cr, out=rot[..., 2, 2])
    return rot


def rotmat_to_euler(rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotation matrices ``S + (3, 3)`` to ZYX Euler angles (roll, pitch, yaw), radians."""
    rpy = rotmat_to_rpy(rot)
    return rpy[..., 0], rpy[..., 1], rpy[..., 2]


def rotmat_to_rpy(rot: np.ndarray) -> np.ndarray:
    """Rotation matrices ``S + (3, 3)`` to ZYX Euler angles ``S + (3,)`` (roll, pitch, yaw),
    radians: :func:`rotmat_to_euler` stacked on the last axis. One compiled call
    (:func:`aerodock.geometry_kernels.roll_pitch_yaw`) with NumPy's own ``arctan2`` and
    ``arcsin`` loops: NumPy's numbers to the bit."""
    kernel, loops = _COMPILED or _load_compiled()
    rot = np.asarray(rot, dtype=float)
    shape = rot.shape[:-1]
    rot = rot.reshape(-1, 3, 3)  # a single rotation too (its angles' out= are rows, not scalars)
    rpy = np.empty((rot.shape[0], 3))
    kernel(loops, rot, rpy)
    return rpy.reshape(shape)


_COMPILED: tuple[Any, ...] = ()


def _load_compiled() -> tuple[Any, ...]:
    """The compiled kernel of :func:`rotmat_to_rpy` and NumPy's loops' addresses, imported on
    first use: the log readers and the flight node read this module and load no compiled code
    (numba)."""
    global _COMPILED
    from aerodock.geometry_kernels import roll_pitch_yaw
    from aerodock.jit import NUMPY_LOOPS

    _COMPILED = (roll_pitch_yaw, NUMPY_LOOPS)
    return _COMPILED


def quat_to_rotmat(quat_wxyz: np.ndarray) -> np.ndarray:
    """Unit quaternions ``S + (4,)`` as ``[w, x, y, z]`` to rotation matrices ``S + (3, 3)``."""
    q = np.asarray(quat_wxyz, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    rot = np.empty(q.shape[:-1] + (3, 3))
    rot[..., 0, 0] = 1 - 2 * (y * y + z * z)
    rot[..., 0, 1] = 2 * (x * y - w * z)
    rot[..., 0, 2] = 2 * (x * z + w * y)
    rot[..., 1, 0] = 2 * (x * y + w * z)
    rot[..., 1, 1] = 1 - 2 * (x * x + z * z)
    rot[..., 1, 2] = 2 * (y * z - w * x)
    rot[..., 2, 0] = 2 * (x * z - w * y)
    rot[..., 2, 1] = 2 * (y * z + w * x)
    rot[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return rot


def rotmat_to_quat(rot: np.ndarray) -> np.ndarray:
    """Rotation matrices ``S + (3, 3)`` to unit quaternions ``[w, x, y, z]`` with ``w >= 0``."""
    rot = np.asarray(rot, dtype=float)
    m = rot.reshape(-1, 3, 3)
    tr = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    cand = np.stack(
        [
            np.stack([1 + tr, m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0],
                      m[:, 1, 0] - m[:, 0, 1]], -1),
            np.stack([m[:, 2, 1] - m[:, 1, 2], 1 + m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2],
                      m[:, 0, 1] + m[:, 1, 0], m[:, 0, 2] + m[:, 2, 0]], -1),
            np.stack([m[:, 0, 2] - m[:, 2, 0], m[:, 0, 1] + m[:, 1, 0],
                      1 - m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2], m[:, 1, 2] + m[:, 2, 1]], -1),
            np.stack([m[:, 1, 0] - m[:, 0, 1], m[:, 0, 2] + m[:, 2, 0], m[:, 1, 2] + m[:, 2, 1],
                      1 - m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2]], -1),
        ],
        axis=1,
    )  # (n, 4 candidates, 4): each candidate is 4 q_i q (up to scale), best-conditioned wins
    best = np.argmax(np.stack([1 + tr, 1 + m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2],
                               1 - m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2],
                               1 - m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2]], -1), axis=-1)
    q = cand[np.arange(len(m)), best]
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(rot.shape[:-2] + (4,))


def rot_z(angle_rad: np.ndarray) -> np.ndarray:
    """Rotations about the z axis, ``S + (3, 3)``."""
    zero = np.zeros_like(np.asarray(angle_rad, dtype=float))
    return euler_to_rotmat(zero, zero, angle_rad)


def rotate_planar(vec_xy: np.ndarray, angle_rad: np.ndarray) -> np.ndarray:
    """Rotate 2-vectors ``S + (2,)`` by ``angle_rad`` (SO(2) action, counter-clockwise x->y)."""
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    x, y = vec_xy[..., 0], vec_xy[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def dot_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products of ``(n, 3)`` arrays, ``(n,)``.

    Written out column by column: unlike BLAS or einsum, each row's rounding does not depend on
    the batch size (a batch of N trials reproduces N single trials bit for bit), and it is fast.
    """
    ab = a * b
    return ab[:, 0] + ab[:, 1] + ab[:, 2]


def norm_rows(a: np.ndarray) -> np.ndarray:
    """Row norms of an ``(n, 3)`` array (``np.linalg.norm(a, axis=1)``, bit for bit, faster)."""
    aa = a * a
    out = aa[:, 0] + aa[:, 1]
    out += aa[:, 2]
    return np.sqrt(out, out=out)


def wrap_angle(angle_rad: np.ndarray) -> np.ndarray:
    """Wrap angles to ``[-pi, pi)``."""
    return (np.asarray(angle_rad) + np.pi) % (2 * np.pi) - np.pi


def thrust_accel(rot: np.ndarray, thrust_n: np.ndarray, mass_kg: float) -> np.ndarray:
    """Acceleration explained by collective thrust, NED: ``g e3 - R e3 T / m`` (thrust along -z_b).

    Args:
        rot: Body (FRD) to world (NED) rotations, ``(T, 3, 3)``.
        thrust_n: Collective thrust, N, ``(T,)`` (positive: upwards in the body).
        mass_kg: Vehicle mass.
    """
    body_z_world = rot[:, :, 2]
    return GRAVITY_MPS2 * E3 - body_z_world * (np.asarray(thrust_n)[:, None] / mass_kg)


def specific_force_to_accel(rot: np.ndarray, specific_force_body: np.ndarray) -> np.ndarray:
    """Kinematic acceleration NED from an accelerometer's specific force in body FRD.

    An accelerometer at rest reads ``-g`` along body z (FRD), so ``a = R f + g e3``.
    """
    return np.einsum("tij,tj->ti", rot, specific_force_body) + GRAVITY_MPS2 * E3
