"""The docking platform: a bar hanging under the leader on two cables of equal length ``d_p``.

The cables hang from two points ``cable_spacing_m`` apart and hold the bar at its ends, so they stay
parallel: the bar translates like a spherical pendulum of length ``d_p`` about the anchor (swinging
in both directions) and yaws like a bifilar (torsion) pendulum,
``omega_yaw^2 = g (s/2)^2 / (L k^2)`` with ``k^2 = l^2 / 12`` for a uniform bar of length ``l``.
The cables only pull: a bar pushed up (by the gripper) goes slack and falls back. After capture
the follower hangs from the bar and the same constraint carries its weight to the leader.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from aerodock.borrowed import borrowed, keep_alive, scratch_row, scratch_rows, scratch_size
from aerodock.config import Config
from aerodock.downwash.base import frozen_record
from aerodock.frozen import freeze
from aerodock.jit import NUMPY_LOOPS, any_layout, dot3_matvec, dot3_vecmat, njit, np_arctan2


@dataclass(frozen=True)
class PlatformParams:
    """Constants of the two-cable bar (see ``[platform]`` in defaults.toml)."""

    cable_length_m: float
    cable_spacing_m: float
    bar_length_m: float
    bar_diameter_m: float
    bar_mass_kg: float
    anchor_below_leader_m: float
    yaw_damping: float
    swing_damping: float
    gravity_mps2: float

    @classmethod
    def from_config(cls, cfg: Config) -> PlatformParams:
        """Bind ``[platform]`` (and gravity) of ``cfg``."""
        p = cfg.platform
        return cls(
            cable_length_m=p.cable_length_m, cable_spacing_m=p.cable_spacing_m,
            bar_length_m=p.bar_length_m, bar_diameter_m=p.bar_diameter_m,
            bar_mass_kg=p.bar_mass_kg, anchor_below_leader_m=p.anchor_below_leader_m,
            yaw_damping=p.yaw_damping, swing_damping=p.swing_damping,
            gravity_mps2=cfg.sim.gravity_mps2,
        )

    @property
    def bar_area_m2(self) -> float:
        """Frontal area of the bar to a vertical flow."""
        return self.bar_length_m * self.bar_diameter_m

    @cached_property
    def yaw_omega2(self) -> float:
        """Squared natural frequency of the bifilar yaw mode, 1/s²."""
        k2 = self.bar_length_m**2 / 12.0
        return self.gravity_mps2 * (self.cable_spacing_m / 2.0) ** 2 / (self.cable_length_m * k2)


@dataclass(frozen=True)
class BarState:
    """Batch of N bars: centre position and velocity (NED), yaw and yaw rate."""

    p: np.ndarray  # (n, 3)
    v: np.ndarray  # (n, 3)
    yaw_rad: np.ndarray  # (n,)
    yaw_rate_radps: np.ndarray  # (n,)


def anchor_point(leader_p: np.ndarray, leader_R: np.ndarray, params: PlatformParams) -> np.ndarray:  # noqa: N803
    """(n, 3) cable attachment point (midpoint of the two cables) on the leader."""
    return leader_p + leader_R[:, :, 2] * params.anchor_below_leader_m


def hanging_bar(anchor_p: np.ndarray, anchor_v: np.ndarray, yaw_rad: np.ndarray,
                params: PlatformParams) -> BarState:
    """Bars at rest straight below ``anchor_p``."""
    p = anchor_p + np.array([0.0, 0.0, params.cable_length_m])
    return BarState(p=p, v=np.array(anchor_v, dtype=float), yaw_rad=np.array(yaw_rad, float),
                    yaw_rate_radps=np.zeros(anchor_p.shape[0]))


def step_bar(
    bar: BarState,
    anchor_p: np.ndarray,
    anchor_v: np.ndarray,
    anchor_a: np.ndarray,
    anchor_p_next: np.ndarray,
    leader_yaw_rad: np.ndarray,
    force_n: np.ndarray,
    mass_kg: np.ndarray,
    params: PlatformParams,
    dt_s: float,
) -> tuple[BarState, np.ndarray]:
    """Advance the bars by ``dt_s``; returns (state, cable force on the leader (n,3), N).

    Args:
        bar: current state.
        anchor_p, anchor_v, anchor_a: (n, 3) attachment point's position, velocity and
            acceleration at the start of the step.
        anchor_p_next: (n, 3) attachment point at the end of the step (the leader has moved).
        leader_yaw_rad: (n,) leader yaw (the bifilar mode aligns the bar with it).
        force_n: (n, 3) every force on the hanging mass except gravity and the cables
            (downwash drag, gripper contact, and for a captured follower its thrust, drag, ...).
        mass_kg: (n,) hanging mass: the bar, or the bar plus a captured follower.
        params: platform constants.
        dt_s: physics step.
    """
    n = bar.p.shape[0]
    p, v, yaw, yaw_rate, cable = (np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty(n),
                                  np.empty((n, 3)))
    step_bar_kernel(bar.p, bar.v, bar.yaw_rad, bar.yaw_rate_radps,
                    np.asarray(anchor_p, dtype=float), np.asarray(anchor_v, dtype=float),
                    np.asarray(anchor_a, dtype=float), np.asarray(anchor_p_next, dtype=float),
                    np.asarray(leader_yaw_rad, dtype=float), np.asarray(force_n, dtype=float),
                    _per_bar(mass_kg, n),
                    params.cable_length_m, params.swing_damping, params.gravity_mps2,
                    params.yaw_omega2, params.yaw_damping, dt_s, p, v, yaw, yaw_rate, cable)
    return frozen_record(BarState, p=p, v=v, yaw_rad=yaw, yaw_rate_radps=yaw_rate), cable


def _per_bar(values: np.ndarray | float, n: int) -> np.ndarray:
    """(n,) float values, one per bar (the array itself when it is one)."""
    values = np.asarray(values, dtype=float)
    return values if values.shape == (n,) else np.broadcast_to(values, (n,))


@njit
def step_bar_kernel(bar_p: np.ndarray, bar_v: np.ndarray, bar_yaw: np.ndarray,
                    bar_yaw_rate: np.ndarray, anchor_p: np.ndarray, anchor_v: np.ndarray,
                    anchor_a: np.ndarray, anchor_p_next: np.ndarray, leader_yaw: np.ndarray,
                    force: np.ndarray, mass: np.ndarray, length: float, swing_damping: float,
                    gravity: float, yaw_omega2: float, yaw_damping: float, dt: float,
                    p_new: np.ndarray, v_new: np.ndarray, yaw_new: np.ndarray,
                    yaw_rate_new: np.ndarray, cable: np.ndarray) -> None:
    """:func:`step_bar` for ``n`` bars: the spherical pendulum under its forces with the
    taut-cable constraint (tension per unit mass ``lam >= 0``: cables only pull; none on a
    slack cable), explicit Euler, then a bar under tension (or past the cable length) put back
    on the sphere about the moved anchor with no radial velocity relative to it; the bifilar
    yaw mode towards the leader's yaw."""
    n = bar_p.shape[0]
    lam = np.empty(n)
    every_tense = True
    for i in range(n):
        rel0, rel1, rel2 = (bar_p[i, 0] - anchor_p[i, 0], bar_p[i, 1] - anchor_p[i, 1],
                            bar_p[i, 2] - anchor_p[i, 2])
        rv0, rv1, rv2 = (bar_v[i, 0] - anchor_v[i, 0], bar_v[i, 1] - anchor_v[i, 1],
                         bar_v[i, 2] - anchor_v[i, 2])
        dist = rel0 * rel0 + rel1 * rel1
        dist += rel2 * rel2
        dist = math.sqrt(dist)
        floor = dist if (dist >= 1e-9 or dist != dist) else 1e-9
        e0, e1, e2 = rel0 / floor, rel1 / floor, rel2 / floor
        m = mass[i]
        f0 = force[i, 0] / m - swing_damping * rv0
        f1 = force[i, 1] / m - swing_damping * rv1
        f2 = force[i, 2] / m - swing_damping * rv2
        f2 += gravity
        radial_v = rv0 * e0 + rv1 * e1 + rv2 * e2
        tangential_v2 = (rv0 * rv0 + rv1 * rv1 + rv2 * rv2) - radial_v * radial_v
        la = e0 * (f0 - anchor_a[i, 0]) + e1 * (f1 - anchor_a[i, 1]) \
            + e2 * (f2 - anchor_a[i, 2])
        la += tangential_v2 / length
        la = la if (la >= 0.0 or la != la) else 0.0
        if not dist >= length - 1e-6:  # a slack cable (or a NaN): no tension
            la = 0.0
        lam[i] = la
        if not la > 0:
            every_tense = False
        a0, a1, a2 = f0 - la * e0, f1 - la * e1, f2 - la * e2
        ml = m * la
        cable[i, 0], cable[i, 1], cable[i, 2] = ml * e0, ml * e1, ml * e2
        vn0 = a0 * dt + bar_v[i, 0]
        vn1 = a1 * dt + bar_v[i, 1]
        vn2 = a2 * dt + bar_v[i, 2]
        v_new[i, 0], v_new[i, 1], v_new[i, 2] = vn0, vn1, vn2
        p_new[i, 0] = vn0 * dt + bar_p[i, 0]
        p_new[i, 1] = vn1 * dt + bar_p[i, 1]
        p_new[i, 2] = vn2 * dt + bar_p[i, 2]
    # Inextensible cables: a bar under tension (or past the cable length) is put back on the
    # sphere and keeps no radial velocity relative to the anchor.
    for i in range(n):
        rel0 = p_new[i, 0] - anchor_p_next[i, 0]
        rel1 = p_new[i, 1] - anchor_p_next[i, 1]
        rel2 = p_new[i, 2] - anchor_p_next[i, 2]
        dist = rel0 * rel0 + rel1 * rel1
        dist += rel2 * rel2
        dist = math.sqrt(dist)
        tense = lam[i] > 0
        if every_tense or dist > length or tense:
            floor = dist if (dist >= 1e-9 or dist != dist) else 1e-9
            u0, u1, u2 = rel0 / floor, rel1 / floor, rel2 / floor
            p_new[i, 0] = u0 * length + anchor_p_next[i, 0]
            p_new[i, 1] = u1 * length + anchor_p_next[i, 1]
            p_new[i, 2] = u2 * length + anchor_p_next[i, 2]
            vn0, vn1, vn2 = v_new[i, 0], v_new[i, 1], v_new[i, 2]
            radial = (vn0 - anchor_v[i, 0]) * u0 + (vn1 - anchor_v[i, 1]) * u1 \
                + (vn2 - anchor_v[i, 2]) * u2
            if not every_tense and not tense:
                radial = radial if (radial >= 0.0 or radial != radial) else 0.0
            v_new[i, 0] = vn0 - radial * u0
            v_new[i, 1] = vn1 - radial * u1
            v_new[i, 2] = vn2 - radial * u2
    for i in range(n):
        err = bar_yaw[i] - leader_yaw[i]
        err += math.pi
        err %= 2 * math.pi
        err -= math.pi
        acc = -yaw_omega2 * math.sin(err)
        acc -= yaw_damping * bar_yaw_rate[i]
        rate = acc * dt + bar_yaw_rate[i]
        yaw_rate_new[i] = rate
        yaw_new[i] = rate * dt + bar_yaw[i]


