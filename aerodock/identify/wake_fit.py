"""Identifying the default jet (:class:`aerodock.downwash.jet.RoundJetField`) from flight logs.

The jet's parameters are dimensionless, so the fit on one pair of vehicles gives the wake of any
other (the world's rotor sizes and the leader's thrust set the scales, by momentum theory):

- **Mean** (``MEAN_PARAMS``): the width at the rotor plane and its growth, the ingest law's
  coefficient and exponent, the planar part; by least squares (``scipy.optimize.least_squares``)
  of the follower's de-biased residual acceleration, vertical and radial, against the jet's mean
  at every logged sample in the interaction region (the logged leader and follower states: the
  leader's thrust, both attitudes, both velocities). A vehicle whose rotor radius the logs do not
  know may have it estimated alongside (``estimate_rotor_for``).
- **Turbulence** (``TURBULENCE_PARAMS``): per-disk intensities (vertical, lateral), the share the
  disks have in common (through the jet's length scale) and the correlation time (through the
  eddy turnover time); from the spread of the residual about the fitted mean near the wake's
  axis, per vehicle pair and band of lateral offset, and from its autocorrelation.

The labels' own noise and bias are accounted for (:mod:`aerodock.learning.labels`): each
flight's residual is de-biased by its free-air median (flights without free-air samples borrow
their follower vehicle's other flights'); the free-air variance (and autocovariance) of each
follower vehicle's residual, about that bias, is subtracted from the wake's before it is read
as turbulence (or, given per sample, the noise at the follower's own speed:
:func:`aerodock.identify.label_noise.with_speed_noise`, ``field fit --noise speed``). The
leader's logged thrust is scaled so that its flight median is its weight (the thrust estimate of
a real log carries the same few-percent bias).

Scores (:func:`score_wake`) are what the issue's targets name, per vehicle pair, on any flights
(held out from the fit): the mean vertical acceleration directly below the leader per bin of
separation, the lateral half-magnitude radius, the vertical and lateral turbulence sd, and the
autocorrelation at 50 and 80 ms. The uncertainty is a bootstrap over flights.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.downwash.jet import CONTRACTED_WIDTH0_RATIO, RoundJetField
from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.learning.labels import estimate_biases, free_air_mask, raw_labels, valid_mask

GRAVITY_MPS2 = 9.81
MEAN_PARAMS = ("width0_ratio", "spread_rate", "ingest_coeff", "ingest_exponent", "planar_ratio")
TURBULENCE_PARAMS = ("turb_vertical", "turb_lateral", "turb_length_ratio", "turb_time_ratio")
FITTED_PARAMS = MEAN_PARAMS + TURBULENCE_PARAMS
# Start and bounds of each parameter (the start is momentum theory's contracted wake with a
# round jet's spread; the bounds keep the jet physical).
START = {"width0_ratio": CONTRACTED_WIDTH0_RATIO, "spread_rate": 0.1, "ingest_coeff": 0.5,
         "ingest_exponent": 1.5, "planar_ratio": 0.0, "turb_vertical": 0.25, "turb_lateral": 0.08,
         "turb_length_ratio": 0.5, "turb_time_ratio": 2.0}
BOUNDS = {"width0_ratio": (0.1, 5.0), "spread_rate": (0.0, 1.0), "ingest_coeff": (1e-3, 10.0),
          "ingest_exponent": (0.3, 3.0), "planar_ratio": (-1.0, 1.0),
          "turb_vertical": (0.0, 3.0), "turb_lateral": (0.0, 3.0),
          "turb_length_ratio": (0.05, 20.0), "turb_time_ratio": (0.05, 100.0)}
ROTOR_BOUNDS_M = (0.005, 0.2)
GEOMETRY_KEYS = ("leader_rotor_radius_m", "leader_n_rotors", "follower_rotor_radius_m",
                 "follower_n_rotors", "follower_diagonal_m", "leader_mass_kg", "follower_mass_kg")
REGION_RADII = 6.0  # the interaction region: horizontally within 6 leader equivalent radii
CORE_RADII = 1.0  # "directly below": within one leader equivalent radius of its axis
SEPARATION_BIN_M = 0.05
MIN_BIN_SAMPLES = 30
LAGS = 9  # autocorrelation lags 0..8 (0-80 ms at 100 Hz)
TARGETS = {"mean_vertical": 0.15, "half_width": 0.20, "vertical_sd": 0.20, "lateral_sd": 0.20}
"""The issue's targets: largest relative error of each figure on held-out flights."""


class WakeFitError(ValueError):
    """The logs cannot be fitted (missing geometry, no samples in the wake); one line."""


