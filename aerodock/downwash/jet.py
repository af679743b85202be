"""The default "truth" downwash: the leader's wake as a momentum-conserving turbulent round jet,
felt on each rotor disk of the follower and on its body.

Physics (DESIGN.md, "Downwash field"; the parameters are fitted to real flights by
``aerodock field fit``, :mod:`aerodock.learning.wake_fit`, and are dimensionless, so one set
serves every pair of vehicles: the world's rotor sizes and the leader's thrust give the scales):

- **A jet that conserves momentum.** Below the leader the wake's axial velocity is a Gaussian of
  half-velocity width ``b(s) = b0 + k s`` at depth ``s`` along the leader's thrust axis,
  ``w(r, s) = w_c(s) exp(-ln2 r^2 / b^2)``. Its momentum flux through any plane below the leader,
  ``rho int w^2 dA = rho w_c^2 pi b^2 / (2 ln2)``, equals the leader's thrust ``T``, so the
  centreline speed follows from the width: ``w_c(s) = sqrt(2 ln2 T / (rho pi)) / b(s)`` (finite
  at the rotor plane, ~1/distance far away, the turbulent round jet's decay).
  ``b0 = width0_ratio * R_eq`` with ``R_eq = R sqrt(n)`` the leader's equivalent disk radius;
  ``width0_ratio = sqrt(ln2) = 0.83`` is momentum theory's fully contracted wake (area ``A/2``
  at ``2 v_h``), ``k = spread_rate``.
- **Wake skew**: air reaching depth ``s`` left the rotors ``tau(s) = int ds / w_c`` ago, so behind
  a horizontally moving leader the wake's centre there is displaced by ``-v_leader * tau(s)``.
- **On each rotor disk** of the follower (centres ``rotor_offsets_body_m``, radius ``R_f``): the
  thrust the disk loses to the wake air it ingests, ``F = c rho A_d v_hf^(2-p) phi(w_d)`` along
  the wake's axis, with ``v_hf`` the follower's own hover-induced velocity,
  ``phi(w) = sign(w) |w|^p``, ``c = ingest_coeff`` and ``p = ingest_exponent`` (1: a rotor at a
  fixed command loses thrust in proportion to the axial inflow, blade-element theory at small
  inflow; 2: the disk takes the momentum flux ``rho A w^2``); ``w_d^p`` is ``w^p`` averaged over
  the disk (the Gaussian blurred by the disk, exact in the disk's second moment). The follower's
  own axial velocity ``v`` enters as ``phi(w_d - v) - phi(-v)``: the still-air part
  ``phi(-v)`` is the vehicle's own drag, which its model already has.
- **On the body** (top area ``body_area_ratio`` of the follower's total disk area, at its centre
  of mass): drag of the wake air, ``rho C_d A_b phi_2(w_b) / 2``, the same way.
- **A planar part** on each disk and the body, zero on the wake's axis, ``planar_ratio`` times the
  local axial force times ``r / r_half`` along the outward radial direction (``r_half`` the
  force's half-magnitude radius): for a point follower it peaks at ``r_half / sqrt(2 ln2)`` at
  ``planar_ratio`` of the centreline axial force; a negative ratio points inwards.
- **The disks' differences, scaled** (``disk_torque_gain``, 1 by default): each disk's mean axial
  force is its disks' mean plus ``disk_torque_gain`` times its difference from it, so the net
  force and the turbulence stay as they are and the axial forces' mean torque scales by the
  gain. The real
  Crazyflie flights' logged motor torques put the wake's torque at 5-8 times this jet's
  (docs/crazyflie.md, "The wake's torque in the logs"), by no mechanism the jet has; the default
  keeps the jet's own, and a world can ask for the logs' to see what it costs.
- **Turbulence per rotor disk**: each disk's axial force is scaled by ``1 + turb_vertical n_k``,
  ``n_k`` a unit Ornstein-Uhlenbeck process of its own, correlated with the other disks' by the
  jet's integral length scale ``l = turb_length_ratio * b``: a process shared by the disks (and
  the body's) times ``sqrt(rho)`` plus the disk's own times ``sqrt(1 - rho)``, with
  ``rho = exp(-d / l)`` for the disks' mean spacing ``d``; their differences are a torque. The
  sideways gusts are one process for the whole follower: each disk and the body are pushed by
  ``turb_lateral |F_k| (m e1 + l e2)`` (``e1, e2`` across the wake's axis; per-disk lateral
  processes would double the random draws of a step for a yaw torque only). The correlation
  time is the local eddy turnover time, ``turb_time_ratio * b / w_c`` at the follower's depth.

A field offers the two parts separately (:meth:`RoundJetField.wrench`: the disks' force and
torque; :meth:`RoundJetField.body_force_n`: the body's force, of the same step's turbulence) and
together (:meth:`RoundJetField.acceleration`, :meth:`RoundJetField.mean_acceleration`). The bar
under the leader feels drag of the wake air (:meth:`RoundJetField.bar_force_n`).
"""

from __future__ import annotations

import copy

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.downwash.wrench import quad_rotor_offsets_body_m
from aerodock.frozen import freeze, is_frozen
from aerodock.rng import standard_normal_t

_LN2 = float(np.log(2.0))
# max over x of x * exp(-ln2 x^2): the planar profile's peak, used to normalise planar_ratio.
_PLANAR_PEAK = float(np.sqrt(1.0 / (2.0 * _LN2)) * np.exp(-0.5))
CONTRACTED_WIDTH0_RATIO = float(np.sqrt(_LN2))
"""``b0 / R_eq`` of momentum theory's fully contracted wake (area ``A/2`` moving at ``2 v_h``)."""
_SHARED_ROWS = 3  # the follower's shared processes: axial, lateral 1, lateral 2


