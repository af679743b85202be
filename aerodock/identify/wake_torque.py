"""The wake's torque on the follower, read from real flights, beside the jet's.

A fit of the wake (:mod:`aerodock.identify.wake_fit`) sees the follower's acceleration only.
Flights whose logs carry the motors' torque (``follower_motor_torque_nm``, N·m, body FRD: the
Neural-Swarm logs' own mixer of the per-motor thrusts the firmware asked for, its commanded torque;
:mod:`aerodock.identify.motor_commands` gives the torque of the commands as sent) and the body rates
(``follower_body_rates_radps``) also give the wake's torque, from Euler's equation:

    tau_wake = J dw/dt + w x J w - (tau_motors - tau_free)

``tau_free`` is the follower's median motor torque in free air in the same flight (its trim: a
centre of mass off the middle, motors that differ); ``dw/dt`` is the logged rates' central
difference. The part that matters is the *inward* torque, the one that pushes the follower's
disks nearer the leader's axis down (its component along ``-(e_r x e_z)``, ``e_r`` the horizontal
unit vector from the axis to the follower): the jet's torque at the wake's edge, the paper's
oscillatory behaviour. Binned by the horizontal offset, it is set beside the jet's mean torque at
the same logged states (:func:`torque_profile`).

What the logged torque stands on: the per-motor thrusts are the ones the firmware asked for, and
each motor's command (PWM, 0..1) follows from them and the battery's voltage by a still-air map,
up to the top of the commands' range, where the command stops short of the thrust asked for
(:mod:`aerodock.identify.motor_commands`). Where the motors nearest the axis run near
their ceiling (``follower_motor_pwm``, 0..1), that map is least certain and the follower is at
the limit of its roll authority; the profile reports those motors' median command per bin.
:func:`thrust_map_slope` checks the map's slope in free air against the accelerometer (the
torque labels scale with it), and :func:`force_profile` reads the force beside the torque out
beyond the jet's edge, below the other vehicle and, as a control, above it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from aerodock.downwash.jet import quad_rotor_offsets_body_m
from aerodock.flightlog import FlightLog
from aerodock.geometry import GRAVITY_MPS2, quat_to_rotmat
from aerodock.identify.flights import FlightSamples, WakeFitError, log_geometry, pair_name
from aerodock.identify.hub_moments import hub_moments_nm
from aerodock.identify.wake_fit import build_jet, geometry_with
from aerodock.learning.labels import free_air_mask, raw_labels, valid_mask

MOTOR_TORQUE_KEY = "follower_motor_torque_nm"
BODY_RATES_KEY = "follower_body_rates_radps"
MOTOR_PWM_KEY = "follower_motor_pwm"
# Free air for the trim: farther than this to the side of the leader, or above it, m.
FREE_AIR_OFFSET_M = 0.4
MIN_FREE_SAMPLES = 50
MIN_BIN_SAMPLES = 20
RADIAL_SPEED_MPS = 0.1  # moving towards or away from the axis: faster than this along e_r


@dataclass(frozen=True)
class TorqueBin:
    """One bin of horizontal offset from the leader's axis: the inward torque, N·m."""

    offset_lo_m: float
    offset_hi_m: float
    samples: int
    real_nm: float
    real_se_nm: float
    jet_nm: float
    ratio: float
    real_down_force_n: float
    """The real wake's mean downward force on the follower (its de-biased label times its
    mass), N."""
    half_diagonal_m: float
    """The follower's motors' distance from its centre, m."""
    lean_in_deg: float
    """The real follower's mean lean towards the axis (its body z axis's tilt, signed)."""
    near_motor_pwm: float | None
    """Median command (0..1) of the motor nearest the axis, when the log has it."""
    real_moving_in_nm: float = float("nan")
    real_moving_out_nm: float = float("nan")
    """The real inward torque over the samples where the follower moves towards / away from
    the axis (its own horizontal velocity along ``e_r`` beyond ``RADIAL_SPEED_MPS``; nan: fewer
    than ``MIN_BIN_SAMPLES``): a torque of the follower's own motion through the air (blade
    flapping, rotor drag) changes sign between them, the wake's does not."""
    hub_nm: float = float("nan")
    """The jet's inward hub moments (:func:`aerodock.identify.hub_moments.hub_moments_nm`: its
    axial load spread over each disk, which ``jet_nm`` puts at the hubs), N·m; nan: not asked
    for."""
    rotor_radius_m: float = float("nan")
    """The follower's rotor radius, m (the lever's bound with ``half_diagonal_m``)."""

    @property
    def lever_m(self) -> float:
        """The inward torque over the downward force: where the force would have to act to make
        the torque. A loss of thrust on the disks alone puts it at most ``half_diagonal_m``
        from the centre if each disk's force acts at its hub, at most :attr:`lever_bound_m`
        however it is spread over the disks; beyond that the disks away from the axis must gain
        thrust."""
        force = self.real_down_force_n
        return float(self.real_nm / force) if abs(force) > 1e-12 else float("nan")

    @property
    def lever_bound_m(self) -> float:
        """The farthest a downward load on the disks can act from the centre: the half
        diagonal plus the rotor radius, m."""
        return self.half_diagonal_m + self.rotor_radius_m

    @property
    def nm_per_rad(self) -> float:
        """The real inward torque over the real lean into the axis: how stiffly the real
        follower's attitude loop holds it (an apparent figure: the lean is the position
        loop's too), N·m per radian."""
        lean = np.radians(self.lean_in_deg)
        return float(self.real_nm / lean) if abs(lean) > 1e-9 else float("nan")