@dataclass(frozen=True)
class FlightSamples:
    """One flight log's samples in the interaction region, as the fit uses them.

    Attributes:
        name: the log's name; ``flight``: the flight it belongs to (both vehicles' logs of one
            flight share it); ``pair``: the vehicle pair, e.g. ``"32 g under 67 g"``.
        geometry: the field's vehicle keywords (:data:`GEOMETRY_KEYS`).
        vehicles: ``{"leader": id, "follower": id}`` (the logs' vehicle ids, or None).
        leader, follower: the logged states of the region's samples (leader thrust scaled to
            its weight, follower thrust its weight).
        label_mps2: (m, 3) de-biased residual ``a_obs - cmd``, NED.
        index: (m,) the samples' indices in the log (consecutive samples: consecutive indices).
        dt_s: the log's median sample interval.
        free_var_mps4: (3,) the follower vehicle's free-air label variance per axis.
        free_autocov: (LAGS,) its free-air vertical autocovariance, lags 0..LAGS-1 samples.
        noise_var_mps4: (m, 3) the label noise variance of each sample, where it is known per
            sample (:func:`aerodock.identify.label_noise.with_speed_noise`: the free-air
            variance at the follower's speed); None: ``free_var_mps4`` for every sample.
    """

    name: str
    flight: str
    pair: str
    geometry: dict[str, float]
    vehicles: dict[str, str | None]
    leader: BodyState
    follower: BodyState
    label_mps2: np.ndarray
    index: np.ndarray
    dt_s: float
    free_var_mps4: np.ndarray
    free_autocov: np.ndarray
    noise_var_mps4: np.ndarray | None = None

    @property
    def sample_noise_var_mps4(self) -> np.ndarray:
        """(m, 3) the label noise variance the turbulence is read above, per sample."""
        if self.noise_var_mps4 is not None:
            return self.noise_var_mps4
        return np.broadcast_to(self.free_var_mps4, self.label_mps2.shape)

    @property
    def offset_m(self) -> np.ndarray:
        """(m, 3) follower minus leader position, NED."""
        return self.follower.p - self.leader.p

    @property
    def equivalent_radius_m(self) -> float:
        """The leader's equivalent disk radius ``R sqrt(n)``."""
        return float(self.geometry["leader_rotor_radius_m"]
                     * np.sqrt(self.geometry["leader_n_rotors"]))


@dataclass
class WakeFit:
    """The fitted parameters, their bootstrap spread, and what the fit saw."""

    params: dict[str, float]
    rotor_radii_m: dict[str, float] = field(default_factory=dict)
    bootstrap: dict[str, dict[str, float]] = field(default_factory=dict)
    bootstrap_runs: int = 0
    bootstrap_draws: list[dict[str, float]] = field(default_factory=list)
    flights: list[str] = field(default_factory=list)
    samples: int = 0
    mean_rms_mps2: float = float("nan")
    turbulence_bins: list[dict[str, Any]] = field(default_factory=list)
    autocorrelation: dict[str, dict[str, list[float]]] = field(default_factory=dict)

    def field_params(self) -> dict[str, float]:
        """The ``[downwash.params]`` values the fit identified."""
        return {k: float(self.params[k]) for k in FITTED_PARAMS}


# -- data ------------------------------------------------------------------------------------
def flight_key(log: FlightLog) -> str:
    """The flight a log belongs to: its name less the follower's id (both logs of a two-vehicle
    Neural-Swarm flight share it), else the name."""
    name = str(log.meta.get("name", ""))
    follower = log.meta.get("follower_id")
    if follower and name.endswith(f"_{follower}"):
        return name[: -len(follower) - 1]
    return name


def log_geometry(log: FlightLog, rotor_radii_m: dict[str, float] | None = None) -> dict:
    """The field's vehicle keywords from a log's meta (``rotor_radii_m`` overrides a vehicle's
    rotor radius by its id).

    Raises:
        WakeFitError: a key the meta lacks (named).
    """
    meta = log.meta
    out: dict[str, float] = {}
    for key in GEOMETRY_KEYS:
        value = meta.get(key)
        if not isinstance(value, int | float) or not np.isfinite(value) or value <= 0:
            raise WakeFitError(f"{log.name}: the log's meta has no {key} (the wake fit needs "
                               "both vehicles' masses, rotors and the follower's diagonal)")
        out[key] = float(value)
    for role in ("leader", "follower"):
        vid = meta.get(f"{role}_id")
        if rotor_radii_m and vid in rotor_radii_m:
            out[f"{role}_rotor_radius_m"] = float(rotor_radii_m[vid])
    return out


def pair_name(geometry: dict[str, float]) -> str:
    """``"32 g under 67 g"``: the follower's and the leader's mass."""
    return (f"{1000 * geometry['follower_mass_kg']:.0f} g under "
            f"{1000 * geometry['leader_mass_kg']:.0f} g")


def prepare_flights(logs: Sequence[FlightLog], *, region_radii: float = REGION_RADII,
                    ) -> list[FlightSamples]:
    """The fit's samples of each log: de-biased labels in the interaction region and the
    follower vehicle's free-air noise (module docstring).

    Free air (the bias, the noise) and the interaction region are set by the leader's size:
    horizontally within ``region_radii`` leader equivalent radii below the leader is the region,
    farther (or above it) is free air.

    Raises:
        WakeFitError: a log without the geometry, or no sample in any region.
    """
    logs = list(logs)
    groups: dict[str, list[int]] = {}
    for i, log in enumerate(logs):
        key = f"{log.meta.get('follower_id') or ''}|{log.meta.get('follower_mass_kg')}"
        groups.setdefault(key, []).append(i)
    out: list[FlightSamples | None] = [None] * len(logs)
    for members in groups.values():
        group = [logs[i] for i in members]
        radii = [_equivalent_radius(log) * region_radii for log in group]
        raws = [raw_labels(log) for log in group]
        biases = [estimate_biases([log], free_air_radius_m=r, raw=[raw])[0][0]
                  for log, r, raw in zip(group, radii, raws, strict=True)]
        own = [b for b in biases if b.source == "own"]
        fallback = (np.median([b.bias for b in own], axis=0) if own else np.zeros(3))
        free_parts, auto_parts = [], []
        debiased = []
        for log, r, raw, b in zip(group, radii, raws, biases, strict=True):
            y = raw - (b.bias if b.source == "own" else fallback)
            debiased.append(y)
            mask = free_air_mask(log, r)
            if mask.sum() > LAGS:
                free_parts.append(y[mask])
                auto_parts.append((y[:, 2], mask))
        if free_parts:
            free = np.concatenate(free_parts)
            free_var = free.var(axis=0)
            free_auto = _autocovariance(auto_parts)
        else:
            free_var, free_auto = np.zeros(3), np.zeros(LAGS)
        for i, log, r, y in zip(members, group, radii, debiased, strict=True):
            out[i] = _region_samples(log, y, r, free_var, free_auto)
    flights = [s for s in out if s is not None]
    if not flights:
        raise WakeFitError("no log has samples below its leader within the interaction region")
    return flights