def step_hanging_bar(
    bar: BarState,
    lead_p: np.ndarray,
    lead_v: np.ndarray,
    lead_a: np.ndarray,
    lead_R: np.ndarray,  # noqa: N803
    lead_p_next: np.ndarray,
    leader_yaw_rad: np.ndarray | None,
    force_n: np.ndarray,
    mass_kg: np.ndarray,
    params: PlatformParams,
    dt_s: float,
) -> tuple[BarState, np.ndarray]:
    """:func:`step_bar` about the leaders' anchors, from the leaders' rows themselves: the
    anchor ``p + R e3 d`` at the start of the step and ``p_next + R e3 d`` at its end (the
    start-of-step attitude for both, as the world's step has it), and, for ``leader_yaw_rad``
    None, the leaders' yaw ``arctan2(R10, R00)`` (NumPy's own loop). One compiled call
    (:func:`hanging_bar_kernel`) instead of a dozen small NumPy ones, with the same numbers:
    the anchor's products and sums are elementwise, rounded as NumPy rounds them
    (``tests/unit/test_glue_rest.py``).

    Args:
        bar: current state.
        lead_p, lead_v, lead_a: (m, 3) float64, the leaders' position, velocity and
            acceleration at the start of the step (rows ``0..n-1`` are read: the world passes
            its whole 2n batch).
        lead_R: (m, 3, 3) float64, the leaders' attitude at the start of the step.
        lead_p_next: (m, 3) float64, the leaders' position at the end of the step.
        leader_yaw_rad: (n,) float64, the leaders' yaw (None: from ``lead_R``).
        force_n: (n, 3) float64, every force on the hanging mass except gravity and the cables.
        mass_kg: (n,) float64 hanging mass.
        params: platform constants.
        dt_s: physics step.
    """
    n = bar.p.shape[0]
    p, v, yaw, yaw_rate, cable = (np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty(n),
                                  np.empty((n, 3)))
    rows = min(lead_p.shape[0], lead_v.shape[0], lead_a.shape[0], lead_R.shape[0],
               lead_p_next.shape[0])
    if rows < n or force_n.shape[0] != n or mass_kg.shape[0] != n:
        raise ValueError(f"step_hanging_bar: {n} bars need at least {n} leader rows and {n} "
                         f"forces and masses, got {rows}, {force_n.shape[0]}, {mass_kg.shape[0]}")
    from_rot = leader_yaw_rad is None
    hanging_bar_kernel(NUMPY_LOOPS, bar.p, bar.v, bar.yaw_rad, bar.yaw_rate_radps, lead_p,
                       lead_v, lead_a, lead_R, lead_p_next,
                       _NO_YAW if from_rot else leader_yaw_rad, from_rot, force_n, mass_kg,
                       params.anchor_below_leader_m, params.cable_length_m,
                       params.swing_damping, params.gravity_mps2, params.yaw_omega2,
                       params.yaw_damping, dt_s, p, v, yaw, yaw_rate, cable)
    return frozen_record(BarState, p=p, v=v, yaw_rad=yaw, yaw_rate_radps=yaw_rate), cable