def motor_command_range(logs: Sequence[FlightLog]) -> dict[str, dict[str, float]]:
    """Per follower vehicle id, its motor commands (0..1) over every flight that logs them:
    ``free_air_median`` (all motors, in free air: hover and the manoeuvres) and ``p99`` (all
    samples: the top of the range the flights use)."""
    free: dict[str, list[np.ndarray]] = {}
    every: dict[str, list[np.ndarray]] = {}
    for log in logs:
        if MOTOR_PWM_KEY not in log.extra:
            continue
        vid = str(log.meta.get("follower_id"))
        pwm = np.asarray(log.extra[MOTOR_PWM_KEY], dtype=float)
        far = free_air_mask(log, FREE_AIR_OFFSET_M)
        free.setdefault(vid, []).append(pwm[far].ravel())
        every.setdefault(vid, []).append(pwm.ravel())
    return {vid: {"free_air_median": float(np.median(np.concatenate(free[vid]))),
                  "p99": float(np.percentile(np.concatenate(every[vid]), 99.0))}
            for vid in sorted(every)}


def free_air_map_check(logs: Sequence[FlightLog],
                       bands: Sequence[tuple[float, float]] = ((0.0, 0.75), (0.75, 0.85),
                                                               (0.85, 0.9), (0.9, 1.0)),
                       ) -> dict[str, list[dict[str, float]]]:
    """Does the logs' thrust map hold at the top of its range? Per follower vehicle id and band
    of its highest motor's command, in free air: the samples and the mean vertical residual
    ``a_obs - (g e3 - R e3 T/m)`` (each flight's free-air median taken away), m/s², down
    positive. A map that gave a motor near its ceiling more thrust than it makes would show as
    a residual growing with the band."""
    per: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for log in logs:
        if MOTOR_PWM_KEY not in log.extra:
            continue
        far = free_air_mask(log, FREE_AIR_OFFSET_M)
        if far.sum() < MIN_FREE_SAMPLES:
            continue
        vertical = raw_labels(log)[:, 2]
        vertical = vertical - np.median(vertical[far])
        top = np.asarray(log.extra[MOTOR_PWM_KEY], dtype=float).max(axis=1)
        per.setdefault(str(log.meta.get("follower_id")), []).append((top[far], vertical[far]))
    out: dict[str, list[dict[str, float]]] = {}
    for vid in sorted(per):
        top, vertical = (np.concatenate(c) for c in zip(*per[vid]))
        rows = []
        for lo, hi in bands:
            m = (top >= lo) & (top < hi)
            rows.append({"pwm_lo": float(lo), "pwm_hi": float(hi), "samples": int(m.sum()),
                         "vertical_residual_mps2": (float(vertical[m].mean()) if m.any()
                                                    else float("nan"))})
        out[vid] = rows
    return out