def _equivalent_radius(log: FlightLog) -> float:
    geometry = log_geometry(log)
    return geometry["leader_rotor_radius_m"] * np.sqrt(geometry["leader_n_rotors"])


def _region_samples(log: FlightLog, label: np.ndarray, radius_m: float, free_var: np.ndarray,
                    free_auto: np.ndarray) -> FlightSamples | None:
    geometry = log_geometry(log)
    dp = log.follower_pos_m - log.leader_pos_m
    horizontal = np.hypot(dp[:, 0], dp[:, 1])
    keep = (dp[:, 2] > 0.0) & (horizontal < radius_m) & valid_mask(log)
    if keep.sum() < 2:
        return None
    index = np.nonzero(keep)[0]
    g = GRAVITY_MPS2
    m_lead, m_fol = geometry["leader_mass_kg"], geometry["follower_mass_kg"]
    logged = log.extra.get("leader_thrust_n")
    if logged is not None and np.median(logged) > 0:
        thrust = m_lead * g * np.asarray(logged, dtype=float) / float(np.median(logged))
    else:
        thrust = np.full(log.n_samples, m_lead * g)
    n = index.size
    leader = BodyState(log.leader_pos_m[index], log.leader_vel_mps[index],
                       quat_to_rotmat(log.leader_quat[index]), thrust[index],
                       np.full(n, m_lead))
    follower = BodyState(log.follower_pos_m[index], log.follower_vel_mps[index],
                         quat_to_rotmat(log.follower_quat[index]), np.full(n, m_fol * g),
                         np.full(n, m_fol))
    dt = float(np.median(np.diff(log.t_s))) if log.n_samples > 1 else 0.01
    return FlightSamples(
        name=log.name, flight=flight_key(log), pair=pair_name(geometry), geometry=geometry,
        vehicles={"leader": log.meta.get("leader_id"), "follower": log.meta.get("follower_id")},
        leader=leader, follower=follower, label_mps2=label[index], index=index, dt_s=dt,
        free_var_mps4=np.asarray(free_var, dtype=float),
        free_autocov=np.asarray(free_auto, dtype=float))