_NO_YAW = np.zeros(0)
freeze(_NO_YAW)


@njit
def hanging_bar_kernel_body(loops: np.ndarray, bar_p: np.ndarray, bar_v: np.ndarray,
                            bar_yaw: np.ndarray, bar_yaw_rate: np.ndarray, lead_p: np.ndarray,
                            lead_v: np.ndarray, lead_a: np.ndarray, lead_r: np.ndarray,
                            lead_p_next: np.ndarray, lead_yaw: np.ndarray, yaw_from_rot: bool,
                            force: np.ndarray, mass: np.ndarray, anchor_below: float, length: float,
                            swing_damping: float, gravity: float, yaw_omega2: float,
                            yaw_damping: float, dt: float, p_new: np.ndarray, v_new: np.ndarray,
                            yaw_new: np.ndarray, yaw_rate_new: np.ndarray,
                            cable: np.ndarray) -> None:
    """:func:`step_hanging_bar`'s kernel: the anchors (``R[:, :, 2] * d`` added to the start
    and end positions, NumPy's elementwise operations), the yaw by NumPy's arctan2 loop when
    ``yaw_from_rot``, then :func:`step_bar_kernel` on the first ``n`` rows."""
    n = bar_p.shape[0]
    owner = np.empty(scratch_size(7 * n, 3))  # the rows below are views of it
    (work,) = borrowed((owner,))
    anchor_p, at = scratch_rows(work, 0, n, 3)
    anchor_p_next, at = scratch_rows(work, at, n, 3)
    for i in range(n):
        for k in range(3):
            offset = lead_r[i, k, 2] * anchor_below
            anchor_p[i, k] = lead_p[i, k] + offset
            anchor_p_next[i, k] = lead_p_next[i, k] + offset
    if yaw_from_rot:
        yaw, at = scratch_row(work, at, n)
        np_arctan2(loops, lead_r[:n, 1, 0], lead_r[:n, 0, 0], yaw)
        step_bar_kernel(bar_p, bar_v, bar_yaw, bar_yaw_rate, anchor_p, lead_v[:n], lead_a[:n],
                        anchor_p_next, yaw, force, mass, length, swing_damping, gravity,
                        yaw_omega2, yaw_damping, dt, p_new, v_new, yaw_new, yaw_rate_new, cable)
    else:
        step_bar_kernel(bar_p, bar_v, bar_yaw, bar_yaw_rate, anchor_p, lead_v[:n], lead_a[:n],
                        anchor_p_next, lead_yaw, force, mass, length, swing_damping, gravity,
                        yaw_omega2, yaw_damping, dt, p_new, v_new, yaw_new, yaw_rate_new, cable)
    keep_alive(owner)


