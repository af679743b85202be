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

The wake also acts where it is felt (``wrench``): on each rotor disk of the follower (giving a
torque when the follower is off the wake's axis) and on the hanging bar (``bar_force_n``: drag of
the bar's velocity relative to the turbulent wake air); see those methods.

With the default parameters, directly below a hovering 0.7 kg leader (0.7 kg follower) the mean
downward acceleration is about 4.4 m/s² at 0.36 m, 3.0 at 0.64 m and 1.5 at 1.35 m, the
calibration of DESIGN.md (checked in ``tests/unit/test_downwash.py``).
"""

from __future__ import annotations

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.rng import standard_normal_t

_LN2 = np.log(2.0)
_SQRT2 = np.sqrt(2.0)
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
        turb_corr_time_s: turbulence correlation time (follower and bar).
        bar_drag_coeff: drag coefficient of the docking bar (cylinder, cross-flow).
        bar_turb_vertical: sd of the bar's drag along the wake axis, as a fraction of its local
            mean (DESIGN.md's vertical 20-25 %; default the follower's).
        bar_turb_lateral: sd of the bar's drag across the wake axis, as a fraction of its local
            mean axial drag (DESIGN.md's lateral 5-10 %; default the follower's).
        rotor_radius_m, n_rotors, air_density_kgpm3: the follower's rotors (the disks that
            ingest the wake) and the air; the leader's too unless given apart.
        leader_rotor_radius_m, leader_n_rotors: the leader's rotors, whose disk area sets the
            wake's speed ``w0 = 2 v_h`` (None: the follower's, a pair of one vehicle type).
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
        bar_turb_vertical: float = 0.22,
        bar_turb_lateral: float = 0.08,
        rotor_radius_m: float = 0.0635,
        n_rotors: int = 4,
        air_density_kgpm3: float = 1.225,
        leader_rotor_radius_m: float | None = None,
        leader_n_rotors: int | None = None,
    ):
        lead_radius_m = rotor_radius_m if leader_rotor_radius_m is None else leader_rotor_radius_m
        for name, value in (("core_length_m", core_length_m), ("half_width0_m", half_width0_m),
                            ("turb_corr_time_s", turb_corr_time_s),
                            ("rotor_radius_m", rotor_radius_m),
                            ("leader_rotor_radius_m", lead_radius_m)):
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
        self.bar_turb_vertical = bar_turb_vertical
        self.bar_turb_lateral = bar_turb_lateral
        self.disk_area_m2 = n_rotors * np.pi * rotor_radius_m**2
        self.leader_disk_area_m2 = (
            (n_rotors if leader_n_rotors is None else leader_n_rotors) * np.pi * lead_radius_m**2)
        self.air_density_kgpm3 = air_density_kgpm3
        # Turbulence states, component-major (3, n) like the hot loop's work arrays.
        self._noise = np.zeros((3, 0))
        self._bar_noise = np.zeros((3, 0))
        self._rng = np.random.default_rng(0)
        self._ou: tuple[float, float, float] | None = None  # (dt, decay, innovation scale)
        self._last_dt: float | None = None
        # The leader's part of the wake, computed by acceleration() and reused by the
        # bar_force_n() call of the same physics step (same leader object), then dropped.
        self._lead_key: BodyState | None = None
        self._lead_wake: tuple | None = None

    # -- protocol ---------------------------------------------------------------------------
    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Start ``n`` trials; turbulence (follower's, then bar's) starts from its stationary
        distribution, drawn from ``rng`` (per trial with a :class:`aerodock.rng.TrialRNG`)."""
        self._rng = rng
        self._noise = standard_normal_t(rng, n, 3)
        self._bar_noise = standard_normal_t(rng, n, 3)
        self._lead_key = self._lead_wake = None

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) acceleration on the follower, m/s², NED; advances the turbulence by ``dt``."""
        return np.ascontiguousarray(self._accel_step(leader, follower, dt).T)

    def _accel_step(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """:meth:`acceleration`, component-major (3, n)."""
        if self._noise.shape[1] != leader.n:
            self.reset(leader.n, self._rng)
        noise = self._noise = self._ou_step(self._noise, dt)
        self._last_dt = dt
        lead = self._leader_wake(leader)
        self._lead_key, self._lead_wake = leader, lead
        return self._accel(leader, follower.p, follower.v, follower.mass_kg, noise, lead)

    def wrench(self, leader: BodyState, follower: BodyState, rotor_offsets_body_m: np.ndarray,
               dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Force (n, 3), N, world NED, and torque (n, 3), N·m, in the follower's body frame about
        its centre of mass, from the wake sampled at each rotor disk; advances the turbulence by
        ``dt`` exactly as :meth:`acceleration` does (call one of them per physics step).

        The total force is the calibrated one, ``acceleration * mass`` (same turbulence draw),
        so force and acceleration agree exactly and DESIGN.md's calibration table holds for
        both. It is shared among the rotor disks (``rotor_offsets_body_m`` (k, 3), FRD) in
        proportion to the wake's dynamic pressure ``rho w_k^2 / 2`` at each disk centre: the
        split that sampling each disk with its own area gives (a disk ingests the momentum flux
        of the air it sits in), while the sum stays the whole-vehicle force the calibration
        was measured as. Point samples of a narrow wake at the disks (0.135 m off the centre)
        alone would give about 40 % of the calibrated force on the axis, because a real
        follower's inflow draws wake air into all of its rotors. The force thus acts at the
        disks' centre of pressure ``c = sum_k share_k r_k`` and the torque is
        ``c x (R^T F)``: zero for a level follower on the wake's axis (equal shares) and, off
        the axis, pushing the rotors nearer the axis down, tilting the follower towards the
        axis (the paper's oscillatory behaviour near the wake's edge). Turbulence scales the
        whole wrench (uncorrelated per-disk turbulence is not modelled).
        """
        # Component-major (3, n) work arrays: every operation runs on contiguous rows of n.
        force = self._accel_step(leader, follower, dt)
        force *= np.asarray(follower.mass_kg, dtype=float)
        offsets = np.asarray(rotor_offsets_body_m, dtype=float).reshape(-1, 3)
        c = self._pressure_centre_body(leader, follower, offsets, self._lead_wake)
        R = follower.R  # noqa: N806
        f0, f1, f2 = force
        # R^T F, column by column (rounding independent of the batch size, like dot_rows)
        fb = R[:, 0, :].T * f0
        fb += R[:, 1, :].T * f1
        fb += R[:, 2, :].T * f2
        torque = np.empty((f0.shape[0], 3))  # centre x force_body, written out
        np.multiply(c[1], fb[2], out=torque[:, 0])
        torque[:, 0] -= c[2] * fb[1]
        np.multiply(c[2], fb[0], out=torque[:, 1])
        torque[:, 1] -= c[0] * fb[2]
        np.multiply(c[0], fb[1], out=torque[:, 2])
        torque[:, 2] -= c[1] * fb[0]
        return np.ascontiguousarray(force.T), torque

    # -- extras used by the simulator, the oracle and `field probe` ---------------------------
    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean (turbulence-free) acceleration on the follower, m/s², NED."""
        return np.ascontiguousarray(
            self._accel(leader, follower.p, follower.v, follower.mass_kg, None).T)

    def wind_mps(self, leader: BodyState, points_m: np.ndarray) -> np.ndarray:
        """(n, 3) mean wake air velocity at ``points_m`` (n, 3), NED (used for the bar's drag)."""
        axis, _, speed, _, _ = self._wake(leader.p, points_m, self._leader_wake(leader))
        return np.ascontiguousarray((axis * speed).T)

    def bar_force_n(self, leader: BodyState, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                    bar_area_m2: float, dt: float | None = None,
                    bar_axis: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) drag force of the turbulent wake air on the docking bar, N, NED.

        Quadratic drag of the bar's velocity relative to the local air,
        ``F = rho C_d A |u_rel| u_rel / 2`` with ``u_rel = w (1 + a n_v) e_axis
        + w b (n_1 e_1 + n_2 e_2) - v_bar``, where ``w`` is the local mean wake speed, ``n_*``
        the bar's own Ornstein-Uhlenbeck turbulence (correlation time ``turb_corr_time_s``,
        drawn per trial from the ``rng`` given to :meth:`reset`), ``e_1, e_2`` the leader's body
        x and y, ``a = bar_turb_vertical / 2`` and ``b = bar_turb_lateral``: so the drag's sd is
        ``bar_turb_vertical`` of its mean along the axis and ``bar_turb_lateral`` of it across
        (drag grows with the square of the speed). Outside the wake the bar feels the drag of
        its own motion through still air.

        Args:
            leader: the leader's state.
            bar_p_m, bar_v_mps: (n, 3) bar centre position, m, and velocity, m/s.
            bar_area_m2: projected area (length x diameter), m².
            dt: physics step, s; the bar's turbulence advances by it. ``None`` (a world that
                predates it) advances by the step of the last :meth:`acceleration` call.
            bar_axis: (n, 3) unit vectors along the bar, NED: only the flow across the
                cylinder makes drag (cross-flow principle). ``None``: all of ``u_rel`` counts.
        """
        lead = self._lead_wake if leader is self._lead_key else self._leader_wake(leader)
        self._lead_key = self._lead_wake = None
        axis, _, speed, _, _ = self._wake(leader.p, bar_p_m, lead)  # component-major (3, n)
        n = axis.shape[1]
        if self._bar_noise.shape[1] != n:
            self._bar_noise = standard_normal_t(self._rng, n, 3)
        step = dt if dt is not None else self._last_dt
        if step is not None and step > 0:
            self._bar_noise = self._ou_step(self._bar_noise, step)
        noise = self._bar_noise
        R = leader.R  # noqa: N806
        along = 0.5 * self.bar_turb_vertical * noise[0]
        along += 1.0
        along *= speed
        rel = axis * along
        lateral = self.bar_turb_lateral * speed
        work = np.array(R[:, :, 0].T, dtype=float, order="C")  # a copy, even for n = 1
        rel += np.multiply(work, lateral * noise[1], out=work)
        np.copyto(work, R[:, :, 1].T)
        rel += np.multiply(work, lateral * noise[2], out=work)
        rel -= np.asarray(bar_v_mps, dtype=float).T
        if bar_axis is not None:
            ba = np.ascontiguousarray(np.asarray(bar_axis, dtype=float).T)
            across = rel * ba
            dot = across[0] + across[1]
            dot += across[2]
            rel -= np.multiply(dot, ba, out=across)
        drag = 0.5 * self.air_density_kgpm3 * self.bar_drag_coeff * bar_area_m2
        sq = rel * rel
        norm = sq[0] + sq[1]
        norm += sq[2]
        np.sqrt(norm, out=norm)
        norm *= drag
        out = np.empty((n, 3))
        np.multiply(norm, rel, out=out.T)
        return out

    # -- internals -----------------------------------------------------------------------------
    def _leader_wake(self, leader: BodyState) -> tuple:
        """The parts of :meth:`_wake` that depend on the leader only; vectors component-major
        (3, n)."""
        # body z (down when level): the wake's direction
        axis = np.array(leader.R[:, :, 2].T, dtype=float, order="C")
        thrust = np.maximum(leader.thrust_n, 0.0)
        w0 = 2.0 * np.sqrt(thrust / (2.0 * self.air_density_kgpm3 * self.leader_disk_area_m2))
        lv = np.ascontiguousarray(np.asarray(leader.v, dtype=float).T)
        prod = lv * axis
        along = prod[0] + prod[1]
        along += prod[2]
        v_perp = np.multiply(along, axis, out=prod)
        np.subtract(lv, v_perp, out=v_perp)
        return axis, w0, np.maximum(w0, 1e-6), v_perp

    def _wake(self, leader_p_m: np.ndarray, points_m: np.ndarray, lead: tuple):
        """Axis, radial vector (both component-major, (3, n)), local wake speed, distance from
        the wake's centre and force half-radius at ``points_m`` (n, 3), for leaders at
        ``leader_p_m`` with wake parts ``lead`` (:meth:`_leader_wake`)."""
        axis, w0, w0_min, v_perp = lead
        rel = np.subtract(np.asarray(points_m, dtype=float).T,
                          np.asarray(leader_p_m, dtype=float).T, out=np.empty(axis.shape))
        prod = rel * axis
        depth = prod[0] + prod[1]
        depth += prod[2]
        s = np.maximum(depth, 0.0)
        lc = self.core_length_m
        centre_speed = w0 * lc
        centre_speed /= s + lc
        # Wake skew: convection time from the rotor to depth s, tau = int_0^s ds'/w_c(s').
        tau = s * s
        tau /= 2.0 * lc
        tau += s
        tau /= w0_min
        radial = rel
        radial -= np.multiply(depth, axis, out=prod)
        radial += np.multiply(v_perp, tau, out=prod)
        np.multiply(radial, radial, out=prod)
        r = prod[0] + prod[1]
        r += prod[2]
        np.sqrt(r, out=r)
        half_width = self.spread_rate * s
        half_width += self.half_width0_m
        g = r / half_width
        g *= g
        g *= -_LN2
        speed = centre_speed * np.exp(g, out=g)
        below = depth < 0.0
        if below.any():  # nothing above the rotors
            speed *= np.where(below, np.exp(-((depth / 0.05) ** 2)), 1.0)
        return axis, radial, speed, r, half_width / _SQRT2

    def _accel(self, leader, p_m, v_mps, mass_kg, noise, lead=None) -> np.ndarray:
        """The acceleration on followers at ``p_m`` moving at ``v_mps``, component-major (3, n);
        ``noise`` (3, n) the turbulence (None: the mean)."""
        lead = self._leader_wake(leader) if lead is None else lead
        axis, radial, speed, r, force_half_radius = self._wake(leader.p, p_m, lead)
        prod = np.array(np.asarray(v_mps, dtype=float).T, order="C")  # a copy, even for n = 1
        prod *= axis
        w_rel = prod[0] + prod[1]
        w_rel += prod[2]
        w_rel *= speed > 0
        np.subtract(speed, w_rel, out=w_rel)
        k = self.ingest_coeff * self.air_density_kgpm3 * self.disk_area_m2 / mass_kg
        axial = k * w_rel
        axial *= np.abs(w_rel)
        x = r / force_half_radius
        unit_radial = np.divide(radial, np.maximum(r, 1e-9), out=radial)
        planar = (self.planar_ratio / _PLANAR_PEAK) * axial
        planar *= x
        if noise is not None:
            R = leader.R  # noqa: N806
            lat0, lat1 = np.ascontiguousarray(R[:, :, 0].T), np.ascontiguousarray(R[:, :, 1].T)
            lateral = np.abs(axial)
            lateral *= self.turb_lateral
            along = self.turb_vertical * noise[0]
            along += 1.0
            along *= axial
            out = axis * along
            out += np.multiply(planar, unit_radial, out=prod)
            out += np.multiply(lat0, lateral * noise[1], out=prod)
            out += np.multiply(lat1, lateral * noise[2], out=prod)
            return out
        out = axis * axial
        out += np.multiply(planar, unit_radial, out=prod)
        return out

    def _ou_step(self, state: np.ndarray, dt: float) -> np.ndarray:
        """One Ornstein-Uhlenbeck step of a unit-variance state (3, n) (correlation time
        ``turb_corr_time_s``), with fresh draws from the trial's random source."""
        ou = self._ou
        if ou is None or ou[0] != dt:
            decay = np.exp(-dt / self.turb_corr_time_s)
            ou = self._ou = (dt, decay, np.sqrt(1.0 - decay**2))
        noise = standard_normal_t(self._rng, state.shape[1], state.shape[0]) * ou[2]
        noise += ou[1] * state
        return noise

    def _pressure_centre_body(self, leader: BodyState, follower: BodyState,
                              offsets_body_m: np.ndarray, lead: tuple | None) -> np.ndarray:
        """(3, n) body-frame centre of the rotor disks (component-major) weighted by the wake's
        dynamic pressure at each disk centre (equal weights where no disk is in the wake).

        The wake of :meth:`_wake` evaluated at the (n, k) disk centres at once; the factor
        ``w0^2`` common to a trial's disks cancels in the weights and is left out. Elementwise
        arithmetic only, so each trial's rounding is independent of the batch size.
        """
        axis, _, w0_min, v_perp = self._leader_wake(leader) if lead is None else lead
        R = follower.R  # noqa: N806
        # Work arrays (3 components, k disks, n trials): every operation runs on rows of n.
        k = offsets_body_m.shape[0]
        n = axis.shape[1]
        ox, oy, oz = (offsets_body_m[:, i:i + 1] for i in range(3))  # (k, 1)
        rt = np.ascontiguousarray(R.transpose(2, 1, 0))  # rt[j, i] = R[:, i, j], rows of n
        d = np.ascontiguousarray((follower.p - leader.p).T)[:, None, :]
        rel = np.multiply(rt[0][:, None, :], ox, out=np.empty((3, k, n)))  # disk centres
        prod = np.multiply(rt[1][:, None, :], oy, out=np.empty((3, k, n)))
        rel += prod
        if oz.any():
            rel += np.multiply(rt[2][:, None, :], oz, out=prod)
        rel += d
        axis3 = axis[:, None, :]
        np.multiply(rel, axis3, out=prod)
        depth = prod[0] + prod[1]
        depth += prod[2]
        s = np.maximum(depth, 0.0)
        lc = self.core_length_m
        tau = s * s
        tau *= 0.5 / lc
        tau += s
        tau /= w0_min
        radial = rel
        radial -= np.multiply(depth, axis3, out=prod)
        radial += np.multiply(v_perp[:, None, :], tau, out=prod)
        radial *= radial
        r2 = radial[0] + radial[1]
        r2 += radial[2]
        half_width = self.spread_rate * s
        half_width += self.half_width0_m
        r2 /= half_width * half_width
        r2 *= -2.0 * _LN2
        pressure = np.exp(r2, out=r2)
        centre_speed = s + lc
        np.divide(lc, centre_speed, out=centre_speed)
        pressure *= centre_speed * centre_speed
        above = depth < 0.0
        if above.any():  # nothing above the rotors (as in _wake)
            pressure *= np.where(above, np.exp(-2.0 * (depth / 0.05) ** 2), 1.0)
        total = pressure[0].copy()
        for j in range(1, k):
            total += pressure[j]
        inside = total > 1e-300
        if inside.all():
            pressure /= total
            share = pressure
        else:
            share = np.where(inside, pressure / np.where(inside, total, 1.0), 1.0 / k)
        cols = offsets_body_m[:, :, None]  # (k, 3, 1)
        centre = np.multiply(cols[0], share[0], out=np.empty((3, n)))
        work = np.empty((3, n))
        for j in range(1, k):
            centre += np.multiply(cols[j], share[j], out=work)
        return centre