def _autocovariance(parts: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Autocovariance (lags 0..LAGS-1 samples) of zero-mean series (de-biased labels, or
    residuals about the jet's mean) over the runs of consecutive samples where ``mask`` holds,
    pooled over the runs (a run shorter than a lag adds nothing to it)."""
    num, count = np.zeros(LAGS), np.zeros(LAGS)
    for series, mask in parts:
        for start, stop in _runs(mask):
            x = series[start:stop]
            for lag in range(min(LAGS, x.size)):
                num[lag] += np.dot(x[: x.size - lag], x[lag:])
                count[lag] += x.size - lag
    return np.where(count > 0, num / np.maximum(count, 1), 0.0)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of each run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0], strict=True))


def select_flights(flights: Sequence[FlightSamples], patterns: Sequence[str],
                   ) -> tuple[list[FlightSamples], list[FlightSamples]]:
    """``(others, matching)``: the flights whose flight key matches none / one of the
    shell-style ``patterns`` (e.g. ``"swap_ss_0[56]"``)."""
    match = [f for f in flights if any(fnmatch.fnmatchcase(f.flight, p) for p in patterns)]
    names = {f.name for f in match}
    return [f for f in flights if f.name not in names], match


# -- the model at the samples ---------------------------------------------------------------
def build_jet(params: dict[str, float], geometry: dict[str, float]) -> RoundJetField:
    """The jet with ``params`` (fitted keys) between the vehicles of ``geometry``."""
    kwargs = {k: v for k, v in params.items() if k in FITTED_PARAMS}
    return RoundJetField(
        **kwargs, leader_rotor_radius_m=geometry["leader_rotor_radius_m"],
        leader_n_rotors=int(geometry["leader_n_rotors"]),
        follower_rotor_radius_m=geometry["follower_rotor_radius_m"],
        follower_n_rotors=int(geometry["follower_n_rotors"]),
        follower_diagonal_m=geometry["follower_diagonal_m"], gravity_mps2=GRAVITY_MPS2)


def geometry_with(flight: FlightSamples, rotor_radii_m: dict[str, float]) -> dict[str, float]:
    """The flight's vehicle geometry with ``rotor_radii_m`` (by vehicle id) in place of its
    logged rotor radii."""
    geometry = dict(flight.geometry)
    for role in ("leader", "follower"):
        vid = flight.vehicles.get(role)
        if vid in rotor_radii_m:
            geometry[f"{role}_rotor_radius_m"] = rotor_radii_m[vid]
    return geometry


def model_mean(params: dict[str, float], flight: FlightSamples,
               rotor_radii_m: dict[str, float] | None = None) -> np.ndarray:
    """(m, 3) the jet's mean acceleration at the flight's samples, m/s², NED."""
    jet = build_jet(params, geometry_with(flight, rotor_radii_m or {}))
    return jet.mean_acceleration(flight.leader, flight.follower)


def model_turbulence(params: dict[str, float], flight: FlightSamples,
                     rotor_radii_m: dict[str, float] | None = None) -> dict[str, np.ndarray]:
    """The jet's turbulence at the flight's samples (:meth:`RoundJetField.turbulence`)."""
    jet = build_jet(params, geometry_with(flight, rotor_radii_m or {}))
    return jet.turbulence(flight.leader, flight.follower)


def _radial_unit(offset_m: np.ndarray) -> np.ndarray:
    h = np.hypot(offset_m[:, 0], offset_m[:, 1])
    unit = np.zeros((offset_m.shape[0], 2))
    far = h > 1e-6
    unit[far] = offset_m[far, :2] / h[far, None]
    return unit


# -- the fit ---------------------------------------------------------------------------------
def fit_mean(flights: Sequence[FlightSamples], start: dict[str, float] | None = None,
             estimate_rotor_for: Sequence[str] = (),
             rotor_start_m: dict[str, float] | None = None,
             ) -> tuple[dict[str, float], dict[str, float], float]:
    """Least squares of the de-biased residual (vertical and radial) against the jet's mean.

    Returns:
        ``(params, rotor_radii_m, rms)`` (the start: ``start``'s parameters, else
        :data:`START`; ``rotor_start_m``'s radii, else the logs'): the mean parameters, the
        estimated rotor radii of
        ``estimate_rotor_for`` (vehicle ids), and the vertical residual's RMS, m/s² (each
        vehicle pair weighs the same in the fit).
    """
    from scipy.optimize import least_squares

    start = {**START, **(start or {})}
    rotors = list(estimate_rotor_for)
    for vid in rotors:
        if not any(vid in f.vehicles.values() for f in flights):
            raise WakeFitError(f"--estimate-rotor {vid}: no log has a vehicle {vid!r}")
    x0 = [start[k] for k in MEAN_PARAMS] + [(rotor_start_m or {}).get(v)
                                             or _logged_radius(flights, v) for v in rotors]
    low = [BOUNDS[k][0] for k in MEAN_PARAMS] + [ROTOR_BOUNDS_M[0]] * len(rotors)
    high = [BOUNDS[k][1] for k in MEAN_PARAMS] + [ROTOR_BOUNDS_M[1]] * len(rotors)
    x0 = np.clip(x0, low, high)
    units = [_radial_unit(f.offset_m) for f in flights]
    # Each vehicle pair weighs the same, however many samples its flights hold.
    counts: dict[str, int] = {}
    for f in flights:
        counts[f.pair] = counts.get(f.pair, 0) + f.label_mps2.shape[0]
    total = sum(counts.values())
    weights = [np.sqrt(total / (len(counts) * counts[f.pair])) for f in flights]
    fixed = {k: v for k, v in start.items() if k not in MEAN_PARAMS}

    def unpack(x: np.ndarray) -> tuple[dict[str, float], dict[str, float]]:
        params = {**fixed, **dict(zip(MEAN_PARAMS, x[:len(MEAN_PARAMS)], strict=True))}
        return params, dict(zip(rotors, x[len(MEAN_PARAMS):], strict=True))

    def residual(x: np.ndarray) -> np.ndarray:
        params, radii = unpack(x)
        parts = []
        for f, unit, w in zip(flights, units, weights, strict=True):
            err = f.label_mps2 - model_mean(params, f, radii)
            parts.append(w * err[:, 2])
            parts.append(w * (err[:, 0] * unit[:, 0] + err[:, 1] * unit[:, 1]))
        return np.concatenate(parts)

    result = least_squares(residual, x0, bounds=(low, high), x_scale="jac")
    params, radii = unpack(result.x)
    rms = float(np.sqrt(np.mean(np.concatenate(
        [(f.label_mps2 - model_mean(params, f, radii))[:, 2] for f in flights]) ** 2)))
    return {k: float(v) for k, v in params.items()}, {k: float(v) for k, v in radii.items()}, rms


def _logged_radius(flights: Sequence[FlightSamples], vehicle_id: str) -> float:
    for f in flights:
        for role in ("leader", "follower"):
            if f.vehicles.get(role) == vehicle_id:
                return f.geometry[f"{role}_rotor_radius_m"]
    return 0.03


def turbulence_bins(params: dict[str, float], flights: Sequence[FlightSamples],
                    rotor_radii_m: dict[str, float] | None = None) -> list[dict[str, Any]]:
    """Per vehicle pair and band of lateral offset near the axis (0-0.5 and 0.5-1 leader
    equivalent radii: "directly below", where the targets are scored), each flight's residual's
    spread about the jet's mean (and its own offset), less the label noise (``real_*_var``;
    :attr:`FlightSamples.sample_noise_var_mps4`),
    beside the jet's own turbulence variance there (``model_*_var``), m²/s⁴.
    Bins with fewer than :data:`MIN_BIN_SAMPLES` samples are left out."""
    bands = ((0.0, 0.5), (0.5, 1.0))
    rows: dict[tuple[str, int], dict[str, list]] = {}
    for f in flights:
        mean = model_mean(params, f, rotor_radii_m)
        turb = model_turbulence(params, f, rotor_radii_m)
        dp = f.offset_m
        h = np.hypot(dp[:, 0], dp[:, 1]) / f.equivalent_radius_m
        err = centred(f.label_mps2 - mean, h < bands[-1][1])
        for b, (lo, hi) in enumerate(bands):
            sel = (h >= lo) & (h < hi)
            if not sel.any():
                continue
            row = rows.setdefault((f.pair, b), {k: [] for k in
                                                ("ez", "exy", "vz", "vl", "fz", "fl")})
            row["ez"].append(err[sel, 2])
            row["exy"].append(err[sel, :2])
            row["vz"].append(turb["axial_var_mps4"][sel])
            row["vl"].append(turb["lateral_var_mps4"][sel])
            noise = f.sample_noise_var_mps4[sel]
            row["fz"].append(noise[:, 2])
            row["fl"].append(0.5 * (noise[:, 0] + noise[:, 1]))
    out = []
    for (pair, b), row in sorted(rows.items()):
        ez = np.concatenate(row["ez"])
        if ez.size < MIN_BIN_SAMPLES:
            continue
        exy = np.concatenate(row["exy"])
        out.append({
            "pair": pair, "band_radii": list(bands[b]), "samples": int(ez.size),
            "real_vertical_var": float(ez.var() - np.mean(np.concatenate(row["fz"]))),
            "real_lateral_var": float(0.5 * (exy[:, 0].var() + exy[:, 1].var())
                                      - np.mean(np.concatenate(row["fl"]))),
            "model_vertical_var": float(np.mean(np.concatenate(row["vz"]))),
            "model_lateral_var": float(np.mean(np.concatenate(row["vl"]))),
        })
    return out


def centred(err: np.ndarray, core: np.ndarray) -> np.ndarray:
    """``err`` less its mean over ``core``: one flight's residual about the jet's mean, less
    that flight's own offset (a bias the free-air samples missed is not turbulence)."""
    if not core.any():
        return err
    return err - err[core].mean(axis=0)