@any_layout("p_new", "v_new", "yaw_new", "yaw_rate_new", "cable")
@njit
def hanging_bar_kernel(loops: np.ndarray, bar_p: np.ndarray, bar_v: np.ndarray,
                       bar_yaw: np.ndarray, bar_yaw_rate: np.ndarray, lead_p: np.ndarray,
                       lead_v: np.ndarray, lead_a: np.ndarray, lead_r: np.ndarray,
                       lead_p_next: np.ndarray, lead_yaw: np.ndarray, yaw_from_rot: bool,
                       force: np.ndarray, mass: np.ndarray, anchor_below: float,
                       length: float, swing_damping: float, gravity: float,
                       yaw_omega2: float, yaw_damping: float, dt: float, p_new: np.ndarray,
                       v_new: np.ndarray, yaw_new: np.ndarray, yaw_rate_new: np.ndarray,
                       cable: np.ndarray) -> None:
    """:func:`hanging_bar_kernel_body` for a call from Python: any array layout (sealed to one
    general signature, :func:`aerodock.jit.any_layout`); compiled callers call the body itself,
    which no seal stops from compiling for their types."""
    hanging_bar_kernel_body(loops, bar_p, bar_v, bar_yaw, bar_yaw_rate, lead_p, lead_v, lead_a,
                            lead_r, lead_p_next, lead_yaw, yaw_from_rot, force, mass, anchor_below,
                            length, swing_damping, gravity, yaw_omega2, yaw_damping, dt, p_new,
                            v_new, yaw_new, yaw_rate_new, cable)