def has_motor_torque(log: FlightLog) -> bool:
    """True when ``log`` carries the motor torque and the body rates this module reads."""
    return MOTOR_TORQUE_KEY in log.extra and BODY_RATES_KEY in log.extra


def real_wake_torque_nm(log: FlightLog, inertia_kgm2: Sequence[float], *,
                        free_air_offset_m: float = FREE_AIR_OFFSET_M) -> np.ndarray | None:
    """(T, 3) the wake's torque on the follower in its body frame (FRD), N·m, from Euler's
    equation (module docstring), or None when the flight has fewer than
    ``MIN_FREE_SAMPLES`` samples in free air (farther than ``free_air_offset_m`` to the side or
    above: no trim to take away).

    Raises:
        WakeFitError: the log has no motor torque or body rates.
    """
    if not has_motor_torque(log):
        raise WakeFitError(f"{log.name}: the log has no {MOTOR_TORQUE_KEY} and "
                           f"{BODY_RATES_KEY} (Neural-Swarm logs carry both)")
    inertia = np.asarray(inertia_kgm2, dtype=float)
    motors = np.asarray(log.extra[MOTOR_TORQUE_KEY], dtype=float)
    rates = np.asarray(log.extra[BODY_RATES_KEY], dtype=float)
    free = free_air_mask(log, free_air_offset_m)
    if free.sum() < MIN_FREE_SAMPLES or log.n_samples < 3:
        return None
    trim = np.median(motors[free], axis=0)
    rate_dot = np.gradient(rates, log.t_s, axis=0)
    return inertia * rate_dot + np.cross(rates, inertia * rates) - (motors - trim)


def inward_nm(torque_world: np.ndarray, e_r: np.ndarray) -> np.ndarray:
    """The torque's component that pushes the disks nearer the axis down: ``-(tau . (e_r x
    e_z))`` in NED, ``e_r x e_z = (e_ry, -e_rx, 0)``."""
    return -(torque_world[:, 0] * e_r[:, 1] - torque_world[:, 1] * e_r[:, 0])