def fit_turbulence(params: dict[str, float], flights: Sequence[FlightSamples],
                   rotor_radii_m: dict[str, float] | None = None) -> dict[str, float]:
    """The turbulence parameters, given the mean ones: the vertical intensity and the disks'
    shared share (length ratio) from the vertical spread per pair and offset band, the lateral
    intensity from the lateral spread, the correlation time from the autocorrelation."""
    from scipy.optimize import least_squares

    params = {**START, **params}

    def bins_with(x: dict[str, float]) -> list[dict[str, Any]]:
        return turbulence_bins({**params, **x}, flights, rotor_radii_m)

    def rel_err(model_var: float, real_var: float) -> float:
        real = np.sqrt(max(real_var, 1e-6))
        return (np.sqrt(max(model_var, 0.0)) - real) / real

    names = ("turb_vertical", "turb_length_ratio")
    x0 = [params[k] for k in names]

    def vertical(x: np.ndarray) -> np.ndarray:
        rows = bins_with(dict(zip(names, x, strict=True)))
        return np.array([rel_err(r["model_vertical_var"], r["real_vertical_var"])
                         * np.sqrt(r["samples"]) for r in rows])

    low, high = [BOUNDS[k][0] for k in names], [BOUNDS[k][1] for k in names]
    res = least_squares(vertical, np.clip(x0, low, high), bounds=(low, high), x_scale="jac")
    out = dict(zip(names, (float(v) for v in res.x), strict=True))
    # The lateral intensity scales the lateral variance exactly: a weighted ratio of sds.
    rows = bins_with({**out, "turb_lateral": 1.0})
    weights = np.array([r["samples"] for r in rows], dtype=float)
    real = np.sqrt(np.maximum([r["real_lateral_var"] for r in rows], 0.0))
    unit = np.sqrt(np.maximum([r["model_lateral_var"] for r in rows], 1e-300))
    out["turb_lateral"] = float(np.clip(np.sum(weights * real * unit)
                                        / np.sum(weights * unit * unit), *BOUNDS["turb_lateral"]))
    out["turb_time_ratio"] = fit_correlation_time(params, flights, rotor_radii_m)
    return out