@njit
def cable_wrench_kernel(cable: np.ndarray, rot: np.ndarray, anchor_below: float,
                        force: np.ndarray, torque_t: np.ndarray, rigid: bool) -> None:
    """The cables' pull on the leaders (rows ``0..n-1`` of the world's accumulators), in the
    order and rounding of NumPy's ``force[:n] += cable`` and, for rigid bodies,
    ``c_b = matmul(cable[:, None, :], R[:n])[:, 0]`` (a row vector times a matrix, summed as
    ``np.matmul`` sums it here: :func:`aerodock.jit.dot3_vecmat`),
    ``torque_t[0, :n] -= d c_b[:, 1]``, ``torque_t[1, :n] += d c_b[:, 0]`` (the anchor ``d``
    below the centre of mass)."""
    for i in range(cable.shape[0]):
        c0, c1, c2 = cable[i, 0], cable[i, 1], cable[i, 2]
        force[i, 0] += c0
        force[i, 1] += c1
        force[i, 2] += c2
        if rigid:
            b0 = dot3_vecmat(c0, c1, c2, rot[i, 0, 0], rot[i, 1, 0], rot[i, 2, 0])
            b1 = dot3_vecmat(c0, c1, c2, rot[i, 0, 1], rot[i, 1, 1], rot[i, 2, 1])
            torque_t[0, i] -= anchor_below * b1
            torque_t[1, i] += anchor_below * b0


