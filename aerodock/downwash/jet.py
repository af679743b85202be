"""The default "truth" downwash: the leader's wake as a momentum-conserving turbulent round jet,
felt on each rotor disk of the follower and on its body.

Physics (DESIGN.md, "Downwash field"; the parameters are fitted to real flights by
``aerodock field fit``, :mod:`aerodock.identify.wake_fit`, and are dimensionless, so one set
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
  gain. The real Crazyflie flights' logged motor torques put the wake's torque at 2.2-4.5 times
  this jet's fitted with it (docs/crazyflie.md, "The wake's torque in the logs"), by no mechanism
  the jet has (its moments about the hubs add 4-13 %: ``aerodock.identify.hub_moments``); the
  default keeps the jet's own, and a world can ask for the logs' to see what it costs.
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
under the leader feels drag of the wake air (:meth:`RoundJetField.bar_force_n`). A physics step's
wrench, body force and bar force are also one compiled call (:meth:`RoundJetField.wake_step`, the
world's way: the same numbers and random draws as the three calls in turn).
"""

from __future__ import annotations

import copy

import numpy as np

from aerodock.downwash import jet_kernel
from aerodock.downwash.base import BodyState
from aerodock.downwash.jet_inputs import (
    NO_DRAWS,
    NO_PROCESSES,
    NO_ROWS,
    leader_arrays,
    mean_pair_distance_m,
    offsets_array,
    rows3,
)
from aerodock.downwash.wrench import quad_rotor_offsets_body_m
from aerodock.frozen import freeze, is_frozen
from aerodock.jit import NUMPY_LOOPS
from aerodock.rng import standard_normal_t

_LN2 = float(np.log(2.0))
# max over x of x * exp(-ln2 x^2): the planar profile's peak, used to normalise planar_ratio.
_PLANAR_PEAK = float(np.sqrt(1.0 / (2.0 * _LN2)) * np.exp(-0.5))
CONTRACTED_WIDTH0_RATIO = float(np.sqrt(_LN2))
"""``b0 / R_eq`` of momentum theory's fully contracted wake (area ``A/2`` moving at ``2 v_h``)."""
_SHARED_ROWS = 3  # the follower's shared processes: axial, lateral 1, lateral 2
# What RoundJetField.wake_step stands for: it gives way (None) when any of them is not the jet's
# own (RoundJetField._parts_are_the_jets).
_WAKE_STEP_PARTS = ("wrench", "body_force_n", "bar_force_n", "_run")


def centreline_speed_mps(thrust_n: np.ndarray, half_width_m: np.ndarray,
                         air_density_kgpm3: float) -> np.ndarray:
    """Centreline speed of a Gaussian jet of half-velocity width ``half_width_m`` whose momentum
    flux equals ``thrust_n``: ``sqrt(2 ln2 T / (rho pi)) / b``, m/s."""
    thrust = np.maximum(np.asarray(thrust_n, dtype=float), 0.0)
    return np.sqrt(2.0 * _LN2 * thrust / (air_density_kgpm3 * np.pi)) / half_width_m