def torque_profile(params: dict[str, float], flights: Sequence[FlightSamples],
                   logs: Sequence[FlightLog], inertia_kgm2: dict[str, Sequence[float]], *,
                   rotor_radii_m: dict[str, float] | None = None,
                   separation_m: tuple[float, float] = (0.15, 0.45),
                   bin_m: float = 0.02, max_offset_m: float = 0.16,
                   free_air_offset_m: float = FREE_AIR_OFFSET_M, hub_moments: bool = False,
                   hub_exponent: float | None = None) -> dict[str, list[TorqueBin]]:
    """Per pairing (``FlightSamples.pair``), the inward wake torque against the horizontal
    offset from the leader's axis: the real flights' (module docstring) and the jet's with
    ``params`` at the same logged states, over the samples ``separation_m`` below the leader;
    with ``hub_moments``, also the jet's moments about the hubs
    (:func:`aerodock.identify.hub_moments.hub_moments_nm`, its load's exponent
    ``hub_exponent``: None, the jet's own).

    Args:
        params: the jet's fitted parameters (:data:`wake_fit.FITTED_PARAMS` keys).
        flights: the fit's samples (:func:`wake_fit.prepare_flights`) of ``logs``.
        logs: the FlightLogs (matched to ``flights`` by name); those without the motor torque
            or without free air are left out.
        inertia_kgm2: the follower's principal moments of inertia by vehicle id.
        rotor_radii_m: rotor radii by vehicle id overriding the logs' (as the fit's).
        free_air_offset_m: where free air starts, for the trim (:func:`real_wake_torque_nm`).

    Raises:
        WakeFitError: no flight with the motor torque, or a follower without an inertia.
    """
    samples = _inward_samples(params, flights, logs, inertia_kgm2, rotor_radii_m or {},
                              free_air_offset_m, hub_moments, hub_exponent)
    out: dict[str, list[TorqueBin]] = {}
    for pair, x in samples.items():
        horizontal, sep, real, model, lean, pwm, down, half, radial_v, hub, radius = (
            x[k] for k in ("horizontal", "separation", "real", "model", "lean", "near_pwm",
                           "down", "half", "radial_v", "hub", "radius"))
        below = (sep >= separation_m[0]) & (sep <= separation_m[1])
        bins = []
        for lo in np.arange(0.0, max_offset_m - 1e-9, bin_m):
            m = below & (horizontal >= lo) & (horizontal < lo + bin_m)
            n = int(m.sum())
            if n < MIN_BIN_SAMPLES:
                continue
            jet_nm = float(model[m].mean())
            real_nm = float(real[m].mean())
            bins.append(TorqueBin(
                offset_lo_m=float(lo), offset_hi_m=float(lo + bin_m), samples=n,
                real_nm=real_nm, real_se_nm=float(real[m].std() / np.sqrt(n)), jet_nm=jet_nm,
                ratio=real_nm / jet_nm if abs(jet_nm) > 1e-12 else float("nan"),
                real_down_force_n=float(down[m].mean()),
                half_diagonal_m=float(half[m].mean()), lean_in_deg=float(lean[m].mean()),
                near_motor_pwm=(float(np.nanmedian(pwm[m])) if np.isfinite(pwm[m]).any()
                                else None),
                real_moving_in_nm=_mean_if_enough(real[m & (radial_v < -RADIAL_SPEED_MPS)]),
                real_moving_out_nm=_mean_if_enough(real[m & (radial_v > RADIAL_SPEED_MPS)]),
                hub_nm=float(hub[m].mean()), rotor_radius_m=float(radius[m].mean())))
        out[pair] = bins
    return out