@njit
def any_above(p: np.ndarray, z: float) -> bool:
    """Whether any row's third component exceeds ``z`` (NaN aside): ``np.fmax.reduce(p[:, 2])
    > z`` for a non-empty ``p``, without the reduction's call overhead (the ground's test)."""
    for i in range(p.shape[0]):
        if p[i, 2] > z:
            return True
    return False


def platform_segments(anchor_p: np.ndarray, leader_yaw_rad: np.ndarray, bar: BarState,
                      params: PlatformParams) -> tuple[np.ndarray, np.ndarray]:
    """End points (a, b), each (n, 3 segments, 3), of the bar and its two cables.

    The cables hang from points ``cable_spacing_m`` apart along the leader's yaw axis at the
    anchor, to the bar's ends (:func:`segments_kernel`).
    """
    n = bar.p.shape[0]
    seg_a, seg_b = np.empty((n, 3, 3)), np.empty((n, 3, 3))
    segments_kernel(anchor_p, leader_yaw_rad, bar.p, bar.yaw_rad, 0.5 * params.bar_length_m,
                    0.5 * params.cable_spacing_m, seg_a, seg_b)
    return seg_a, seg_b


@any_layout("seg_a", "seg_b")
@njit
def segments_kernel(anchor_p: np.ndarray, leader_yaw: np.ndarray, bar_p: np.ndarray,
                    bar_yaw: np.ndarray, half_bar_m: float, half_spacing_m: float,
                    seg_a: np.ndarray, seg_b: np.ndarray) -> None:
    """:func:`platform_segments`' kernel (:func:`_segments`)."""
    _segments(anchor_p, leader_yaw, bar_p, bar_yaw, half_bar_m, half_spacing_m, seg_a, seg_b)


@njit
def _segments(anchor_p: np.ndarray, leader_yaw: np.ndarray, bar_p: np.ndarray,
              bar_yaw: np.ndarray, half_bar_m: float, half_spacing_m: float, seg_a: np.ndarray,
              seg_b: np.ndarray) -> None:
    """:func:`platform_segments`' numbers, row by row: the bar's ends ``p -/+ half_bar_m
    (cos yaw, sin yaw, 0)``, the cables' tops ``anchor -/+ half_spacing_m (cos, sin, 0)`` of
    the leader's yaw (``math.cos`` and ``math.sin`` are NumPy's numbers here: NumPy's float64
    ``cos`` and ``sin`` are the C library's); ``seg_a`` = (end 1, top 1, top 2), ``seg_b`` =
    (end 2, end 1, end 2)."""
    for i in range(bar_p.shape[0]):
        bar_axis = (math.cos(bar_yaw[i]), math.sin(bar_yaw[i]), 0.0)
        lead_axis = (math.cos(leader_yaw[i]), math.sin(leader_yaw[i]), 0.0)
        for k in range(3):
            end_1 = bar_p[i, k] - half_bar_m * bar_axis[k]
            end_2 = bar_p[i, k] + half_bar_m * bar_axis[k]
            seg_a[i, 0, k] = end_1
            seg_a[i, 1, k] = anchor_p[i, k] - half_spacing_m * lead_axis[k]
            seg_a[i, 2, k] = anchor_p[i, k] + half_spacing_m * lead_axis[k]
            seg_b[i, 0, k] = end_2
            seg_b[i, 1, k] = end_1
            seg_b[i, 2, k] = end_2


# Half the thickness of a rotor's swept disk (blade pitch and flapping): 1 cm on the paper's
# 0.0635 m rotors, in proportion to the rotor radius otherwise (a propeller's sweep scales with
# its size; written so that it is exactly 1 cm there).
DISK_HALF_THICKNESS_M = 0.01
PAPER_ROTOR_RADIUS_M = 0.0635


def disk_half_thickness(rotor_radius_m: float, disk_half_thickness_m: float | None) -> float:
    """Half the thickness of a rotor's swept disk, m: ``disk_half_thickness_m``, or for None
    :data:`DISK_HALF_THICKNESS_M` scaled to the rotor radius."""
    if disk_half_thickness_m is None:
        return DISK_HALF_THICKNESS_M * (rotor_radius_m / PAPER_ROTOR_RADIUS_M)
    return disk_half_thickness_m


