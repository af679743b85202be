"""The default "truth" downwash: the leader's wake as a contracted jet that spreads like a round
jet.

Physics (DESIGN.md, "Downwash field"):

- hover-induced velocity from the leader's *actual* thrust, ``v_h = sqrt(T / (2 rho n pi R^2))``;
  the fully contracted near wake moves at ``w0 = 2 v_h``;
- centreline speed ``w_c(s) = w0 * L / (s + L)`` at depth ``s`` along the leader's thrust axis:
  ``w0`` at the rotor plane (no singularity) and ~1/distance far away (turbulent round jet);
- Gaussian radial profile of half-velocity width ``b(s) = b0 + k s`` (linear spreading);
- the wake trails behind a horizontally moving leader: air reaching depth ``s`` left the rotors
  ``tau(s) = int ds / w_c`` ago, so the wake centre there is displaced by ``-v_leader * tau(s)``;
- force on the follower from the momentum flux it ingests and blocks,
  ``F = c_ingest * rho * A_follower * w_rel |w_rel|`` along the wake axis, where ``w_rel`` is the
  wake speed relative to the follower's own velocity along the axis;
- a planar (radial, outward) part, zero on the axis, peaking at the force half-magnitude radius
  ``b / sqrt(2)`` at ``planar_ratio`` of the centreline vertical force;
- time-correlated turbulence: an Ornstein-Uhlenbeck process per trial (correlation time
  ``turb_corr_time_s``), multiplicative on the axial force (sd ``turb_vertical`` of the local mean)
  and additive in the plane (sd ``turb_lateral`` of the local mean axial force).

With the default parameters, directly below a hovering 0.7 kg leader (0.7 kg follower) the mean
downward acceleration is about 4.4 m/s² at 0.36 m, 3.0 at 0.64 m and 1.5 at 1.35 m, the
calibration of DESIGN.md (checked in ``tests/unit/test_downwash.py``).
"""

from __future__ import annotations

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.geometry import dot_rows, norm_rows

_LN2 = np.log(2.0)
# max over x of x * exp(-ln2 x^2): the planar profile's peak, used to normalise planar_ratio.
_PLANAR_PEAK = np.sqrt(1.0 / (2.0 * _LN2)) * np.exp(-0.5)