def _inward_samples(params: dict[str, float], flights: Sequence[FlightSamples],
                    logs: Sequence[FlightLog], inertia_kgm2: dict[str, Sequence[float]],
                    rotor_radii_m: dict[str, float], free_air_offset_m: float,
                    hub_moments: bool = False, hub_exponent: float | None = None,
                    ) -> dict[str, dict[str, np.ndarray]]:
    """Per pairing, every fitted sample of the flights that carry the motor torque: the
    horizontal offset and separation, the real and the jet's inward torque, the lean into the
    axis, the command of the motor nearest it (nan: not logged), the real downward force, the
    half diagonal and rotor radius, the follower's own radial speed, the angle (deg, 0-45 on a
    quad) between the line to the axis and its nearest motor arm, in the body's plane, and the
    jet's inward hub moments (nan unless ``hub_moments``).

    Raises:
        WakeFitError: no flight with the motor torque, or a follower without an inertia.
    """
    by_name = {log.name: log for log in logs}
    parts: dict[str, list[dict[str, np.ndarray]]] = {}
    for flight in flights:
        log = by_name.get(flight.name)
        if log is None or not has_motor_torque(log):
            continue
        vehicle = flight.vehicles.get("follower")
        if vehicle not in inertia_kgm2:
            raise WakeFitError(f"{flight.name}: no inertia for the follower {vehicle!r}")
        real_body = real_wake_torque_nm(log, inertia_kgm2[vehicle],
                                        free_air_offset_m=free_air_offset_m)
        if real_body is None:
            continue
        i = flight.index
        rot = quat_to_rotmat(log.follower_quat[i])
        geometry = geometry_with(flight, rotor_radii_m)
        jet = build_jet(params, geometry)
        jet_body = jet.mean_disk_torque_nm(flight.leader, flight.follower)
        hub_body = (hub_moments_nm(jet, flight.leader, flight.follower, exponent=hub_exponent)
                    if hub_moments else np.full((i.size, 3), np.nan))
        dp = flight.follower.p - flight.leader.p
        horizontal = np.hypot(dp[:, 0], dp[:, 1])
        e_r = dp[:, :2] / np.maximum(horizontal, 1e-9)[:, None]
        # The lean towards the axis: the thrust axis (-body z) tipped towards -e_r.
        up = -rot[:, :, 2]
        lean = np.degrees(np.arcsin(np.clip(-(up[:, 0] * e_r[:, 0] + up[:, 1] * e_r[:, 1]),
                                            -1.0, 1.0)))
        offsets = quad_rotor_offsets_body_m(geometry["follower_diagonal_m"], 4)
        near_pwm = np.full(i.size, np.nan)
        if MOTOR_PWM_KEY in log.extra:
            motors = flight.follower.p[:, None, :2] + np.einsum(
                "nij,kj->nki", rot, offsets)[:, :, :2]
            nearest = np.argmin(np.linalg.norm(motors - flight.leader.p[:, None, :2], axis=2),
                                axis=1)
            near_pwm = np.asarray(log.extra[MOTOR_PWM_KEY], dtype=float)[
                i, _LOG_MOTOR_ORDER[nearest]]
        # the line to the axis (-e_r) in the body's plane against the motor arms
        to_axis = np.einsum("nji,nj->ni", rot[:, :2, :], -e_r)[:, :2]
        arms = offsets[:, :2] / np.linalg.norm(offsets[:, :2], axis=1, keepdims=True)
        cos = (to_axis @ arms.T) / np.maximum(np.linalg.norm(to_axis, axis=1), 1e-12)[:, None]
        parts.setdefault(flight.pair, []).append({
            "horizontal": horizontal, "separation": dp[:, 2],
            "real": inward_nm(np.einsum("nij,nj->ni", rot, real_body[i]), e_r),
            "model": inward_nm(np.einsum("nij,nj->ni", rot, jet_body), e_r), "lean": lean,
            "near_pwm": near_pwm, "down": flight.label_mps2[:, 2] * geometry["follower_mass_kg"],
            "half": np.full(i.size, geometry["follower_diagonal_m"] / 2.0),
            "radius": np.full(i.size, geometry["follower_rotor_radius_m"]),
            "hub": inward_nm(np.einsum("nij,nj->ni", rot, hub_body), e_r),
            "radial_v": np.sum(flight.follower.v[:, :2] * e_r, axis=1),  # its own, in the air
            "motor_angle_deg": np.degrees(np.arccos(np.clip(cos.max(axis=1), -1.0, 1.0)))})
    if not parts:
        raise WakeFitError("no flight carries the motor torque and body rates with free air "
                           "to take the trim from")
    return {pair: {key: np.concatenate([c[key] for c in chunks]) for key in chunks[0]}
            for pair, chunks in parts.items()}


@dataclass(frozen=True)
class AngleBin:
    """The inward torque by where the follower's motors point: the angle between the line to
    the leader's axis and the nearest motor arm (0: a motor on it; 45 on a quad: the axis
    between two), N·m."""

    angle_lo_deg: float
    angle_hi_deg: float
    samples: int
    real_nm: float
    real_se_nm: float
    jet_nm: float