def autocorrelations(params: dict[str, float], flights: Sequence[FlightSamples],
                     rotor_radii_m: dict[str, float] | None = None,
                     ) -> dict[str, dict[str, list[float]]]:
    """Per pair: the real vertical autocorrelation near the axis (the residual about the mean,
    less the free-air autocovariance), lags 0..LAGS-1 samples, and the jet's (``model``:
    ``exp(-lag dt / tau)`` averaged over the same samples), with the lags in s."""
    by_pair: dict[str, dict[str, list]] = {}
    for f in flights:
        dp = f.offset_m
        core = np.hypot(dp[:, 0], dp[:, 1]) < CORE_RADII * f.equivalent_radius_m
        err = centred(f.label_mps2 - model_mean(params, f, rotor_radii_m), core)[:, 2]
        series = np.zeros(int(f.index.max()) + 1)
        mask = np.zeros(series.size, dtype=bool)
        series[f.index] = err
        mask[f.index] = core
        tau = model_turbulence(params, f, rotor_radii_m)["corr_time_s"][core]
        entry = by_pair.setdefault(f.pair, {"parts": [], "free": [], "tau": [], "dt": []})
        entry["parts"].append((series, mask))
        entry["free"].append(f.free_autocov)
        entry["tau"].append(tau)
        entry["dt"].append(f.dt_s)
    out = {}
    for pair, entry in sorted(by_pair.items()):
        cov = _autocovariance(entry["parts"])
        cov = cov - np.mean(entry["free"], axis=0)
        if not cov[0] > 0:
            continue
        dt = float(np.median(entry["dt"]))
        lags = np.arange(LAGS) * dt
        tau = np.concatenate(entry["tau"])
        if tau.size == 0:
            continue
        model = np.exp(-lags[:, None] / tau[None, :]).mean(axis=1)
        out[pair] = {"lag_s": lags.tolist(), "real": (cov / cov[0]).tolist(),
                     "model": model.tolist()}
    return out


def fit_correlation_time(params: dict[str, float], flights: Sequence[FlightSamples],
                         rotor_radii_m: dict[str, float] | None = None) -> float:
    """``turb_time_ratio`` of the real vertical autocorrelation near the axis at lags 10-80 ms
    (:func:`autocorrelations`, all pairs together), read as a fast exponential (the jet's
    turbulence, its correlation time ``turb_time_ratio * b / w_c`` at each sample) on a
    plateau: each pair's ``A exp(-lag / tau) + (1 - A)``, where the plateau ``1 - A`` is what
    varies more slowly than 80 ms (the mean's own error along a pass; the model does not read it
    as turbulence's time scale)."""
    from scipy.optimize import least_squares

    unit = autocorrelations({**params, "turb_time_ratio": 1.0}, flights, rotor_radii_m)
    if not unit:
        return float(params.get("turb_time_ratio", START["turb_time_ratio"]))
    taus = {}
    for f in flights:
        dp = f.offset_m
        core = np.hypot(dp[:, 0], dp[:, 1]) < CORE_RADII * f.equivalent_radius_m
        tau1 = model_turbulence({**params, "turb_time_ratio": 1.0}, f,
                                rotor_radii_m)["corr_time_s"][core]
        taus.setdefault(f.pair, []).append(tau1)
    pairs = sorted(unit)

    def residual(x: np.ndarray) -> np.ndarray:
        parts = []
        for share, pair in zip(x[1:], pairs, strict=True):
            tau = np.exp(x[0]) * np.concatenate(taus[pair])
            lags = np.asarray(unit[pair]["lag_s"])[1:]
            fast = np.exp(-lags[:, None] / tau[None, :]).mean(axis=1)
            parts.append(share * fast + (1.0 - share) - np.asarray(unit[pair]["real"])[1:])
        return np.concatenate(parts)

    low = [np.log(BOUNDS["turb_time_ratio"][0])] + [0.0] * len(pairs)
    high = [np.log(BOUNDS["turb_time_ratio"][1])] + [1.0] * len(pairs)
    x0 = [np.log(START["turb_time_ratio"])] + [0.7] * len(pairs)
    res = least_squares(residual, x0, bounds=(low, high))
    return float(np.exp(res.x[0]))


def fit_wake(flights: Sequence[FlightSamples], *, estimate_rotor_for: Sequence[str] = (),
             bootstrap: int = 0, seed: int = 0,
             progress: Callable[[int, int], None] | None = None) -> WakeFit:
    """The whole fit: mean, then turbulence, then (``bootstrap`` > 0) the spread of every
    parameter over refits on flights resampled with replacement.

    Raises:
        WakeFitError: no flights.
    """
    flights = list(flights)
    if not flights:
        raise WakeFitError("no flights to fit")
    mean, radii, rms = fit_mean(flights, estimate_rotor_for=estimate_rotor_for)
    turb = fit_turbulence(mean, flights, radii)
    params = {**mean, **turb}
    fit = WakeFit(params=params, rotor_radii_m=radii, flights=sorted({f.flight for f in flights}),
                  samples=int(sum(f.label_mps2.shape[0] for f in flights)), mean_rms_mps2=rms,
                  turbulence_bins=turbulence_bins(params, flights, radii),
                  autocorrelation=autocorrelations(params, flights, radii))
    if bootstrap > 0:
        fit.bootstrap_draws = _bootstrap(flights, fit, estimate_rotor_for, bootstrap, seed,
                                         progress)
        fit.bootstrap_runs = len(fit.bootstrap_draws)
        fit.bootstrap = summarise_draws(fit.bootstrap_draws)
    return fit


def summarise_draws(draws: Sequence[dict[str, float]]) -> dict[str, dict[str, float]]:
    """Per key of ``draws``: sd and the 2.5 and 97.5 percentiles."""
    keys = sorted({k for d in draws for k in d})
    out = {}
    for k in keys:
        v = np.array([d[k] for d in draws if k in d], dtype=float)
        out[k] = {"sd": float(v.std(ddof=1)) if v.size > 1 else float("nan"),
                  "p2_5": float(np.percentile(v, 2.5)), "p97_5": float(np.percentile(v, 97.5))}
    return out