def rotor_strike(follower_p: np.ndarray, follower_R: np.ndarray,  # noqa: N803
                 rotor_offsets_body_m: np.ndarray, rotor_radius_m: float,
                 seg_a: np.ndarray, seg_b: np.ndarray, bar_radius_m: float,
                 disk_half_thickness_m: float | None = None) -> np.ndarray:
    """(n,) bool: the bar or a cable passes through one of the follower's rotor disks.

    Each rotor disk is a thin cylinder (radius ``rotor_radius_m``, ``2 disk_half_thickness_m``
    thick, the blades' sweep; None: :data:`DISK_HALF_THICKNESS_M` scaled to the radius)
    about its centre; a segment (bar or cable, radius
    ``bar_radius_m``) strikes it when the segment's point closest to the disk centre lies inside
    that cylinder grown by the segment's radius (:func:`strike_kernel`).
    """
    hit = np.empty(follower_p.shape[0], dtype=bool)
    strike_kernel(follower_p, follower_R, rotor_offsets_body_m, seg_a, seg_b,
                  disk_half_thickness(rotor_radius_m, disk_half_thickness_m) + bar_radius_m,
                  rotor_radius_m + bar_radius_m, hit)
    return hit


def platform_strike(follower_p: np.ndarray, follower_R: np.ndarray,  # noqa: N803
                    leader_p: np.ndarray, leader_R: np.ndarray,  # noqa: N803
                    leader_yaw_rad: np.ndarray, bar: BarState, params: PlatformParams,
                    rotor_offsets_body_m: np.ndarray, rotor_radius_m: float,
                    bar_radius_m: float) -> np.ndarray:
    """(n,) bool: :func:`rotor_strike` of the bar and cables of :func:`platform_segments` hung
    at the leaders' :func:`anchor_point`, the same numbers in one compiled call
    (:func:`platform_strike_kernel`; the mission's check every control period).

    Args:
        follower_p, leader_p: (n, 3) positions, m, NED.
        follower_R, leader_R: (n, 3, 3) body-to-world rotations.
        leader_yaw_rad: (n,) the leaders' yaw (as the follower sees it).
        bar: the hanging bars.
        params: platform constants.
        rotor_offsets_body_m: (k, 3) the follower's rotor centres, body FRD, m.
        rotor_radius_m, bar_radius_m: radii, m.
    """
    hit = np.empty(follower_p.shape[0], dtype=bool)
    platform_strike_kernel(follower_p, follower_R, rotor_offsets_body_m, leader_p, leader_R,
                           params.anchor_below_leader_m, leader_yaw_rad, bar.p, bar.yaw_rad,
                           0.5 * params.bar_length_m, 0.5 * params.cable_spacing_m,
                           disk_half_thickness(rotor_radius_m, None) + bar_radius_m,
                           rotor_radius_m + bar_radius_m, hit)
    return hit


@any_layout("hit")
@njit
def platform_strike_kernel(fol_p: np.ndarray, fol_r: np.ndarray, offsets: np.ndarray,
                           lead_p: np.ndarray, lead_r: np.ndarray, anchor_below_m: float,
                           leader_yaw: np.ndarray, bar_p: np.ndarray, bar_yaw: np.ndarray,
                           half_bar_m: float, half_spacing_m: float, axial_reach_m: float,
                           radial_reach_m: float, hit: np.ndarray) -> None:
    """:func:`platform_strike`: the anchors ``p + R[:, :, 2] d`` (NumPy's elementwise
    numbers), the segments (:func:`_segments`), the strikes (:func:`_strikes`)."""
    n = fol_p.shape[0]
    anchor = np.empty((n, 3))
    for i in range(n):
        for k in range(3):
            anchor[i, k] = lead_p[i, k] + lead_r[i, k, 2] * anchor_below_m
    seg_a, seg_b = np.empty((n, 3, 3)), np.empty((n, 3, 3))
    _segments(anchor, leader_yaw, bar_p, bar_yaw, half_bar_m, half_spacing_m, seg_a, seg_b)
    _strikes(fol_p, fol_r, offsets, seg_a, seg_b, axial_reach_m, radial_reach_m, hit)


