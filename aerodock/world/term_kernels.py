"""The compiled arithmetic of the world step's terms that were NumPy: the ground, a captured
follower's rows of the hanging pair, injected rotor faults. Each is the one implementation its
term (:mod:`aerodock.world.terms`) and the compiled control period
(:mod:`aerodock.world.period_kernel`) both call, element by element as NumPy computed it
(``tests/unit/test_period_kernel.py``)."""

from __future__ import annotations

import numpy as np

from aerodock.jit import njit


@njit
def ground_kernel(p: np.ndarray, v: np.ndarray, ground_contact: np.ndarray, lo: int,
                  hi: int) -> None:
    """The ground (z = 0, NED) on trials ``lo..hi`` of the 2n vehicles ``p``, ``v`` (in place,
    leaders first): a vehicle whose ``z`` is above it stops there (``z = 0``, its ``vz``
    clipped to ``min(vz, 0)``, a NaN kept), and ``ground_contact`` (n,) of its trial is set
    (the world's ``ground`` term). Row by row, so a block of trials computes what the whole
    batch does for its rows; NumPy's batch form, ``np.minimum(z, 0)`` on every row once one is
    above, differs only in turning another row's ``z = -0`` into +0."""
    n = p.shape[0] // 2
    for i in range(lo, hi):
        hit = False
        for j in (i, n + i):
            if p[j, 2] > 0.0:
                p[j, 2] = 0.0
                vz = v[j, 2]
                v[j, 2] = vz if (vz < 0.0 or vz != vz) else 0.0
                hit = True
        if hit:
            ground_contact[i] = True


@njit
def hang_captured(captured: np.ndarray, bar_mass: float, fol_mass: np.ndarray,
                  fol_accel: np.ndarray, gravity: np.ndarray, fol_mass_rows: np.ndarray,
                  bar_force: np.ndarray, hang_mass: np.ndarray) -> None:
    """A captured follower's forces on the hanging mass, before the bar's step (the world's
    ``hanging pair`` term): ``hang_mass = np.where(captured, bar_mass + fol_mass, bar_mass)``
    and ``bar_force += np.where(captured, (fol_accel - gravity) * fol_mass_rows, 0.0)`` (the
    free followers' rows add +0), element by element as NumPy computes them."""
    for i in range(captured.shape[0]):
        cap = captured[i]
        hang_mass[i] = bar_mass + fol_mass[i] if cap else bar_mass
        for k in range(3):
            own = (fol_accel[i, k] - gravity[k]) * fol_mass_rows[i, k]
            bar_force[i, k] += own if cap else 0.0


@njit
def carry_captured(captured: np.ndarray, bar_p: np.ndarray, bar_v: np.ndarray,
                   fol_r_new: np.ndarray, fol_p_new: np.ndarray, fol_v_new: np.ndarray,
                   fol_v: np.ndarray, fol_accel: np.ndarray, hang_offset: float,
                   dt: float) -> None:
    """A captured follower carried with its bar, after the bar's step (the world's ``hanging
    pair`` term): at ``bar_p - (-R e3) hang_offset`` (its new attitude's up axis; the offset the
    arm's height plus the bar's radius), with the bar's velocity, its acceleration ``(v_new -
    v) / dt``; NumPy's ``np.copyto(..., where=captured)``, element by element."""
    for i in range(captured.shape[0]):
        if not captured[i]:
            continue
        for k in range(3):
            up = -fol_r_new[i, k, 2]
            fol_p_new[i, k] = bar_p[i, k] - up * hang_offset
        for k in range(3):
            fol_v_new[i, k] = bar_v[i, k]
        for k in range(3):
            fol_accel[i, k] = (fol_v_new[i, k] - fol_v[i, k]) / dt


@njit
def rotor_fault_wrench(omega: np.ndarray, thrust_coeff: float, gain: np.ndarray,
                       loss: np.ndarray, rot: np.ndarray, torque_map: np.ndarray,
                       force: np.ndarray, torque_t: np.ndarray) -> None:
    """The thrust the followers' faulty rotors do not give (the world's ``rotor faults`` term):
    ``lost = omega^2 (k_T gain) loss`` per rotor (the followers' rows: ``omega`` (n, k),
    ``gain`` (n,), ``rot`` (n, 3, 3), ``loss`` (n, k)), added to their force along their body
    z, ``force += R e3 sum(lost)`` (n, 3), and taken from their torque, ``torque_t -= lost_i
    map_i`` (3, n) rotor by rotor; each element as NumPy computes it (its sum of a row of fewer
    than eight numbers is the running one)."""
    n, k = loss.shape
    lost = np.empty(k)
    for j in range(n):
        kc = thrust_coeff * gain[j]
        for i in range(k):
            x = omega[j, i] * omega[j, i]
            x *= kc
            x *= loss[j, i]
            lost[i] = x
        total = lost[0]
        for i in range(1, k):
            total += lost[i]
        for c in range(3):
            force[j, c] += rot[j, c, 2] * total
        for i in range(k):
            for c in range(3):
                torque_t[c, j] -= lost[i] * torque_map[i, c]