def _bootstrap(flights: list[FlightSamples], fit: WakeFit, estimate_rotor_for: Sequence[str],
               runs: int, seed: int, progress: Callable[[int, int], None] | None,
               ) -> list[dict[str, float]]:
    """Refits on the flights resampled with replacement (a flight drawn twice counts twice):
    one dict of parameters (and ``rotor_radius_m[ID]``) per refit that succeeded."""
    rng = np.random.default_rng(seed)
    keys = sorted({f.flight for f in flights})
    by_key = {k: [f for f in flights if f.flight == k] for k in keys}
    draws: list[dict[str, float]] = []
    for run in range(runs):
        chosen = rng.choice(len(keys), size=len(keys), replace=True)
        sample: list[FlightSamples] = []
        for j, i in enumerate(chosen):
            sample += [replace(f, name=f"{f.name}#{j}") for f in by_key[keys[i]]]
        wanted = [v for v in estimate_rotor_for if any(v in f.vehicles.values() for f in sample)]
        try:
            mean, radii, _ = fit_mean(sample, start=fit.params, estimate_rotor_for=wanted,
                                      rotor_start_m=fit.rotor_radii_m)
            turb = fit_turbulence({**fit.params, **mean}, sample, radii)
        except (WakeFitError, ValueError):
            continue
        draw = {k: v for k, v in {**mean, **turb}.items() if k in FITTED_PARAMS}
        draw.update({f"rotor_radius_m[{k}]": v for k, v in radii.items()})
        draws.append(draw)
        if progress:
            progress(run + 1, runs)
    return draws


def wake_at_separations(params: dict[str, float], cfg: Any,
                        separations_m: Sequence[float] = (0.36, 0.64, 1.35)) -> list[dict]:
    """The jet with ``params`` in the world of ``cfg`` (its vehicles, its air), directly below
    a hovering leader at each separation: mean downward acceleration on a level follower,
    half-magnitude radius of it, the sd of the whole follower's turbulence along the axis and
    across it, and the correlation time."""
    from aerodock.downwash import build_field
    from aerodock.downwash.probe import half_magnitude_radius_m, probe_bodies

    cfg = cfg.with_overrides({"downwash": {"field": "aerodock.downwash.jet:RoundJetField",
                                           "params": {k: float(v) for k, v in params.items()
                                                      if k in FITTED_PARAMS}}},
                             source=cfg.source)
    jet = build_field(cfg)
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    rows = []
    for sep in separations_m:
        leader, follower = probe_bodies(sep, 0.0, 0.0, mass, g)
        mean = float(jet.mean_acceleration(leader, follower)[0, 2])
        turb = jet.turbulence(leader, follower)
        rows.append({"separation_m": float(sep), "mean_mps2": mean,
                     "half_width_m": half_magnitude_radius_m(jet.mean_acceleration, sep, mass, g),
                     "vertical_sd_mps2": float(np.sqrt(turb["axial_var_mps4"][0])),
                     "lateral_sd_mps2": float(np.sqrt(turb["lateral_var_mps4"][0])),
                     "corr_time_s": float(turb["corr_time_s"][0])})
    return rows


