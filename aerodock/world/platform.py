"""The docking platform: a bar hanging under the leader on two cables of equal length ``d_p``.

The cables hang from two points ``cable_spacing_m`` apart and hold the bar at its ends, so they stay
parallel: the bar translates like a spherical pendulum of length ``d_p`` about the anchor (swinging
in both directions) and yaws like a bifilar (torsion) pendulum,
``omega_yaw^2 = g (s/2)^2 / (L k^2)`` with ``k^2 = l^2 / 12`` for a uniform bar of length ``l``.
The cables only pull: a bar pushed up (by the gripper) goes slack and falls back. After capture
the follower hangs from the bar and the same constraint carries its weight to the leader.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from aerodock.config import Config
from aerodock.geometry import dot_rows, norm_rows

_min = np.minimum.reduce  # NaN if any element is NaN: "min >= x" is then False, as elementwise


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
    length = params.cable_length_m
    rel = bar.p - anchor_p
    rel_v = bar.v - anchor_v
    dist = norm_rows(rel)
    unit = rel / np.maximum(dist, 1e-9)[:, None]
    free = force_n / mass_kg[:, None]
    free -= params.swing_damping * rel_v
    free[:, 2] += params.gravity_mps2
    # Taut-cable constraint |rel| = L: tension per unit mass (>= 0: cables only pull).
    radial_v = dot_rows(rel_v, unit)
    tangential_v2 = dot_rows(rel_v, rel_v) - radial_v**2
    lam = dot_rows(unit, free - anchor_a)
    lam += tangential_v2 / length
    np.maximum(lam, 0.0, out=lam)
    if not _min(dist) >= length - 1e-6:  # a slack cable somewhere (or a NaN): no tension there
        lam = np.where(dist >= length - 1e-6, lam, 0.0)
    accel = free - lam[:, None] * unit
    cable_force = (mass_kg * lam)[:, None] * unit
    v = accel * dt_s
    v += bar.v
    p = v * dt_s
    p += bar.p
    # Inextensible cables: a bar under tension (or past the cable length) is put back on the
    # sphere and keeps no radial velocity relative to the anchor.
    rel = p - anchor_p_next
    dist = norm_rows(rel)
    every_tense = _min(lam) > 0  # the usual case: every cable pulls, skip the selections
    tense = None if every_tense else lam > 0
    hold = None if every_tense else (dist > length) | tense
    if every_tense or hold.any():
        every = every_tense or hold.all()
        unit_new = rel / np.maximum(dist, 1e-9)[:, None]
        on_sphere = unit_new * length
        on_sphere += anchor_p_next
        p = on_sphere if every else np.where(hold[:, None], on_sphere, p)
        radial = dot_rows(v - anchor_v, unit_new)
        if not every_tense and not tense.all():
            radial = np.where(tense, radial, np.maximum(radial, 0.0))
        no_radial = v - radial[:, None] * unit_new
        v = no_radial if every else np.where(hold[:, None], no_radial, v)
    yaw_err = bar.yaw_rad - leader_yaw_rad
    yaw_err += np.pi
    yaw_err %= 2 * np.pi
    yaw_err -= np.pi
    yaw_acc = -params.yaw_omega2 * np.sin(yaw_err)
    yaw_acc -= params.yaw_damping * bar.yaw_rate_radps
    yaw_rate = yaw_acc * dt_s
    yaw_rate += bar.yaw_rate_radps
    yaw = yaw_rate * dt_s
    yaw += bar.yaw_rad
    return BarState(p, v, yaw, yaw_rate), cable_force



def platform_segments(anchor_p: np.ndarray, leader_yaw_rad: np.ndarray, bar: BarState,
                      params: PlatformParams) -> tuple[np.ndarray, np.ndarray]:
    """End points (a, b), each (n, 3 segments, 3), of the bar and its two cables.

    The cables hang from points ``cable_spacing_m`` apart along the leader's yaw axis at the
    anchor, to the bar's ends.
    """
    half = 0.5 * params.bar_length_m
    axis_bar = np.stack([np.cos(bar.yaw_rad), np.sin(bar.yaw_rad),
                         np.zeros_like(bar.yaw_rad)], axis=1)
    axis_lead = np.stack([np.cos(leader_yaw_rad), np.sin(leader_yaw_rad),
                          np.zeros_like(leader_yaw_rad)], axis=1)
    end_1, end_2 = bar.p - half * axis_bar, bar.p + half * axis_bar
    top_1 = anchor_p - 0.5 * params.cable_spacing_m * axis_lead
    top_2 = anchor_p + 0.5 * params.cable_spacing_m * axis_lead
    return np.stack([end_1, top_1, top_2], axis=1), np.stack([end_2, end_1, end_2], axis=1)


# Half the thickness of a rotor's swept disk (blade pitch and flapping): 1 cm on the paper's
# 0.0635 m rotors, in proportion to the rotor radius otherwise (a propeller's sweep scales with
# its size; written so that it is exactly 1 cm there).
DISK_HALF_THICKNESS_M = 0.01
PAPER_ROTOR_RADIUS_M = 0.0635


def rotor_strike(follower_p: np.ndarray, follower_R: np.ndarray,  # noqa: N803
                 rotor_offsets_body_m: np.ndarray, rotor_radius_m: float,
                 seg_a: np.ndarray, seg_b: np.ndarray, bar_radius_m: float,
                 disk_half_thickness_m: float | None = None) -> np.ndarray:
    """(n,) bool: the bar or a cable passes through one of the follower's rotor disks.

    Each rotor disk is a thin cylinder (radius ``rotor_radius_m``, ``2 disk_half_thickness_m``
    thick, the blades' sweep; None: :data:`DISK_HALF_THICKNESS_M` scaled to the radius)
    about its centre; a segment (bar or cable, radius
    ``bar_radius_m``) strikes it when the segment's point closest to the disk centre lies inside
    that cylinder grown by the segment's radius.
    """
    if disk_half_thickness_m is None:
        disk_half_thickness_m = DISK_HALF_THICKNESS_M * (rotor_radius_m / PAPER_ROTOR_RADIUS_M)
    centres = follower_p[:, None, :] + np.matmul(follower_R[:, None], rotor_offsets_body_m[
        None, :, :, None])[..., 0]  # (n, k, 3)
    axis = follower_R[:, :, 2][:, None, None, :]  # rotor axis, (n, 1, 1, 3)
    a, b = seg_a[:, None], seg_b[:, None]  # (n, 1, s, 3)
    c = centres[:, :, None]  # (n, k, 1, 3)
    ab = b - a
    t = ((c - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)
    closest = a + np.clip(t, 0.0, 1.0)[..., None] * ab
    rel = closest - c
    axial = (rel * axis).sum(-1)
    radial = np.sqrt(np.maximum((rel * rel).sum(-1) - axial * axial, 0.0))
    hit = (np.abs(axial) < disk_half_thickness_m + bar_radius_m) & (
        radial < rotor_radius_m + bar_radius_m)
    return hit.any(axis=(1, 2))