@any_layout("hit")
@njit
def strike_kernel(fol_p: np.ndarray, fol_r: np.ndarray, offsets: np.ndarray,
                  seg_a: np.ndarray, seg_b: np.ndarray, axial_reach_m: float,
                  radial_reach_m: float, hit: np.ndarray) -> None:
    """:func:`rotor_strike`'s kernel (:func:`_strikes`)."""
    _strikes(fol_p, fol_r, offsets, seg_a, seg_b, axial_reach_m, radial_reach_m, hit)


@njit
def _strikes(fol_p: np.ndarray, fol_r: np.ndarray, offsets: np.ndarray, seg_a: np.ndarray,
             seg_b: np.ndarray, axial_reach_m: float, radial_reach_m: float,
             hit: np.ndarray) -> None:
    """:func:`rotor_strike` for each follower: a rotor ``c = p + R o`` (``np.matmul``'s order
    here for a matrix times a column, :func:`aerodock.jit.dot3_matvec`) and a segment
    ``a -> b`` meet when the segment's point closest to ``c``,
    ``q = a + clip(t, 0, 1) (b - a)`` with ``t = (c - a).(b - a) / max(|b - a|^2, 1e-12)``,
    lies within ``axial_reach_m`` of the disk's plane (along ``R[:, 2]``) and
    ``radial_reach_m`` of its axis. Sums of three are
    NumPy's ``sum(-1)`` (left to right), maxima and clips NumPy's (a NaN propagates, and
    compares false: no strike)."""
    for i in range(fol_p.shape[0]):
        struck = False
        ax0, ax1, ax2 = fol_r[i, 0, 2], fol_r[i, 1, 2], fol_r[i, 2, 2]
        for j in range(offsets.shape[0]):
            o0, o1, o2 = offsets[j, 0], offsets[j, 1], offsets[j, 2]
            c0 = fol_p[i, 0] + dot3_matvec(fol_r[i, 0, 0], fol_r[i, 0, 1],
                                         fol_r[i, 0, 2], o0, o1, o2)
            c1 = fol_p[i, 1] + dot3_matvec(fol_r[i, 1, 0], fol_r[i, 1, 1],
                                         fol_r[i, 1, 2], o0, o1, o2)
            c2 = fol_p[i, 2] + dot3_matvec(fol_r[i, 2, 0], fol_r[i, 2, 1],
                                         fol_r[i, 2, 2], o0, o1, o2)
            for s in range(seg_a.shape[1]):
                a0, a1, a2 = seg_a[i, s, 0], seg_a[i, s, 1], seg_a[i, s, 2]
                ab0, ab1, ab2 = seg_b[i, s, 0] - a0, seg_b[i, s, 1] - a1, seg_b[i, s, 2] - a2
                along = (c0 - a0) * ab0 + (c1 - a1) * ab1
                along += (c2 - a2) * ab2
                length2 = ab0 * ab0 + ab1 * ab1
                length2 += ab2 * ab2
                t = along / (length2 if (length2 >= 1e-12 or length2 != length2) else 1e-12)
                if not (t > 0.0 or t != t):  # np.clip(t, 0, 1)
                    t = 0.0
                elif t >= 1.0:
                    t = 1.0
                r0 = (a0 + t * ab0) - c0
                r1 = (a1 + t * ab1) - c1
                r2 = (a2 + t * ab2) - c2
                axial = r0 * ax0 + r1 * ax1
                axial += r2 * ax2
                rr = r0 * r0 + r1 * r1
                rr += r2 * r2
                rr -= axial * axial
                radial = math.sqrt(rr if (rr >= 0.0 or rr != rr) else 0.0)
                if abs(axial) < axial_reach_m and radial < radial_reach_m:
                    struck = True
        hit[i] = struck