def torque_by_motor_angle(params: dict[str, float], flights: Sequence[FlightSamples],
                          logs: Sequence[FlightLog], inertia_kgm2: dict[str, Sequence[float]],
                          *, rotor_radii_m: dict[str, float] | None = None,
                          separation_m: tuple[float, float] = (0.15, 0.45),
                          offset_m: tuple[float, float] = (0.04, 0.10),
                          bands_deg: Sequence[tuple[float, float]] = ((0.0, 15.0), (15.0, 30.0),
                                                                      (30.0, 45.0)),
                          free_air_offset_m: float = FREE_AIR_OFFSET_M,
                          ) -> dict[str, list[AngleBin]]:
    """Per pairing, the real and the jet's inward torque ``offset_m`` off the axis and
    ``separation_m`` below it, by the angle between the line to the axis and the nearest motor
    arm (``bands_deg``). A torque made by the wake's force on the disks is largest with a motor
    on that line (its lever the half diagonal, against that over sqrt 2 between two motors on a
    quad), as the disk-sampled jet's is; one made elsewhere would not depend on the angle.

    Raises:
        WakeFitError: as :func:`torque_profile`.
    """
    samples = _inward_samples(params, flights, logs, inertia_kgm2, rotor_radii_m or {},
                              free_air_offset_m)
    out: dict[str, list[AngleBin]] = {}
    for pair, x in samples.items():
        near = ((x["separation"] >= separation_m[0]) & (x["separation"] <= separation_m[1])
                & (x["horizontal"] >= offset_m[0]) & (x["horizontal"] < offset_m[1]))
        bins = []
        for lo, hi in bands_deg:
            angle = x["motor_angle_deg"]
            upper = angle <= hi if (lo, hi) == tuple(bands_deg[-1]) else angle < hi
            m = near & (angle >= lo) & upper
            n = int(m.sum())
            if n >= MIN_BIN_SAMPLES:
                bins.append(AngleBin(angle_lo_deg=float(lo), angle_hi_deg=float(hi), samples=n,
                                     real_nm=float(x["real"][m].mean()),
                                     real_se_nm=float(x["real"][m].std() / np.sqrt(n)),
                                     jet_nm=float(x["model"][m].mean())))
        out[pair] = bins
    return out


@dataclass(frozen=True)
class ForceBin:
    """One bin of horizontal offset from the other vehicle's axis: the follower's mean downward
    force (its vertical label, less its flight's free-air median, times its mass), N, with the
    follower below the other vehicle and, as a control without a wake, above it."""

    offset_lo_m: float
    offset_hi_m: float
    below_samples: int
    below_n: float
    below_se_n: float
    above_samples: int
    above_n: float
    above_se_n: float