class RoundJetField:
    """Physically grounded default downwash field (see the module docstring).

    Every parameter is required: their defaults live in one place, ``[downwash.params]`` and
    the vehicles of ``aerodock/config/defaults.toml``, and reach the jet through
    :func:`aerodock.downwash.build_field` (or :func:`aerodock.downwash.field_kwargs`).

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
        *,
        width0_ratio: float,
        spread_rate: float,
        ingest_coeff: float,
        ingest_exponent: float,
        planar_ratio: float,
        body_area_ratio: float,
        body_drag_coeff: float,
        disk_torque_gain: float,
        turb_vertical: float,
        turb_lateral: float,
        turb_length_ratio: float,
        turb_time_ratio: float,
        bar_drag_coeff: float,
        bar_turb_vertical: float,
        bar_turb_lateral: float,
        leader_rotor_radius_m: float,
        leader_n_rotors: int,
        follower_rotor_radius_m: float,
        follower_n_rotors: int,
        follower_diagonal_m: float,
        air_density_kgpm3: float,
        gravity_mps2: float,
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
        self._pair_distance_m = 0.0
        # Turbulence states, component-major: the follower's shared processes (3, n: axial, and
        # the two lateral ones), each disk's own axial one (k, n), and the bar's (3, n).
        self._common = np.zeros((_SHARED_ROWS, 0))
        self._own = np.zeros((0, 0))
        self._processes = np.zeros((_SHARED_ROWS, 0))  # both, stacked; the two are its views
        # The last read-only offsets array the pair distance was computed for, and its points
        # (see _geometry): offsets that can be written in place are compared by value.
        self._offsets_obj: np.ndarray | None = None
        self._jp: tuple | None = None  # the kernels' parameters and what they were made of
        self._bar_noise = np.zeros((3, 0))
        self._rng: np.random.Generator = np.random.default_rng(0)
        self._last_dt: float | None = None
        # The body's force of the last turbulent step, for body_force_n() of the same step.
        self._body_key: tuple | None = None
        self._body_force: np.ndarray | None = None
        # The force coefficients of the last read-only follower mass array (see _force_coeff),
        # and the per-row constants of _axial (see _area_columns).
        self._coeff: tuple | None = None
        self._area_key: tuple | None = None
        self._area_cols = np.zeros((4, 0))

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
        self._body_key = self._body_force = None

    def take_rows(self, rows: np.ndarray, rng: np.random.Generator) -> RoundJetField:
        """The field of the trials at ``rows``, their turbulence where it stands, drawing from
        ``rng`` (:class:`~aerodock.downwash.base.SupportsTakeRows`)."""
        out = copy.copy(self)  # the parameters and the geometry caches are shared
        out._rng = rng
        out._set_processes(self._processes[:, rows])
        out._coeff = None  # of the whole batch's masses (keyed by that array: never these rows')
        out.__dict__.pop("_leader_hit", None)  # the whole batch's leader, not these rows'
        out._bar_noise = self._bar_noise[:, rows]
        # Kept for the rest of one physics step only (keyed by the step's objects).
        out._body_key = out._body_force = None
        return out

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) acceleration on the follower (its disks and its body), m/s², NED; advances the
        turbulence by ``dt``."""
        out = self._run(leader, follower, self.rotor_offsets_body_m, dt, advance=True,
                        noisy=True, split=False, want_torque=False)
        self._body_key = self._body_force = None
        total = out[0]
        total /= np.asarray(follower.mass_kg, dtype=float)[:, None]
        return total

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
        offsets = offsets_array(rotor_offsets_body_m)
        force, torque, body, _ = self._run(leader, follower, offsets, dt, advance=True,
                                           noisy=True, split=True, want_torque=True)
        self._body_key, self._body_force = (leader, follower), body
        return force, torque

    def body_force_n(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) the wake's drag on the follower's body, N, NED, at its centre of mass, with the
        turbulence of this step's :meth:`wrench` (or :meth:`acceleration`) call; does not
        advance time."""
        if self._body_key is not None and self._body_key[0] is leader \
                and self._body_key[1] is follower and self._body_force is not None:
            return self._body_force.copy()
        _, _, body, _ = self._run(leader, follower, self.rotor_offsets_body_m, 0.0,
                                  advance=False, noisy=True, split=True, want_torque=False)
        return body

    # -- extras used by the simulator, the oracle, `field probe` and `field fit` --------------
    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean (turbulence-free) acceleration on the follower, m/s², NED."""
        total = self._run(leader, follower, self.rotor_offsets_body_m, 0.0, advance=False,
                          noisy=False, split=False, want_torque=False)[0]
        total /= np.asarray(follower.mass_kg, dtype=float)[:, None]
        return total

    def mean_disk_torque_nm(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean (turbulence-free) torque of the wake on the follower's rotor disks about
        its centre of mass, N·m, body frame (FRD)."""
        return self._run(leader, follower, self.rotor_offsets_body_m, 0.0, advance=False,
                         noisy=False, split=True, want_torque=True)[1]

    def mean_disk_forces_n(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(k, n) mean (turbulence-free) axial force on each of the follower's rotor disks, N,
        along the wake's axis (the leader's body z; positive: a loss of thrust), before
        ``disk_torque_gain`` (with the gain 1, at the hubs they are :meth:`mean_disk_torque_nm`)."""
        offsets = self.rotor_offsets_body_m
        axial = self._run(leader, follower, offsets, 0.0, advance=False, noisy=False,
                          split=True, want_torque=False)[3][0]
        return axial[:offsets.shape[0]].copy()

    def turbulence(self, leader: BodyState, follower: BodyState) -> dict[str, np.ndarray]:
        """The turbulence at the follower, per trial (n,): ``corr_time_s``, the processes'
        correlation time; ``disk_share``, the share of a disk's turbulence all disks have in
        common; ``axial_var_mps4`` and ``lateral_var_mps4``, the variance of the whole
        follower's acceleration along the wake's axis and across it (per direction), m²/s⁴."""
        offsets = self.rotor_offsets_body_m
        k = offsets.shape[0]
        _, _, _, (axial, tau, share) = self._run(leader, follower, offsets, 0.0,
                                                 advance=False, noisy=False, split=True,
                                                 want_torque=False)
        f_disk, f_body = axial[:k], axial[k]
        mass = np.asarray(follower.mass_kg, dtype=float)
        root = np.sqrt(share)
        # sum_k F_k (sqrt(rho) c + sqrt(1 - rho) e_k) + F_b c, unit independent c, e_k
        shared = root * f_disk.sum(axis=0) + f_body
        variance = (shared * shared + (1.0 - share) * (f_disk * f_disk).sum(axis=0)) \
            / (mass * mass)
        total = np.abs(f_disk).sum(axis=0) + np.abs(f_body)  # one lateral process for all
        lateral = (self.turb_lateral * total / mass) ** 2
        return {"corr_time_s": tau, "disk_share": share,
                "axial_var_mps4": self.turb_vertical ** 2 * variance,
                "lateral_var_mps4": lateral}

    def wind_mps(self, leader: BodyState, points_m: np.ndarray) -> np.ndarray:
        """(n, 3) mean wake air velocity at ``points_m`` (n, 3), NED (used for the bar's drag)."""
        axis, speed, _, _ = self._point_wake(leader, points_m)
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
        n = leader.n
        noise, draws, step, advance = self._bar_draws(
            n, dt if dt is not None else self._last_dt)
        out = np.empty((n, 3))
        lr, lt, lv, lp = self._leader_arrays(leader)
        jet_kernel.bar_force(
            NUMPY_LOOPS, self._jet_params(), lr, lt, lv, lp, rows3(bar_p_m), rows3(bar_v_mps),
            NO_ROWS if bar_axis is None else rows3(bar_axis), bar_axis is not None, noise,
            draws, step, advance, self._bar_params(bar_area_m2), out)
        self._bar_noise = noise
        return out

    def wake_step(self, leader: BodyState, follower: BodyState,
                  rotor_offsets_body_m: np.ndarray, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                  bar_area_m2: float, dt: float, bar_axis: np.ndarray | None = None,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """One physics step's wake in one compiled call (:func:`jet_kernel.wake_step`): the
        numbers, random draws and turbulence of ``wrench(leader, follower,
        rotor_offsets_body_m, dt)``, then ``body_force_n(leader, follower)``, then
        ``bar_force_n(leader, bar_p_m, bar_v_mps, bar_area_m2, dt, bar_axis)``, bit for bit
        (``tests/unit/test_fused_wake.py``). Both turbulences are drawn before the kernel, the
        follower's first, as the three calls draw them; afterwards :meth:`body_force_n` of the
        same states gives this step's body force, as after :meth:`wrench`.

        Returns:
            ``(force_n, torque_nm, body_force_n, bar_force_n)``, each (n, 3): the disks' force,
            N, world NED; their torque about the centre of mass, N·m, body FRD; the body's
            force and the bar's, N, NED (views of one array, made for this call; the body's is
            the one :meth:`body_force_n` copies for the rest of the step: read, not written).
            None, drawing nothing, when one of the parts it stands for is not the jet's own (a
            subclass, a mixin or the instance replaced ``wrench``, ``body_force_n``,
            ``bar_force_n`` or ``_run``, or set one to None): the world then calls the parts.
        """
        if not self._parts_are_the_jets():
            return None
        offsets = offsets_array(rotor_offsets_body_m)
        n, k = leader.n, offsets.shape[0]
        draws = self._follower_draws(n, k, noisy=True, advance=True)  # as wrench's _run
        self._pair_distance(offsets)
        bar_noise, bar_draws, bar_dt, bar_advance = self._bar_draws(n, dt)  # as bar_force_n
        out = np.empty((4, n, 3))
        lr, lt, lv, lp = self._leader_arrays(leader)
        jet_kernel.wake_step(
            NUMPY_LOOPS, self._jet_params(), self._columns(k), offsets, lr, lt, lv, lp,
            np.asarray(follower.R, dtype=float), rows3(follower.p), rows3(follower.v),
            self._force_coeff(follower.mass_kg, k), self._processes, draws, float(dt),
            rows3(bar_p_m), rows3(bar_v_mps),
            NO_ROWS if bar_axis is None else rows3(bar_axis), bar_axis is not None, bar_noise,
            bar_draws, bar_dt, bar_advance, self._bar_params(bar_area_m2), out)
        self._last_dt = dt
        self._bar_noise = bar_noise
        force, torque, body, bar = out
        self._body_key, self._body_force = (leader, follower), body  # body_force_n copies it
        return force, torque, body, bar

    def _parts_are_the_jets(self) -> bool:
        """Whether the parts :meth:`wake_step` stands for are this class's own, as the field
        finds them now (its class's, however inherited, and none set on the instance)."""
        cls, own = type(self), vars(self)
        return all(getattr(cls, name, None) is getattr(RoundJetField, name)
                   and name not in own for name in _WAKE_STEP_PARTS)

    def _leader_arrays(self, leader: BodyState) -> tuple[np.ndarray, ...]:
        """:func:`~aerodock.downwash.jet_inputs.leader_arrays` of ``leader``, kept for the last
        :class:`BodyState` object (the follower's wrench and the bar's drag read the same leader
        in one physics step). A ``BodyState`` is frozen, so the same object holds the same
        arrays, and the kernels read their numbers when called, as before; other leader types
        are converted every call."""
        hit = self.__dict__.get("_leader_hit")
        if hit is not None and hit[0] is leader:
            return hit[1]
        arrays = leader_arrays(leader)
        if type(leader) is BodyState:
            self.__dict__["_leader_hit"] = (leader, arrays)
        return arrays

    def _bar_params(self, bar_area_m2: float) -> np.ndarray:
        """The bar kernel's three float parameters, cached for the field's current values and
        ``bar_area_m2`` (the same numbers as computing them afresh: the same expressions; the
        kernel only reads them, and the array stays writable, the type it was compiled for)."""
        key = (self.bar_turb_vertical, self.bar_turb_lateral, self.air_density_kgpm3,
               self.bar_drag_coeff, bar_area_m2)
        hit = self.__dict__.get("_bar_params_hit")
        if hit is not None and hit[0] == key:
            return hit[1]
        values = np.array([0.5 * self.bar_turb_vertical, self.bar_turb_lateral,
                           0.5 * self.air_density_kgpm3 * self.bar_drag_coeff * bar_area_m2])
        self.__dict__["_bar_params_hit"] = (key, values)
        return values

    # -- internals -----------------------------------------------------------------------------
    def _follower_draws(self, n: int, k: int, noisy: bool, advance: bool) -> np.ndarray:
        """This step's draws for the follower's turbulence, (3 + k, n) (none unless
        ``advance``), after starting the processes afresh for a new batch shape when ``noisy``;
        the processes left contiguous for the kernel to advance in place."""
        if noisy and (self._common.shape[1] != n or self._own.shape[0] != k):
            self._draw_follower_noise(n, k)
        draws = standard_normal_t(self._rng, n, _SHARED_ROWS + k) if advance else NO_DRAWS
        if advance and not self._processes.flags.c_contiguous:
            self._set_processes(np.array(self._processes, order="C"))
        return draws

    def _bar_draws(self, n: int, dt: float | None,
                   ) -> tuple[np.ndarray, np.ndarray, float, bool]:
        """The bar's turbulence for a step of ``dt`` (None or 0: no step): (its state, a copy
        the kernel advances in place (3, n); this step's draws; the step, s, 0 without one;
        whether it advances), after starting it afresh for a new batch size."""
        if self._bar_noise.shape[1] != n:
            self._bar_noise = standard_normal_t(self._rng, n, 3)
        advance = dt is not None and dt > 0
        draws = standard_normal_t(self._rng, n, 3) if advance else NO_DRAWS
        return (np.array(self._bar_noise, order="C"), draws, float(dt) if advance else 0.0,
                advance)

    def _draw_follower_noise(self, n: int, k: int) -> None:
        draw = standard_normal_t(self._rng, n, _SHARED_ROWS + k)
        self._set_processes(np.array(draw, order="C"))

    def _set_processes(self, processes: np.ndarray) -> None:
        """The follower's turbulence states, (3 + k, n): the shared ones, then each disk's own
        (one array: a step advances them in one operation each)."""
        self._processes = processes
        self._common, self._own = processes[:_SHARED_ROWS], processes[_SHARED_ROWS:]

    def _jet_params(self) -> np.ndarray:
        """The kernels' float parameters (``jet_kernel.JP_*``), read-only, cached for the
        field's current values."""
        values = (self.half_width0_m, self.spread_rate, self.ingest_exponent,
                  2.0 * _LN2 / (self.air_density_kgpm3 * np.pi), self.turb_time_ratio,
                  self.turb_length_ratio, self._pair_distance_m, self.turb_vertical,
                  self.turb_lateral, self.disk_torque_gain, self.planar_ratio, _LN2)
        hit = self._jp
        if hit is not None and hit[0] == values:
            return hit[1]
        jp = np.array(values, dtype=float)
        freeze(jp)
        self._jp = (values, jp)
        return jp

    def _run(self, leader: BodyState, follower: BodyState, offsets: np.ndarray, dt: float,
             advance: bool, noisy: bool, split: bool, want_torque: bool,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple]:
        """The compiled forces (:func:`jet_kernel.jet_forces`): (the disks' force, or the
        whole force when not ``split``, (n, 3); their torque (n, 3); the body's force (n, 3);
        (the mean axial force per point (k + 1, n), the correlation time and the disks'
        shared variance (n,)))."""
        n, k = leader.n, offsets.shape[0]
        draws = self._follower_draws(n, k, noisy, advance)
        self._pair_distance(offsets)
        force, torque, body = np.empty((n, 3)), np.zeros((n, 3)), np.empty((n, 3))
        axial, tau, share = np.empty((k + 1, n)), np.empty(n), np.empty(n)
        lr, lt, lv, lp = self._leader_arrays(leader)
        jet_kernel.jet_forces(
            NUMPY_LOOPS, self._jet_params(), self._columns(k), offsets, lr, lt, lv, lp,
            np.asarray(follower.R, dtype=float), rows3(follower.p), rows3(follower.v),
            self._force_coeff(follower.mass_kg, k),
            self._processes if noisy else NO_PROCESSES, draws, float(dt), advance, noisy,
            split, want_torque, force, torque, body, axial, tau, share)
        if advance:
            self._last_dt = dt
        return force, torque, body, (axial, tau, share)

    def _point_wake(self, leader: BodyState, points_m: np.ndarray):
        """Axis (3, n), and the local axial air speed, half-width and centreline speed (n,) at
        ``points_m`` (n, 3) (a point: no averaging over an area)."""
        n = leader.n
        axis, speed, half_width, centre = np.empty((3, n)), np.empty(n), np.empty(n), \
            np.empty(n)
        lr, lt, lv, lp = self._leader_arrays(leader)
        jet_kernel.point_wake(NUMPY_LOOPS, self._jet_params(), lr, lt, lv, lp,
                              rows3(points_m), axis, speed, half_width, centre)
        return axis, speed, half_width, centre

    def _columns(self, k: int) -> np.ndarray:
        """(4, k + 1) the kernels' per-point constants (``jet_kernel.COL_*``): sig2's divisor
        ``2 p ln2`` (the disks) or ``4 ln2`` (the body), the area's second moment ``a^2 / 4``,
        the exponent's factor 2 or 4, and ``planar_ratio / peak * sqrt(p)`` per disk,
        ``sqrt(2)`` for the body (cached)."""
        key = (k, self.ingest_exponent, self.follower_disk_radius_m, self.body_radius_m,
               self.planar_ratio)
        if self._area_key != key:
            p = self.ingest_exponent
            cols = np.empty((4, k + 1))
            cols[0], cols[0, k] = 2.0 * p * _LN2, 4.0 * _LN2
            cols[1], cols[1, k] = 0.25 * self.follower_disk_radius_m ** 2, \
                0.25 * self.body_radius_m ** 2
            cols[2], cols[2, k] = 2.0, 4.0
            cols[3], cols[3, k] = np.sqrt(p), np.sqrt(2.0)
            cols[3] *= self.planar_ratio / _PLANAR_PEAK
            freeze(cols)
            self._area_key, self._area_cols = key, cols
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

    def _pair_distance(self, offsets: np.ndarray) -> None:
        """The disks' mean spacing for ``offsets`` (kept for the last read-only array; others
        are looked up by value, :func:`mean_pair_distance_m`)."""
        if offsets is not self._offsets_obj or not is_frozen(offsets):
            self._pair_distance_m = mean_pair_distance_m(offsets)
            self._offsets_obj = offsets