# -- scores ----------------------------------------------------------------------------------
def score_wake(params: dict[str, float], flights: Sequence[FlightSamples],
               rotor_radii_m: dict[str, float] | None = None) -> dict[str, Any]:
    """Per vehicle pair, the issue's targets on ``flights`` (module docstring): each figure real
    and fitted, its relative error and whether it is within the target (:data:`TARGETS`)."""
    pairs: dict[str, list[FlightSamples]] = {}
    for f in flights:
        pairs.setdefault(f.pair, []).append(f)
    out: dict[str, Any] = {}
    for pair, group in sorted(pairs.items()):
        means = [model_mean(params, f, rotor_radii_m) for f in group]
        turbs = [model_turbulence(params, f, rotor_radii_m) for f in group]
        label = np.concatenate([f.label_mps2 for f in group])
        model = np.concatenate(means)
        dp = np.concatenate([f.offset_m for f in group])
        req = np.concatenate([np.full(f.label_mps2.shape[0], f.equivalent_radius_m)
                              for f in group])
        h = np.hypot(dp[:, 0], dp[:, 1])
        core = h < CORE_RADII * req
        entry: dict[str, Any] = {"flights": sorted({f.flight for f in group}),
                                 "samples": int(label.shape[0]), "core_samples": int(core.sum())}
        # Mean vertical acceleration directly below, per separation bin.
        bins = []
        edges = np.arange(0.0, dp[:, 2].max() + SEPARATION_BIN_M, SEPARATION_BIN_M)
        for lo in edges:
            sel = core & (dp[:, 2] >= lo) & (dp[:, 2] < lo + SEPARATION_BIN_M)
            if sel.sum() < MIN_BIN_SAMPLES:
                continue
            real, fitted = float(label[sel, 2].mean()), float(model[sel, 2].mean())
            bins.append({"separation_m": [round(float(lo), 3),
                                          round(float(lo + SEPARATION_BIN_M), 3)],
                         "samples": int(sel.sum()), "real_mps2": real, "fitted_mps2": fitted,
                         "real_sd_mps2": float(label[sel, 2].std()),
                         "rel_error": (fitted - real) / abs(real) if real else float("nan")})
        entry["separation_bins"] = bins
        worst = max((abs(b["rel_error"]) for b in bins), default=float("nan"))
        entry["mean_vertical"] = {"worst_rel_error": worst,
                                  "met": bool(bins) and worst <= TARGETS["mean_vertical"]}
        # Lateral half-magnitude radius of the vertical acceleration, all depths of the pair.
        profile = lateral_profile(h, label[:, 2], model[:, 2], float(np.median(req)))
        entry["lateral_profile"] = profile
        real_hw, fit_hw = profile["real_half_width_m"], profile["fitted_half_width_m"]
        rel = (fit_hw - real_hw) / real_hw if real_hw and np.isfinite(real_hw) else float("nan")
        entry["half_width"] = {"real_m": real_hw, "fitted_m": fit_hw, "rel_error": rel,
                               "met": bool(np.isfinite(rel) and abs(rel) <= TARGETS["half_width"])}
        # Turbulence sd near the axis: each flight's residual about the mean (and its own
        # offset), less the free-air noise.
        err = label - model
        about = np.concatenate([
            centred(f.label_mps2 - m, np.hypot(f.offset_m[:, 0], f.offset_m[:, 1])
                    < CORE_RADII * f.equivalent_radius_m) for f, m in zip(group, means,
                                                                         strict=True)])
        free = np.concatenate([f.sample_noise_var_mps4 for f in group])
        axial = np.concatenate([t["axial_var_mps4"] for t in turbs])
        lateral = np.concatenate([t["lateral_var_mps4"] for t in turbs])
        for name, real_var, model_var, key in (
                ("vertical_sd", about[core, 2].var() - free[core, 2].mean(),
                 axial[core].mean() if core.any() else np.nan, "vertical_sd"),
                ("lateral_sd", 0.5 * (about[core, 0].var() + about[core, 1].var())
                 - 0.5 * (free[core, 0] + free[core, 1]).mean(),
                 lateral[core].mean() if core.any() else np.nan, "lateral_sd")):
            real_sd = float(np.sqrt(real_var)) if core.sum() >= MIN_BIN_SAMPLES \
                and real_var > 0 else float("nan")
            fit_sd = float(np.sqrt(model_var)) if np.isfinite(model_var) else float("nan")
            rel = (fit_sd - real_sd) / real_sd if np.isfinite(real_sd) else float("nan")
            entry[name] = {"real_mps2": real_sd, "fitted_mps2": fit_sd, "rel_error": rel,
                           "met": bool(np.isfinite(rel) and abs(rel) <= TARGETS[key])}
        entry["rmse_mps2"] = float(np.sqrt(np.mean(np.sum(err ** 2, axis=1))))
        entry["zero_model_rmse_mps2"] = float(np.sqrt(np.mean(np.sum(label ** 2, axis=1))))
        out[pair] = entry
    ac = autocorrelations(params, flights, rotor_radii_m)
    for pair, entry in out.items():
        if pair in ac:
            lags = np.asarray(ac[pair]["lag_s"])
            entry["autocorrelation"] = {
                f"{1000 * lag:.0f}ms": {"real": float(np.interp(lag, lags, ac[pair]["real"])),
                                        "fitted": float(np.interp(lag, lags,
                                                                  ac[pair]["model"]))}
                for lag in (0.05, 0.08)}
            entry["autocorrelation_curve"] = ac[pair]
    out_all = {"pairs": out, "targets": TARGETS}
    out_all["all_met"] = all(e[k]["met"] for e in out.values()
                             for k in ("mean_vertical", "half_width", "vertical_sd",
                                       "lateral_sd"))
    return out_all


def lateral_profile(offset_m: np.ndarray, real_mps2: np.ndarray, fitted_mps2: np.ndarray,
                    equivalent_radius_m: float) -> dict[str, Any]:
    """Binned real and fitted vertical acceleration against lateral offset (bins of a quarter
    of the leader's equivalent radius, to four), and each profile's half-magnitude radius: where
    it first falls to half its value in the innermost bin (linear between bins)."""
    width = 0.25 * equivalent_radius_m
    edges = np.arange(0.0, 4.0 * equivalent_radius_m + 1e-12, width)
    centres, real, fitted, spread, counts = [], [], [], [], []
    for lo in edges[:-1]:
        sel = (offset_m >= lo) & (offset_m < lo + width)
        if sel.sum() < MIN_BIN_SAMPLES:
            continue
        centres.append(float(lo + 0.5 * width))
        real.append(float(real_mps2[sel].mean()))
        fitted.append(float(fitted_mps2[sel].mean()))
        spread.append(float(real_mps2[sel].std()))
        counts.append(int(sel.sum()))
    return {"offset_m": centres, "real_mps2": real, "fitted_mps2": fitted,
            "real_sd_mps2": spread, "samples": counts,
            "real_half_width_m": _half_width(centres, real),
            "fitted_half_width_m": _half_width(centres, fitted)}


def _half_width(x: list[float], y: list[float]) -> float:
    if len(x) < 2 or not y[0] > 0:
        return float("nan")
    half = 0.5 * y[0]
    for i in range(1, len(x)):
        if y[i] <= half:
            return float(x[i - 1] + (x[i] - x[i - 1]) * (y[i - 1] - half) / (y[i - 1] - y[i]))
    return float("nan")