def force_profile(logs: Sequence[FlightLog], *, separation_m: tuple[float, float] = (0.15, 0.45),
                  bin_m: float = 0.02, max_offset_m: float = 0.40,
                  free_air_offset_m: float = FREE_AIR_OFFSET_M) -> dict[str, list[ForceBin]]:
    """Per pairing (:func:`~aerodock.identify.flights.pair_name`), the real wake's downward
    force against the horizontal offset, ``separation_m`` below the other vehicle and the same
    distance above it (the swaps' own manoeuvre at the same offsets, without a wake). Beyond the
    jet's edge the flights show an upward force below the leader and none above it: an upwash
    about the wake that a Gaussian jet has no term for. Bins with fewer than
    ``MIN_BIN_SAMPLES`` on a side hold nan there."""
    parts: dict[str, list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
    for log in logs:
        geometry = log_geometry(log)
        far = free_air_mask(log, free_air_offset_m)
        if far.sum() < MIN_FREE_SAMPLES:
            continue
        vertical = raw_labels(log)[:, 2]
        down = (vertical - np.nanmedian(vertical[far])) * geometry["follower_mass_kg"]
        dp = log.follower_pos_m - log.leader_pos_m
        keep = valid_mask(log) & np.isfinite(down)
        parts.setdefault(pair_name(geometry), []).append(
            (np.hypot(dp[keep, 0], dp[keep, 1]), dp[keep, 2], down[keep]))
    out: dict[str, list[ForceBin]] = {}
    for pair, chunks in parts.items():
        horizontal, below_m, down = (np.concatenate(c) for c in zip(*chunks))
        sides = ((below_m >= separation_m[0]) & (below_m <= separation_m[1]),
                 (-below_m >= separation_m[0]) & (-below_m <= separation_m[1]))
        bins = []
        for lo in np.arange(0.0, max_offset_m - 1e-9, bin_m):
            ring = (horizontal >= lo) & (horizontal < lo + bin_m)
            cells = []
            for side in sides:
                x = down[ring & side]
                ok = x.size >= MIN_BIN_SAMPLES
                cells += [int(x.size), float(x.mean()) if ok else float("nan"),
                          float(x.std() / np.sqrt(x.size)) if ok else float("nan")]
            if cells[0] >= MIN_BIN_SAMPLES or cells[3] >= MIN_BIN_SAMPLES:
                bins.append(ForceBin(float(lo), float(lo + bin_m), *cells))
        out[pair] = bins
    return out


def disk_profile_torque(force: Sequence[ForceBin], torque: Sequence[TorqueBin], *,
                        yaws: int = 12) -> tuple[np.ndarray, dict[str, float]]:
    """The inward torque that the wake's force, if carried by the follower's disks alone,
    would make at ``torque``'s bins: a radial profile of the force on one disk, a Gaussian core
    less a Gaussian ring outside it (an upwash about the wake, at most as strong as the core;
    none if the fit wants none),

        f(r) = A (exp(-r^2 / 2 s1^2) - c exp(-(r - r0)^2 / 2 s2^2)),  0 <= c <= 1, r0 >= 5 cm,

    fitted (weighted least squares) to the force profile ``force`` (its ``below_n``) as the sum
    over four disks on the follower's half diagonal, averaged over ``yaws`` yaws of the follower
    to its offset; its torque is the same disks' forces times their levers. On flights of a
    wake sampled at the disks it gives their torque; a real torque several times it is not a
    distribution of thrust over the disks.

    Returns the torque per ``torque`` bin (N·m) and the profile's parameters (N, m).

    Raises:
        WakeFitError: fewer than six force bins below the other vehicle.
    """
    from scipy.optimize import least_squares

    below = [b for b in force if np.isfinite(b.below_n)]
    if len(below) < 6 or not torque:
        raise WakeFitError("too few offset bins below the other vehicle to fit a disk profile")
    x_f = np.array([(b.offset_lo_m + b.offset_hi_m) / 2.0 for b in below])
    f_n = np.array([b.below_n for b in below])
    se = np.maximum(np.array([b.below_se_n for b in below]), 1e-4)
    x_t = np.array([(b.offset_lo_m + b.offset_hi_m) / 2.0 for b in torque])
    half = float(np.mean([b.half_diagonal_m for b in torque]))
    angle = (np.linspace(0.0, np.pi / 2.0, yaws, endpoint=False)[:, None] + np.pi / 4.0
             + np.arange(4) * np.pi / 2.0)
    ox, oy = half * np.cos(angle), half * np.sin(angle)  # (yaw, disk), e_r along x

    def carried(p: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a, s1, c, r0, s2 = p
        r = np.hypot(x[:, None, None] + ox[None], oy[None])
        disk = a * (np.exp(-r ** 2 / (2 * s1 ** 2)) - c * np.exp(-(r - r0) ** 2 / (2 * s2 ** 2)))
        return disk.sum(axis=2).mean(axis=1), (disk * -ox[None]).sum(axis=2).mean(axis=1)

    peak = max(float(f_n.max()), 1e-3) / 4.0
    fit = least_squares(lambda p: (carried(p, x_f)[0] - f_n) / se,
                        [peak, 0.05, 0.05, 0.2, 0.05],
                        bounds=([0.0, 0.005, 0.0, 0.05, 0.005], [np.inf, 0.3, 1.0, 0.5, 0.3]))
    names = ("core_n", "core_sd_m", "ring_fraction", "ring_radius_m", "ring_sd_m")
    return carried(fit.x, x_t)[1], dict(zip(names, map(float, fit.x), strict=True))


def thrust_map_slope(logs: Sequence[FlightLog], *, band_hz: tuple[float, float] = (0.5, 4.0),
                     max_delay_s: float = 0.2,
                     free_air_offset_m: float = FREE_AIR_OFFSET_M) -> dict[str, dict[str, float]]:
    """How much thrust the logs' still-air map gives for the thrust the vehicle makes, per
    follower vehicle id, in free air: the logged collective thrust against the one its
    accelerometer measures (``-m (a_obs - g e3) . R e3``), both band-passed (``band_hz``,
    zero-phase Butterworth), the measured one delayed by the lag (up to ``max_delay_s``) that
    correlates best. ``forward`` (measured on logged) and ``reverse`` (the inverse of logged on
    measured) bracket the slope when either side carries noise of its own (the closed loop's
    own disturbances are small in free air). The torque labels are the same map's differences,
    so a map that overstated its slope by a factor would make them that factor too large (and
    the force labels with them).

    Returns ``{vid: {"forward", "reverse", "correlation", "delay_s", "samples"}}``."""
    from scipy.signal import butter, sosfiltfilt

    per: dict[str, list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
    dts = []
    for log in logs:
        if log.n_samples < 50:
            continue
        mass = log_geometry(log)["follower_mass_kg"]
        e3 = quat_to_rotmat(log.follower_quat)[:, :, 2]
        g = float(log.meta.get("gravity_mps2", GRAVITY_MPS2))
        specific = log.follower_obs_accel_mps2 - np.array([0.0, 0.0, g])
        measured = -mass * np.einsum("ni,ni->n", specific, e3)
        dt = float(np.median(np.diff(log.t_s)))
        sos = butter(2, band_hz, btype="band", fs=1.0 / dt, output="sos")
        free = free_air_mask(log, free_air_offset_m)
        edge = int(round(2.0 / band_hz[0] / dt))  # the filter's start-up at either end
        free[:edge] = False
        free[-edge:] = False
        per.setdefault(str(log.meta.get("follower_id")), []).append(
            (sosfiltfilt(sos, log.follower_thrust_n), sosfiltfilt(sos, measured), free))
        dts.append(dt)
    out: dict[str, dict[str, float]] = {}
    dt = float(np.median(dts)) if dts else 0.01
    for vid in sorted(per):
        best = None
        for lag in range(int(round(max_delay_s / dt)) + 1):
            x = np.concatenate([a[:a.size - lag][f[lag:]] for a, _, f in per[vid]])
            y = np.concatenate([b[lag:][f[lag:]] for _, b, f in per[vid]])
            if x.size < MIN_FREE_SAMPLES:
                continue
            r = float(np.corrcoef(x, y)[0, 1])
            if best is None or r > best["correlation"]:
                best = {"forward": float(x @ y / (x @ x)), "reverse": float(y @ y / (x @ y)),
                        "correlation": r, "delay_s": lag * dt, "samples": int(x.size)}
        if best is not None:
            out[vid] = best
    return out


def _mean_if_enough(x: np.ndarray) -> float:
    return float(x.mean()) if x.size >= MIN_BIN_SAMPLES else float("nan")


# quad_rotor_offsets_body_m's disks (FRD) -> the Neural-Swarm logs' motor columns (u1..u4:
# front right, back right, back left, front left), filled in by _motor_order below.
def _motor_order() -> np.ndarray:
    offsets = quad_rotor_offsets_body_m(1.0, 4)
    logs_frd = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    order = np.empty(4, dtype=int)
    for k, (x, y) in enumerate(offsets[:, :2]):
        order[k] = int(np.argmax(logs_frd @ np.array([x, y])))
    return order


_LOG_MOTOR_ORDER = _motor_order()