def centreline_speed_mps(thrust_n: np.ndarray, half_width_m: np.ndarray,
                         air_density_kgpm3: float) -> np.ndarray:
    """Centreline speed of a Gaussian jet of half-velocity width ``half_width_m`` whose momentum
    flux equals ``thrust_n``: ``sqrt(2 ln2 T / (rho pi)) / b``, m/s."""
    thrust = np.maximum(np.asarray(thrust_n, dtype=float), 0.0)
    return np.sqrt(2.0 * _LN2 * thrust / (air_density_kgpm3 * np.pi)) / half_width_m


def mean_pair_distance_m(offsets_m: np.ndarray) -> float:
    """Mean distance between the rotor-disk centres ``offsets_m`` (k, 3), m (0 for one disk)."""
    k = offsets_m.shape[0]
    if k < 2:
        return 0.0
    diff = offsets_m[:, None, :] - offsets_m[None, :, :]
    dist = np.sqrt((diff * diff).sum(-1))
    return float(dist[np.triu_indices(k, 1)].mean())


class RoundJetField:
    """Physically grounded default downwash field (see the module docstring).

    Args:
        width0_ratio: the wake's half-velocity width at the rotor plane over the leader's
            equivalent disk radius ``R sqrt(n)``.
        spread_rate: growth of the half-width per metre of depth.
        ingest_coeff: ``c`` of a disk's force ``c rho A v_hf^(2-p) |w|^p``.
        ingest_exponent: ``p`` of that law (1: linear in the inflow; 2: the momentum flux).
        planar_ratio: peak planar force of a point follower as a fraction of the centreline
            axial force (negative: inwards).
        body_area_ratio: the follower's body top area over its total rotor disk area.
        body_drag_coeff: drag coefficient of the body in the wake (a flat plate: 1.2).
        disk_torque_gain: the disks' mean axial forces' differences from their mean, scaled
            (1: the jet's own torque; the net force is unchanged).
        turb_vertical: sd of each disk's axial force as a fraction of its local mean.
        turb_lateral: sd of the follower's gust across the axis (one process for all disks and
            the body), a fraction of each one's local mean axial force.
        turb_length_ratio: the jet's integral length scale over its half-width (sets how much
            the disks' turbulence is shared).
        turb_time_ratio: the turbulence's correlation time over ``b / w_c`` at the follower.
        bar_drag_coeff: drag coefficient of the docking bar (cylinder, cross-flow).
        bar_turb_vertical: sd of the bar's drag along the wake axis, a fraction of its mean.
        bar_turb_lateral: sd of the bar's drag across the wake axis, a fraction of its mean
            axial drag.
        leader_rotor_radius_m, leader_n_rotors: the leader's rotors (the jet's width at the
            rotor plane).
        follower_rotor_radius_m, follower_n_rotors, follower_diagonal_m: the follower's rotors
            (the disks the wake is felt on; an X frame).
        air_density_kgpm3, gravity_mps2: air and gravity.
    """

    def __init__(
        self,
        width0_ratio: float = 1.008,
        spread_rate: float = 0.02309,
        ingest_coeff: float = 0.4989,
        ingest_exponent: float = 0.5573,
        planar_ratio: float = -0.004125,
        body_area_ratio: float = 0.2,
        body_drag_coeff: float = 1.2,
        disk_torque_gain: float = 1.0,
        turb_vertical: float = 0.2478,
        turb_lateral: float = 0.05196,
        turb_length_ratio: float = 0.4736,
        turb_time_ratio: float = 3.829,
        bar_drag_coeff: float = 1.2,
        bar_turb_vertical: float = 0.22,
        bar_turb_lateral: float = 0.08,
        leader_rotor_radius_m: float = 0.0635,
        leader_n_rotors: int = 4,
        follower_rotor_radius_m: float = 0.0635,
        follower_n_rotors: int = 4,
        follower_diagonal_m: float = 0.27,
        air_density_kgpm3: float = 1.225,
        gravity_mps2: float = 9.81,
    ):
        positive = (("width0_ratio", width0_ratio), ("ingest_exponent", ingest_exponent),
                    ("turb_length_ratio", turb_length_ratio),
                    ("turb_time_ratio", turb_time_ratio),
                    ("leader_rotor_radius_m", leader_rotor_radius_m),
                    ("follower_rotor_radius_m", follower_rotor_radius_m),
                    ("follower_diagonal_m", follower_diagonal_m),
                    ("air_density_kgpm3", air_density_kgpm3))
        for name, value in positive:
            if not value > 0:
                raise ValueError(f"RoundJetField: {name} must be > 0, got {value!r}")
        for name, value in (("spread_rate", spread_rate), ("ingest_coeff", ingest_coeff),
                            ("body_area_ratio", body_area_ratio),
                            ("body_drag_coeff", body_drag_coeff),
                            ("disk_torque_gain", disk_torque_gain),
                            ("turb_vertical", turb_vertical), ("turb_lateral", turb_lateral)):
            if not value >= 0:
                raise ValueError(f"RoundJetField: {name} must be >= 0, got {value!r}")
        self.width0_ratio = float(width0_ratio)
        self.spread_rate = float(spread_rate)
        self.ingest_coeff = float(ingest_coeff)
        self.ingest_exponent = float(ingest_exponent)
        self.planar_ratio = float(planar_ratio)
        self.body_area_ratio = float(body_area_ratio)
        self.body_drag_coeff = float(body_drag_coeff)
        self.disk_torque_gain = float(disk_torque_gain)
        self.turb_vertical = float(turb_vertical)
        self.turb_lateral = float(turb_lateral)
        self.turb_length_ratio = float(turb_length_ratio)
        self.turb_time_ratio = float(turb_time_ratio)
        self.bar_drag_coeff = float(bar_drag_coeff)
        self.bar_turb_vertical = float(bar_turb_vertical)
        self.bar_turb_lateral = float(bar_turb_lateral)
        self.air_density_kgpm3 = float(air_density_kgpm3)
        self.gravity_mps2 = float(gravity_mps2)
        # The leader's jet: half-width at the rotor plane, m.
        self.half_width0_m = self.width0_ratio * leader_rotor_radius_m * np.sqrt(leader_n_rotors)
        # The follower's rotors and body.
        self.follower_disk_radius_m = float(follower_rotor_radius_m)
        self.follower_disk_area_m2 = float(np.pi * follower_rotor_radius_m**2)
        self.follower_n_rotors = int(follower_n_rotors)
        self.rotor_offsets_body_m = quad_rotor_offsets_body_m(follower_diagonal_m,
                                                              self.follower_n_rotors)
        freeze(self.rotor_offsets_body_m)  # the geometry's caches key on it
        self.body_area_m2 = self.body_area_ratio * self.follower_n_rotors \
            * self.follower_disk_area_m2
        self.body_radius_m = float(np.sqrt(self.body_area_m2 / np.pi))
        self._offsets_key: tuple | None = None
        self._pair_distance_m = 0.0
        # Turbulence states, component-major: the follower's shared processes (3, n: axial, and
        # the two lateral ones), each disk's own axial one (k, n), and the bar's (3, n).
        self._common = np.zeros((_SHARED_ROWS, 0))
        self._own = np.zeros((0, 0))
        self._processes = np.zeros((_SHARED_ROWS, 0))  # both, stacked; the two are its views
        # The last read-only offsets array the pair distance was computed for, and its points
        # (see _geometry): offsets that can be written in place are compared by value.
        self._offsets_obj: np.ndarray | None = None
        self._points: tuple | None = None  # (offsets, the disks' and the body's centres, arms)
        self._planar_key: tuple | None = None  # what _planar_scale_col was computed for
        self._planar_scale_col = np.zeros((0, 1))
        self._bar_noise = np.zeros((3, 0))
        self._rng: np.random.Generator = np.random.default_rng(0)
        self._last_dt: float | None = None
        # The body's force of the last turbulent step, for body_force_n() of the same step.
        self._body_key: tuple | None = None
        self._body_force: np.ndarray | None = None
        # The leader's part of the wake, computed by the follower's step and reused by the
        # bar_force_n() call of the same physics step (same leader object), then dropped.
        self._lead_key: BodyState | None = None
        self._lead_wake: tuple | None = None
        # The force coefficients of the last read-only follower mass array (see _force_coeff),
        # and the per-row constants of _axial (see _area_columns).
        self._coeff: tuple | None = None
        self._area_key: tuple | None = None
        self._area_cols: tuple = ()

    def __setstate__(self, state: dict) -> None:
        """A copy or an unpickled field: its offsets read-only again (a copied array is
        writable), as the geometry's caches want them."""
        self.__dict__.update(state)
        freeze(self.rotor_offsets_body_m)

    # -- protocol ---------------------------------------------------------------------------
    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Start ``n`` trials; turbulence (the follower's shared processes, each disk's own,
        then the bar's) starts from its stationary distribution, drawn from ``rng`` (per trial
        with a :class:`aerodock.rng.TrialRNG`)."""
        self._rng = rng
        k = self.rotor_offsets_body_m.shape[0]
        self._draw_follower_noise(n, k)
        self._bar_noise = standard_normal_t(rng, n, 3)
        self._lead_key = self._lead_wake = None
        self._body_key = self._body_force = None

    def take_rows(self, rows: np.ndarray, rng: np.random.Generator) -> RoundJetField:
        """The field of the trials at ``rows``, their turbulence where it stands, drawing from
        ``rng`` (:class:`~aerodock.downwash.base.SupportsTakeRows`)."""
        out = copy.copy(self)  # the parameters and the geometry caches are shared
        out._rng = rng
        out._set_processes(self._processes[:, rows])
        out._coeff = None  # of the whole batch's masses (keyed by that array: never these rows')
        out._bar_noise = self._bar_noise[:, rows]
        # Kept for the rest of one physics step only (keyed by the step's objects).
        out._lead_key = out._lead_wake = None
        out._body_key = out._body_force = None
        return out

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) acceleration on the follower (its disks and its body), m/s², NED; advances the
        turbulence by ``dt``."""
        total, _, _ = self._step(leader, follower, self.rotor_offsets_body_m, dt, False,
                                 split=False)
        total /= np.asarray(follower.mass_kg, dtype=float)
        return np.ascontiguousarray(total.T)

    def wrench(self, leader: BodyState, follower: BodyState, rotor_offsets_body_m: np.ndarray,
               dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The wake on the follower's rotor disks: force (n, 3), N, world NED, and torque
        (n, 3), N·m, in its body frame about its centre of mass; advances the turbulence by
        ``dt`` exactly as :meth:`acceleration` does (call one of them per physics step). The
        force on the body is :meth:`body_force_n` (the same step's turbulence).

        Each disk (centres ``rotor_offsets_body_m`` (k, 3), FRD) takes the force of the wake
        air it ingests (module docstring), with its own partly shared turbulence; the torque is
        ``sum_k r_k x (R^T F_k)``: zero for a level follower on the wake's axis in the mean and,
        off the axis, pushing the disks nearer the axis down (the paper's oscillatory behaviour
        near the wake's edge).
        """
        offsets = _offsets(rotor_offsets_body_m)
        force, torque, _ = self._step(leader, follower, offsets, dt, True)
        return np.ascontiguousarray(force.T), torque

    def body_force_n(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) the wake's drag on the follower's body, N, NED, at its centre of mass, with the
        turbulence of this step's :meth:`wrench` (or :meth:`acceleration`) call; does not
        advance time."""
        if self._body_key is not None and self._body_key[0] is leader \
                and self._body_key[1] is follower and self._body_force is not None:
            return np.ascontiguousarray(self._body_force.T)
        _, _, body = self._forces(leader, follower, self.rotor_offsets_body_m, noisy=True,
                                  want_torque=False)
        return np.ascontiguousarray(body.T)

    # -- extras used by the simulator, the oracle, `field probe` and `field fit` --------------
    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean (turbulence-free) acceleration on the follower, m/s², NED."""
        total, _, _ = self._forces(leader, follower, self.rotor_offsets_body_m, noisy=False,
                                   want_torque=False, split=False)
        total /= np.asarray(follower.mass_kg, dtype=float)
        return np.ascontiguousarray(total.T)

    def mean_disk_torque_nm(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean (turbulence-free) torque of the wake on the follower's rotor disks about
        its centre of mass, N·m, body frame (FRD)."""
        _, torque, _ = self._forces(leader, follower, self.rotor_offsets_body_m, noisy=False,
                                    want_torque=True)
        return torque

    def turbulence(self, leader: BodyState, follower: BodyState) -> dict[str, np.ndarray]:
        """The turbulence at the follower, per trial (n,): ``corr_time_s``, the processes'
        correlation time; ``disk_share``, the share of a disk's turbulence all disks have in
        common; ``axial_var_mps4`` and ``lateral_var_mps4``, the variance of the whole
        follower's acceleration along the wake's axis and across it (per direction), m²/s⁴."""
        lead = self._leader_wake(leader)
        offsets = self.rotor_offsets_body_m
        geo = self._geometry(lead, follower, offsets)
        tau, share = self._turbulence_time_and_share(geo, offsets)
        axial = self._axial(geo, follower, lead)
        f_disk, f_body = axial[:geo["k"]], axial[geo["k"]]
        mass = np.asarray(follower.mass_kg, dtype=float)
        root = np.sqrt(share)

        def variance(disk: np.ndarray, body: np.ndarray) -> np.ndarray:
            # sum_k F_k (sqrt(rho) c + sqrt(1 - rho) e_k) + F_b c, unit independent c, e_k
            shared = root * disk.sum(axis=0) + body
            return (shared * shared + (1.0 - share) * (disk * disk).sum(axis=0)) / (mass * mass)

        axial = self.turb_vertical ** 2 * variance(f_disk, f_body)
        total = np.abs(f_disk).sum(axis=0) + np.abs(f_body)  # one lateral process for all
        lateral = (self.turb_lateral * total / mass) ** 2
        return {"corr_time_s": tau, "disk_share": share, "axial_var_mps4": axial,
                "lateral_var_mps4": lateral}

    def wind_mps(self, leader: BodyState, points_m: np.ndarray) -> np.ndarray:
        """(n, 3) mean wake air velocity at ``points_m`` (n, 3), NED (used for the bar's drag)."""
        axis, speed, _, _ = self._point_wake(self._leader_wake(leader), leader.p, points_m)
        return np.ascontiguousarray((axis * speed).T)

    def bar_force_n(self, leader: BodyState, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                    bar_area_m2: float, dt: float | None = None,
                    bar_axis: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) drag force of the turbulent wake air on the docking bar, N, NED.

        Quadratic drag of the bar's velocity relative to the local air,
        ``F = rho C_d A |u_rel| u_rel / 2`` with ``u_rel = w (1 + a n_v) e_axis
        + w b (n_1 e_1 + n_2 e_2) - v_bar``, where ``w`` is the local mean wake speed, ``n_*``
        the bar's own Ornstein-Uhlenbeck turbulence (correlation time as the follower's, at the
        bar's depth; drawn per trial from the ``rng`` given to :meth:`reset`), ``e_1, e_2`` the
        leader's body x and y, ``a = bar_turb_vertical / 2`` and ``b = bar_turb_lateral``: so
        the drag's sd is ``bar_turb_vertical`` of its mean along the axis and
        ``bar_turb_lateral`` of it across (drag grows with the square of the speed). Outside
        the wake the bar feels the drag of its own motion through still air.

        Args:
            leader: the leader's state.
            bar_p_m, bar_v_mps: (n, 3) bar centre position, m, and velocity, m/s.
            bar_area_m2: projected area (length x diameter), m².
            dt: physics step, s; the bar's turbulence advances by it. ``None`` (a world that
                predates it) advances by the step of the last follower call.
            bar_axis: (n, 3) unit vectors along the bar, NED: only the flow across the
                cylinder makes drag (cross-flow principle). ``None``: all of ``u_rel`` counts.
        """
        lead = self._lead_wake if leader is self._lead_key else self._leader_wake(leader)
        self._lead_key = self._lead_wake = None
        axis, speed, half_width, centre = self._point_wake(lead, leader.p, bar_p_m)
        n = axis.shape[1]
        if self._bar_noise.shape[1] != n:
            self._bar_noise = standard_normal_t(self._rng, n, 3)
        step = dt if dt is not None else self._last_dt
        if step is not None and step > 0:
            tau = self.turb_time_ratio * half_width / np.maximum(centre, 1e-6)
            self._bar_noise = self._ou_step(self._bar_noise, step, tau)
        noise = self._bar_noise
        along = 0.5 * self.bar_turb_vertical * noise[0]
        along += 1.0
        along *= speed
        rel = axis * along
        lateral = _lateral(lead[5], noise[1:3], self.bar_turb_lateral * speed)
        rel += lateral[0]
        rel += lateral[1]
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
    def _draw_follower_noise(self, n: int, k: int) -> None:
        draw = standard_normal_t(self._rng, n, _SHARED_ROWS + k)
        self._set_processes(np.array(draw, order="C"))

    def _set_processes(self, processes: np.ndarray) -> None:
        """The follower's turbulence states, (3 + k, n): the shared ones, then each disk's own
        (one array: a step advances them in one operation each)."""
        self._processes = processes
        self._common, self._own = processes[:_SHARED_ROWS], processes[_SHARED_ROWS:]

    def _step(self, leader: BodyState, follower: BodyState, offsets: np.ndarray, dt: float,
              want_torque: bool, split: bool = True,
              ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """Advance the follower's turbulence by ``dt`` and return the disks' force (3, n), their
        torque (n, 3) (None unless asked) and the body's force (3, n); not ``split``: the
        whole force (3, n), None, None."""
        n, k = leader.n, offsets.shape[0]
        if self._common.shape[1] != n or self._own.shape[0] != k:
            self._draw_follower_noise(n, k)
        lead = self._leader_wake(leader)
        self._lead_key, self._lead_wake = leader, lead
        geo = self._geometry(lead, follower, offsets)
        tau, share = self._turbulence_time_and_share(geo, offsets)
        # Random draws: the shared processes (axial, lateral 1, lateral 2), then each disk's own
        # axial one.
        draw = standard_normal_t(self._rng, n, _SHARED_ROWS + k)
        decay = np.exp(-dt / tau)
        innov = np.sqrt(1.0 - decay * decay)
        self._processes *= decay  # the shared processes and the disks' own, (3 + k, n)
        self._processes += draw * innov
        disks, torque, body = self._forces_from(geo, lead, leader, follower, offsets,
                                                (self._common, self._own, share), want_torque,
                                                split)
        self._body_key, self._body_force = ((leader, follower), body) if split else (None, None)
        self._last_dt = dt
        return disks, torque, body

    def _forces(self, leader: BodyState, follower: BodyState, offsets: np.ndarray, noisy: bool,
                want_torque: bool, split: bool = True,
                ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """As :meth:`_step` without advancing time: the mean (``noisy`` False) or with the
        current turbulence."""
        lead = self._leader_wake(leader)
        geo = self._geometry(lead, follower, offsets)
        noise = None
        if noisy:
            if self._common.shape[1] != leader.n or self._own.shape[0] != offsets.shape[0]:
                self._draw_follower_noise(leader.n, offsets.shape[0])
            share = self._turbulence_time_and_share(geo, offsets)[1]
            noise = (self._common, self._own, share)
        return self._forces_from(geo, lead, leader, follower, offsets, noise, want_torque, split)

    def _leader_wake(self, leader: BodyState) -> tuple:
        """The parts of the wake that depend on the leader only, component-major: the axis (body
        z) (3, n), the jet's momentum speed ``sqrt(2 ln2 T / (rho pi))`` (so that
        ``w_c = it / b``) (n,), the same floored for divisions, the leader's velocity across the
        axis (3, n) and position (3, n), and its three body axes (3, 3, n)."""
        # The leader's body axes, component-major (3 axes, 3, n): x and y carry the gusts.
        frame = np.ascontiguousarray(np.asarray(leader.R, dtype=float).transpose(2, 1, 0))
        axis = frame[2]
        thrust = np.maximum(np.asarray(leader.thrust_n, dtype=float), 0.0)
        jet = np.sqrt(thrust * (2.0 * _LN2 / (self.air_density_kgpm3 * np.pi)))
        lv = np.ascontiguousarray(np.asarray(leader.v, dtype=float).T)
        prod = lv * axis
        along = prod[0] + prod[1]
        along += prod[2]
        v_perp = np.multiply(along, axis, out=prod)
        np.subtract(lv, v_perp, out=v_perp)
        position = np.ascontiguousarray(np.asarray(leader.p, dtype=float).T)
        return axis, jet, np.maximum(jet, 1e-6), v_perp, position, frame

    def _depth_terms(self, lead: tuple, rel: np.ndarray) -> tuple[np.ndarray, ...]:
        """For points at ``rel`` (3, ..., n) from the leader (overwritten): depth along the
        axis, half-width, centreline speed (..., n) and radial vector from the (skewed) wake
        centre (3, ..., n)."""
        axis, jet, jet_min, v_perp = lead[:4]
        shape = (3,) + (1,) * (rel.ndim - 2) + (rel.shape[-1],)
        axis_b, v_perp_b = axis.reshape(shape), v_perp.reshape(shape)
        prod = rel * axis_b
        depth = prod[0] + prod[1]
        depth += prod[2]
        s = np.maximum(depth, 0.0)
        b0, k = self.half_width0_m, self.spread_rate
        half_width = k * s
        half_width += b0
        centre = jet / half_width
        # Wake skew: convection time from the rotor to depth s, int_0^s b(s') ds' / jet.
        tau = 0.5 * k * s
        tau += b0
        tau *= s
        tau /= jet_min
        radial = rel
        radial -= np.multiply(depth, axis_b, out=prod)
        radial += np.multiply(v_perp_b, tau, out=prod)
        return depth, half_width, centre, radial

    def _point_wake(self, lead: tuple, leader_p_m: np.ndarray, points_m: np.ndarray):
        """Axis (3, n), and the local axial air speed, half-width and centreline speed (n,) at
        ``points_m`` (n, 3) (a point: no averaging over an area)."""
        axis = lead[0]
        rel = np.subtract(np.asarray(points_m, dtype=float).T,
                          np.asarray(leader_p_m, dtype=float).T, out=np.empty(axis.shape))
        depth, half_width, centre, radial = self._depth_terms(lead, rel)
        r2 = radial * radial
        d2 = r2[0] + r2[1]
        d2 += r2[2]
        d2 /= half_width * half_width
        d2 *= -_LN2
        speed = centre * np.exp(d2, out=d2)
        if _fmin(depth) < 0.0:  # nothing above the rotors
            speed *= np.where(depth < 0.0, np.exp(-((depth / self.half_width0_m) ** 2)), 1.0)
        return axis, speed, half_width, centre

    def _geometry(self, lead: tuple, follower: BodyState, offsets: np.ndarray) -> dict:
        """The wake at the follower's k disk centres and its body centre (P = k + 1 points, the
        body last): depth, half-width, centreline speed, squared distance from the wake centre
        (P, n) and radial vector (3, P, n)."""
        R = follower.R  # noqa: N806
        k = offsets.shape[0]
        n = R.shape[0]
        rt = np.ascontiguousarray(R.transpose(2, 1, 0))  # rt[j, i] = R[:, i, j], rows of n
        points = self._points
        if points is None or points[0] is not offsets or not is_frozen(offsets):
            cols = np.zeros((k + 1, 3))
            cols[:k] = offsets
            freeze(cols)
            points = (offsets, cols[None, :, 0:1], cols[None, :, 1:2],
                      cols[None, :, 2:3] if offsets[:, 2].any() else None,
                      _torque_arms(offsets))
            self._points = points
        _, px, py, pz, arms = points
        rel = np.multiply(rt[0][:, None, :], px, out=np.empty((3, k + 1, n)))
        rel += rt[1][:, None, :] * py
        if pz is not None:
            rel += rt[2][:, None, :] * pz
        d = np.asarray(follower.p, dtype=float).T - lead[4]
        rel += d[:, None, :]
        depth, half_width, centre, radial = self._depth_terms(lead, rel)
        r2 = radial * radial
        d2 = r2[0] + r2[1]
        d2 += r2[2]
        return {"depth": depth, "half_width": half_width, "centre": centre, "radial": radial,
                "d2": d2, "k": k, "rt": rt, "flat": pz is None, "arms": arms}

    def _axial(self, geo: dict, follower: BodyState, lead: tuple) -> np.ndarray:
        """Mean axial force (N) on each disk and on the body, (P, n) (the body last)."""
        k = geo["k"]
        axis = lead[0]
        prod = np.asarray(follower.v, dtype=float).T * axis
        v_axial = prod[0] + prod[1]
        v_axial += prod[2]
        p = self.ingest_exponent
        depth, centre, d2 = geo["depth"], geo["centre"], geo["d2"]
        b2 = geo["half_width"] * geo["half_width"]
        # Disks: w^p is a Gaussian of variance sig2 = b^2 / (2 p ln2); averaged over a disk of
        # radius a (second moment a^2 / 4 per axis) it is (sig2 / sige2) exp(-d^2 / (2 sige2)).
        # Body: drag (p = 2) averaged over its area: (sig2 / sige2)^(1/2) exp(-d^2 / (4 sige2))
        # with sig2 = b^2 / (4 ln2). Rows: the disks, then the body (per-row constants).
        div, add, scale = self._area_columns(k)
        sig2 = b2 / div
        sige2 = sig2 + add
        ratio = sig2 / sige2
        spread = np.divide(d2, np.multiply(sige2, scale, out=sige2), out=sige2)
        w = np.empty(d2.shape)  # (P, n): the wake speed each disk and the body take in
        log_g = np.log(ratio[:k])
        log_g -= spread[:k]
        log_g /= p
        np.multiply(centre[:k], np.exp(log_g, out=log_g), out=w[:k])
        w_body = np.multiply(centre[k], np.sqrt(ratio[k]), out=w[k])
        w_body *= np.exp(np.negative(spread[k]))
        if _fmin(depth) < 0.0:  # nothing above the rotors (fmin: NaN aside, as depth < 0)
            above = depth < 0.0
            w *= np.where(above, np.exp(-((depth / self.half_width0_m) ** 2)), 1.0)
        axial = _ingest_laws(w, v_axial, p, k)
        axial *= self._force_coeff(follower.mass_kg, k)
        return axial

    def _area_columns(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(k + 1, 1) columns of :meth:`_axial`'s per-row constants (cached): sig2's divisor
        ``2 p ln2`` (the disks) or ``4 ln2`` (the body), the area's second moment ``a^2 / 4``,
        and the exponent's factor 2 or 4."""
        key = (k, self.ingest_exponent, self.follower_disk_radius_m, self.body_radius_m)
        if self._area_key != key:
            p = self.ingest_exponent
            cols = np.empty((3, k + 1, 1))
            cols[0], cols[0, k] = 2.0 * p * _LN2, 4.0 * _LN2
            cols[1], cols[1, k] = 0.25 * self.follower_disk_radius_m ** 2, \
                0.25 * self.body_radius_m ** 2
            cols[2], cols[2, k] = 2.0, 4.0
            freeze(cols)
            self._area_key, self._area_cols = key, tuple(cols)
        return self._area_cols

    def _force_coeff(self, mass_kg: np.ndarray, k: int) -> np.ndarray:
        """(k + 1, n) the force per unit of the ingest law, per disk ``c rho A v_hf^(2 - p)``
        (v_hf: the follower's own hover-induced velocity, from its mass) and for the body
        ``rho C_d A_b / 2``, read-only; kept for the same read-only mass array (a world passes
        the same one every step: its bodies' arrays are read-only) and the same parameters."""
        rho, area, p = self.air_density_kgpm3, self.follower_disk_area_m2, self.ingest_exponent
        params = (k, rho, area, p, self.ingest_coeff, self.gravity_mps2, self.follower_n_rotors,
                  self.body_drag_coeff, self.body_area_m2)
        hit = self._coeff
        if hit is not None and hit[0] is mass_kg and hit[1] == params and is_frozen(mass_kg):
            return hit[2]
        mass = np.asarray(mass_kg, dtype=float)
        coeff = np.empty((k + 1, mass.shape[0]))
        disk = self.ingest_coeff * rho * area
        if p != 2.0:
            disk = disk * (mass * self.gravity_mps2
                           / (2.0 * rho * self.follower_n_rotors * area)) ** (1.0 - 0.5 * p)
        coeff[:k] = disk
        coeff[k] = 0.5 * self.body_drag_coeff * rho * self.body_area_m2
        freeze(coeff)
        self._coeff = (mass_kg, params, coeff)
        return coeff

    def _turbulence_time_and_share(self, geo: dict,
                                   offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) correlation time, s, and the share ``rho`` of each disk's turbulence variance
        that all disks (and the body) have in common."""
        k = geo["k"]
        b_c = geo["half_width"][k]
        tau = self.turb_time_ratio * b_c / np.maximum(geo["centre"][k], 1e-6)
        if offsets is not self._offsets_obj or not is_frozen(offsets):
            key = (offsets.shape, offsets.tobytes())
            if key != self._offsets_key:
                self._offsets_key = key
                self._pair_distance_m = mean_pair_distance_m(offsets)
            self._offsets_obj = offsets
        share = np.exp(-self._pair_distance_m / (self.turb_length_ratio * b_c))
        return tau, share

    def _forces_from(self, geo: dict, lead: tuple, leader: BodyState, follower: BodyState,
                     offsets: np.ndarray, noise: tuple | None, want_torque: bool,
                     split: bool = True,
                     ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """The disks' total force (3, n), their torque about the centre of mass in the body
        frame (n, 3) or None, and the body's force (3, n); not ``split`` (and no torque): the
        whole force (3, n), None, None. ``noise`` = (shared (3, n), each disk's own axial
        (k, n), share (n,)) or None for the mean."""
        k = geo["k"]
        axis = lead[0]
        axial = self._axial(geo, follower, lead)  # (P, n)
        if noise is None:
            along = axial
        else:
            shared, own, share = noise
            # Each disk's axial process: the shared one's sqrt(rho), its own sqrt(1 - rho); the
            # body's is the shared one.
            along = np.empty_like(axial)
            np.multiply(own, np.sqrt(1.0 - share), out=along[:k])
            along[:k] += np.sqrt(share) * shared[0]
            along[k] = shared[0]
            along *= self.turb_vertical
            along += 1.0
            along *= axial
        if self.disk_torque_gain != 1.0 and (split or want_torque):
            # The disks' mean forces' differences from their mean, scaled: a zero-sum change,
            # so the net force (and the turbulence about each disk's mean) is unchanged.
            spread = axial[:k] - axial[:k].mean(axis=0)
            spread *= self.disk_torque_gain - 1.0
            if along is axial:
                along = axial.copy()
            along[:k] += spread
        radial = geo["radial"]  # (3, P, n), overwritten
        planar = None
        if self.planar_ratio:
            # planar_ratio / peak * F * r / r_half along r / |r|, r_half = b / sqrt(p)
            planar = axial * self._planar_scale(k)
            planar /= geo["half_width"]
        gust = None
        if noise is not None and self.turb_lateral:
            # One lateral process pushes every disk and the body: R e1 n_1 + R e2 n_2.
            lateral = _lateral(lead[5], noise[0][1:3])
            gust = np.add(lateral[0], lateral[1], out=lateral[0])
            gust *= self.turb_lateral
        if not split and not want_torque:
            total = axis * along.sum(axis=0)
            if planar is not None:
                radial *= planar
                total += radial.sum(axis=1)
            if gust is not None:
                total += gust * np.abs(axial).sum(axis=0)
            return total, None, None
        if planar is not None:
            radial *= planar
            force = radial
        else:
            force = np.zeros_like(radial)
        force += axis[:, None, :] * along
        if gust is not None:
            force += gust[:, None, :] * np.abs(axial)
        disks = force[:, :k].sum(axis=1)
        body = force[:, k]  # a view: its reader copies it
        if not want_torque:
            return disks, None, body
        # R^T F_k per disk (3, k, n), then sum_k r_k x (R^T F_k).
        rt = geo["rt"]
        # All nine products in one broadcast (3, 3, k, n), then summed over j in order.
        prod = np.multiply(rt[:, :, None, :], force[None, :, :k])
        fb = prod[:, 0]
        fb += prod[:, 1]
        fb += prod[:, 2]
        torque = np.empty((axis.shape[1], 3))
        if geo["flat"]:
            # Per disk (y_k f_z, x_k f_z, x_k f_y - y_k f_x), summed over the disks in order
            # into the torque's columns; the second is minus that sum.
            arms = geo["arms"]  # (4, k, 1): y, x, x, y
            terms = np.empty((3,) + fb.shape[1:])
            np.multiply(arms[0:2], fb[2], out=terms[0:2])
            cross = np.multiply(arms[2:4], fb[1::-1])
            np.subtract(cross[0], cross[1], out=terms[2])
            torque_t = np.add.reduce(terms, axis=1, out=torque.T)
            np.negative(torque_t[1], out=torque_t[1])
            return disks, torque, body
        ox, oy, oz = (offsets[:, c:c + 1] for c in range(3))  # (k, 1)
        torque[:, 0] = (oy * fb[2]).sum(axis=0)
        torque[:, 1] = -(ox * fb[2]).sum(axis=0)
        torque[:, 2] = (ox * fb[1] - oy * fb[0]).sum(axis=0)
        # disks out of the centre of mass's plane
        torque[:, 0] -= (oz * fb[1]).sum(axis=0)
        torque[:, 1] += (oz * fb[0]).sum(axis=0)
        return disks, torque, body

    def _planar_scale(self, k: int) -> np.ndarray:
        """(k + 1, 1) ``planar_ratio / peak * sqrt(p)`` per disk, ``sqrt(2)`` for the body
        (cached: the same for every step of a field's parameters)."""
        key = (k, self.ingest_exponent, self.planar_ratio)
        if self._planar_key != key:
            scale = np.full((k + 1, 1), np.sqrt(self.ingest_exponent))
            scale[k] = np.sqrt(2.0)
            scale *= self.planar_ratio / _PLANAR_PEAK
            self._planar_key, self._planar_scale_col = key, scale
        return self._planar_scale_col

    def _ou_step(self, state: np.ndarray, dt: float, tau: np.ndarray) -> np.ndarray:
        """One Ornstein-Uhlenbeck step of unit-variance states (m, n) with correlation times
        ``tau`` (n,), fresh draws from the trial's random source."""
        decay = np.exp(-dt / tau)
        noise = standard_normal_t(self._rng, state.shape[1], state.shape[0]) \
            * np.sqrt(1.0 - decay * decay)
        noise += decay * state
        return noise


def _ingest_law(w_mps: np.ndarray, v_axial_mps: np.ndarray, p: float,
                out: np.ndarray | None = None) -> np.ndarray:
    """``phi(w - v) - phi(-v)`` with ``phi(x) = sign(x) |x|^p``: the force of wake air of
    speed ``w`` on a disk moving at ``v`` along the axis, less that of its motion in still air
    (the vehicle's own drag). Exactly ``w`` for ``p = 1``. Written into ``out`` if given."""
    if p == 1.0:
        if out is None:
            return np.array(w_mps, dtype=float, copy=True)
        np.copyto(out, w_mps)
        return out
    rel = w_mps - v_axial_mps
    if p == 2.0:
        out = np.multiply(rel, np.abs(rel), out=out)
        out += v_axial_mps * np.abs(v_axial_mps)
        return out
    out = np.abs(rel, out=out)
    np.power(out, p, out=out)
    np.copysign(out, rel, out=out)
    own = np.abs(v_axial_mps)
    np.power(own, p, out=own)
    out += np.copysign(own, v_axial_mps, out=own)
    return out


def _ingest_laws(w_mps: np.ndarray, v_axial_mps: np.ndarray, p: float, k: int) -> np.ndarray:
    """:func:`_ingest_law` on rows ``w_mps`` (k + 1, n): the first k (the disks) with ``p``,
    the last (the body) with 2 (the operations they share done once)."""
    if p == 1.0 or p == 2.0:
        out = np.empty(w_mps.shape)
        _ingest_law(w_mps[:k], v_axial_mps, p, out[:k])
        _ingest_law(w_mps[k], v_axial_mps, 2.0, out[k])
        return out
    rel = w_mps - v_axial_mps
    out = np.abs(rel)
    own = np.abs(v_axial_mps)
    # The body's: rel |rel| + v |v|.
    body = np.multiply(rel[k], out[k], out=out[k])
    body += v_axial_mps * own
    # The disks': sign(rel) |rel|^p + sign(v) |v|^p.
    disks = np.power(out[:k], p, out=out[:k])
    np.copysign(disks, rel[:k], out=disks)
    np.power(own, p, out=own)
    disks += np.copysign(own, v_axial_mps, out=own)
    return out


def _offsets(rotor_offsets_body_m: np.ndarray) -> np.ndarray:
    """The disks' centres as a (k, 3) float array: the array itself when it is one (the
    geometry's caches are keyed by the object when it is read-only)."""
    offsets = rotor_offsets_body_m
    if (isinstance(offsets, np.ndarray) and offsets.dtype == np.float64 and offsets.ndim == 2
            and offsets.shape[1] == 3):
        return offsets
    return np.asarray(offsets, dtype=float).reshape(-1, 3)


def _torque_arms(offsets: np.ndarray) -> np.ndarray:
    """(4, k, 1) the disks' (y, x, x, y): the arms of the flat disks' torque."""
    x, y = offsets[:, 0], offsets[:, 1]
    arms = np.stack([y, x, x, y])[:, :, None]
    freeze(arms)
    return arms


def _lateral(frame: np.ndarray, noise: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """(2, 3, n) ``R e1 (s n_1)`` and ``R e2 (s n_2)`` for the body axes ``frame`` (3, 3, n) of
    :meth:`RoundJetField._leader_wake` and lateral processes ``noise`` (2, n) (``s``: a scale
    (n,), or none), component-major."""
    if scale is not None:
        noise = noise * scale
    return np.multiply(frame[0:2], noise[:, None, :])


def _fmin(values: np.ndarray) -> float:
    """The least element, NaN aside (``fmin``): "any element < x" in one reduction."""
    return np.fmin.reduce(values, axis=None)