class RoundJetField:
    """Physically grounded default downwash field (see the module docstring).

    Args:
        core_length_m: ``L`` of the centreline decay ``w0 L / (s + L)``.
        half_width0_m: velocity half-width of the wake at the rotor plane.
        spread_rate: growth of the half-width per metre of depth.
        ingest_coeff: fraction of the follower's disk momentum flux felt as force.
        planar_ratio: peak planar force as a fraction of the centreline axial force.
        turb_vertical: axial turbulence sd as a fraction of the local mean.
        turb_lateral: planar turbulence sd as a fraction of the local mean axial force.
        turb_corr_time_s: turbulence correlation time.
        bar_drag_coeff: drag coefficient of the docking bar (cylinder, cross-flow).
        rotor_radius_m, n_rotors, air_density_kgpm3: vehicle and air constants (both vehicles).
    """

    def __init__(
        self,
        core_length_m: float = 0.99,
        half_width0_m: float = 0.11,
        spread_rate: float = 0.15,
        ingest_coeff: float = 0.42,
        planar_ratio: float = 0.15,
        turb_vertical: float = 0.22,
        turb_lateral: float = 0.08,
        turb_corr_time_s: float = 0.08,
        bar_drag_coeff: float = 1.2,
        rotor_radius_m: float = 0.0635,
        n_rotors: int = 4,
        air_density_kgpm3: float = 1.225,
    ):
        for name, value in (("core_length_m", core_length_m), ("half_width0_m", half_width0_m),
                            ("turb_corr_time_s", turb_corr_time_s),
                            ("rotor_radius_m", rotor_radius_m)):
            if not value > 0:
                raise ValueError(f"RoundJetField: {name} must be > 0, got {value!r}")
        self.core_length_m = core_length_m
        self.half_width0_m = half_width0_m
        self.spread_rate = spread_rate
        self.ingest_coeff = ingest_coeff
        self.planar_ratio = planar_ratio
        self.turb_vertical = turb_vertical
        self.turb_lateral = turb_lateral
        self.turb_corr_time_s = turb_corr_time_s
        self.bar_drag_coeff = bar_drag_coeff
        self.disk_area_m2 = n_rotors * np.pi * rotor_radius_m**2
        self.air_density_kgpm3 = air_density_kgpm3
        self._noise = np.zeros((0, 3))
        self._rng = np.random.default_rng(0)
        self._ou: tuple[float, float, float] | None = None  # (dt, decay, innovation scale)
        # The leader's part of the wake, computed by acceleration() and reused by the
        # bar_force_n() call of the same physics step (same leader object), then dropped.
        self._lead_key: BodyState | None = None
        self._lead_wake: tuple | None = None

    # -- protocol ---------------------------------------------------------------------------
    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Start ``n`` trials; turbulence starts from its stationary distribution."""
        self._rng = rng
        self._noise = rng.standard_normal((n, 3))
        self._lead_key = self._lead_wake = None

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) acceleration on the follower, m/s², NED; advances the turbulence by ``dt``."""
        if self._noise.shape[0] != leader.n:
            self.reset(leader.n, self._rng)
        ou = self._ou
        if ou is None or ou[0] != dt:
            decay = np.exp(-dt / self.turb_corr_time_s)
            ou = self._ou = (dt, decay, np.sqrt(1.0 - decay**2))
        noise = self._rng.standard_normal(self._noise.shape)
        noise *= ou[2]
        noise += ou[1] * self._noise
        self._noise = noise
        lead = self._leader_wake(leader)
        self._lead_key, self._lead_wake = leader, lead
        return self._accel(leader, follower.p, follower.v, follower.mass_kg, noise, lead)

    # -- extras used by the simulator, the oracle and `field probe` ---------------------------
    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean (turbulence-free) acceleration on the follower, m/s², NED."""
        return self._accel(leader, follower.p, follower.v, follower.mass_kg, None)

    def wind_mps(self, leader: BodyState, points_m: np.ndarray) -> np.ndarray:
        """(n, 3) mean wake air velocity at ``points_m`` (n, 3), NED (used for the bar's drag)."""
        axis, _, speed, _, _ = self._wake(leader, points_m)
        return axis * speed[:, None]

    # -- internals -----------------------------------------------------------------------------
    def _leader_wake(self, leader: BodyState) -> tuple:
        """The parts of :meth:`_wake` that depend on the leader only."""
        axis = leader.R[:, :, 2]  # body z (down when level): the wake's direction
        thrust = np.maximum(leader.thrust_n, 0.0)
        w0 = 2.0 * np.sqrt(thrust / (2.0 * self.air_density_kgpm3 * self.disk_area_m2))
        lv = leader.v
        v_perp = lv - dot_rows(lv, axis)[:, None] * axis
        return axis, w0, np.maximum(w0, 1e-6), v_perp

    def _wake(self, leader: BodyState, points_m: np.ndarray, lead: tuple | None = None):
        """Axis, radial vector, local wake speed, centreline speed and force half-radius."""
        axis, w0, w0_min, v_perp = self._leader_wake(leader) if lead is None else lead
        rel = points_m - leader.p
        depth = dot_rows(rel, axis)
        s = np.maximum(depth, 0.0)
        lc = self.core_length_m
        centre_speed = w0 * lc
        centre_speed /= s + lc
        # Wake skew: convection time from the rotor to depth s, tau = int_0^s ds'/w_c(s').
        tau = s**2 / (2.0 * lc)
        tau += s
        tau /= w0_min
        radial = rel - depth[:, None] * axis
        radial += v_perp * tau[:, None]
        r = norm_rows(radial)
        half_width = self.spread_rate * s
        half_width += self.half_width0_m
        g = r / half_width
        g *= g
        g *= -_LN2
        speed = centre_speed * np.exp(g, out=g)
        below = depth < 0.0
        if below.any():  # nothing above the rotors
            speed *= np.where(below, np.exp(-((depth / 0.05) ** 2)), 1.0)
        return axis, radial, speed, r, half_width / np.sqrt(2.0)

    def _accel(self, leader, p_m, v_mps, mass_kg, noise, lead=None) -> np.ndarray:
        axis, radial, speed, r, force_half_radius = self._wake(leader, p_m, lead)
        w_rel = speed - dot_rows(v_mps, axis) * (speed > 0)
        k = self.ingest_coeff * self.air_density_kgpm3 * self.disk_area_m2 / mass_kg
        axial = k * w_rel
        axial *= np.abs(w_rel)
        x = r / force_half_radius
        unit_radial = radial / np.maximum(r, 1e-9)[:, None]
        planar = (self.planar_ratio / _PLANAR_PEAK) * axial
        planar *= x
        if noise is not None:
            R = leader.R  # noqa: N806
            lateral = self.turb_lateral * np.abs(axial)
            out = (axial * (1.0 + self.turb_vertical * noise[:, 0]))[:, None] * axis
            out += planar[:, None] * unit_radial
            out += (lateral * noise[:, 1])[:, None] * R[:, :, 0]
            out += (lateral * noise[:, 2])[:, None] * R[:, :, 1]
            return out
        out = axial[:, None] * axis
        out += planar[:, None] * unit_radial
        return out

    def bar_force_n(self, leader: BodyState, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                    bar_area_m2: float) -> np.ndarray:
        """(n, 3) mean drag force of the wake on the docking bar, N, NED."""
        lead = self._lead_wake if leader is self._lead_key else None
        self._lead_key = self._lead_wake = None
        axis, _, speed, _, _ = self._wake(leader, bar_p_m, lead)
        w_rel = speed - dot_rows(bar_v_mps, axis) * (speed > 0)
        drag = 0.5 * self.air_density_kgpm3 * self.bar_drag_coeff * bar_area_m2
        return (drag * w_rel * np.abs(w_rel))[:, None] * axis

