"""Identifying the default jet (:class:`aerodock.downwash.jet.RoundJetField`) from flight logs.

The jet's parameters are dimensionless, so the fit on one pair of vehicles gives the wake of any
other (the world's rotor sizes and the leader's thrust set the scales, by momentum theory):

- **Mean** (``MEAN_PARAMS``): the width at the rotor plane and its growth, the ingest law's
  coefficient and exponent, the planar part; by least squares (``scipy.optimize.least_squares``)
  of the follower's de-biased residual acceleration, vertical and radial, against the jet's mean
  at every logged sample in the interaction region (the logged leader and follower states: the
  leader's thrust, both attitudes, both velocities). A vehicle whose rotor radius the logs do not
  know may have it estimated alongside (``estimate_rotor_for``).
- **Torque** (``TORQUE_PARAMS``, with ``torque`` labels: :mod:`aerodock.identify.torque_labels`):
  where the logs carry the torque the follower's motors answer, the jet's inward disk torque is
  fitted beside the force, in the same least squares, and the share of the force on the body
  (``body_area_ratio``, else the world's assumption) with it: the force alone hardly tells the
  body's share from the disks', the torque does.
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

The flights are read into samples by :mod:`aerodock.identify.flights`; a fit is scored
against flights by :mod:`aerodock.identify.wake_score`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cache, wraps
from typing import Any, Protocol

import numpy as np

from aerodock.config import load_config
from aerodock.downwash import field_kwargs
from aerodock.downwash.jet import CONTRACTED_WIDTH0_RATIO, RoundJetField
from aerodock.identify.flights import (
    GRAVITY_MPS2,
    LAGS,
    FlightSamples,
    WakeFitError,
    autocovariance,
)


class TorqueResidual(Protocol):
    """What the fit needs of one flight's torque labels
    (:class:`aerodock.identify.torque_labels.TorqueLabels` are such)."""

    def residual_mps2(self, model_body_nm: np.ndarray) -> np.ndarray:
        """(m,) the real torque less the model's (``model_body_nm``: (m, 3) N·m, body FRD), as
        an acceleration (m/s²)."""
        ...


MEAN_PARAMS = ("width0_ratio", "spread_rate", "ingest_coeff", "ingest_exponent", "planar_ratio")
TURBULENCE_PARAMS = ("turb_vertical", "turb_lateral", "turb_length_ratio", "turb_time_ratio")
FITTED_PARAMS = MEAN_PARAMS + TURBULENCE_PARAMS
TORQUE_PARAMS = ("body_area_ratio",)
"""Fitted too when the fit sees the torque (a world's assumption otherwise)."""
TORQUE_START = {"body_area_ratio": 0.2}
"""Where the fit with the torque starts them (0.2: a Crazyflie's board over its disks), whatever
the world's value: the fit of given flights does not depend on the defaults it replaces."""
WORLD_PARAMS = ("body_area_ratio", "body_drag_coeff", "disk_torque_gain")
"""The jet's parameters a world sets that the fit does not (a scored config's, where given)."""
# Start and bounds of each parameter (the start is momentum theory's contracted wake with a
# round jet's spread; the bounds keep the jet physical).
START = {"width0_ratio": CONTRACTED_WIDTH0_RATIO, "spread_rate": 0.1, "ingest_coeff": 0.5,
         "ingest_exponent": 1.5, "planar_ratio": 0.0, "turb_vertical": 0.25, "turb_lateral": 0.08,
         "turb_length_ratio": 0.5, "turb_time_ratio": 2.0}
OTHER_START = {"width0_ratio": 1.0, "spread_rate": 0.0, "ingest_coeff": 1.0, "ingest_exponent": 1.0}
"""The mean's second start, on the far side of its valley from :data:`START` (no spread, wider,
linear ingestion): without ``start``, :func:`fit_mean` runs from both and keeps the lower cost.
The valley holds more than one floor: on the shared flights, from :data:`START`, an Intel Xeon
with AVX-512 settles at ``width0_ratio`` 0.7353 (cost 6837.511) where the project's AMD EPYC
reached 0.7327 (6837.431), as 12 other starts tried on the Intel one do. A default fit runs its
least squares twice (1.6 s -> 2.4 s on the shared flights)."""
BOUNDS = {"width0_ratio": (0.1, 5.0), "spread_rate": (0.0, 1.0), "ingest_coeff": (1e-3, 10.0),
          "ingest_exponent": (0.3, 3.0), "planar_ratio": (-1.0, 1.0),
          "turb_vertical": (0.0, 3.0), "turb_lateral": (0.0, 3.0),
          "turb_length_ratio": (0.05, 20.0), "turb_time_ratio": (0.05, 100.0),
          "body_area_ratio": (0.0, 2.0)}
ROTOR_BOUNDS_M = (0.005, 0.2)
CORE_RADII = 1.0  # "directly below": within one leader equivalent radius of its axis
MIN_BIN_SAMPLES = 30


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
    torque_flights: list[str] = field(default_factory=list)
    """The fitted flights whose logged torque the fit saw (none: a fit of the force alone)."""
    torque_rms_mps2: float = float("nan")
    """The torque residual's RMS over those flights, as the fit weighs it (m/s²: a torque over
    the follower's mass and half diagonal)."""

    @property
    def keys(self) -> tuple[str, ...]:
        """The parameters this fit identified: :data:`FITTED_PARAMS`, and with the torque
        :data:`TORQUE_PARAMS`."""
        return FITTED_PARAMS + (TORQUE_PARAMS if self.torque_flights else ())

    def field_params(self) -> dict[str, float]:
        """The ``[downwash.params]`` values the fit identified."""
        return {k: float(self.params[k]) for k in self.keys}



# -- the model at the samples ---------------------------------------------------------------
def build_jet(params: dict[str, float], geometry: dict[str, float]) -> RoundJetField:
    """The jet with ``params`` (fitted keys, and :data:`WORLD_PARAMS` where given) between the
    vehicles of ``geometry``; every other parameter (the bar's, the air's) is the shipped
    default's (``defaults.toml``, their one home)."""
    kwargs = {k: v for k, v in params.items() if k in FITTED_PARAMS or k in WORLD_PARAMS}
    return RoundJetField(**{
        **_default_jet_kwargs(), **kwargs,
        "leader_rotor_radius_m": geometry["leader_rotor_radius_m"],
        "leader_n_rotors": int(geometry["leader_n_rotors"]),
        "follower_rotor_radius_m": geometry["follower_rotor_radius_m"],
        "follower_n_rotors": int(geometry["follower_n_rotors"]),
        "follower_diagonal_m": geometry["follower_diagonal_m"], "gravity_mps2": GRAVITY_MPS2})


@cache
def _default_jet_kwargs() -> dict[str, Any]:
    """The default jet's keyword arguments under the shipped defaults (read once)."""
    return field_kwargs(load_config(), RoundJetField)


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


def labels_for(torque: Mapping[str, TorqueResidual] | None, name: str) -> TorqueResidual | None:
    """The torque labels of the flight ``name`` (a bootstrap's copy, ``NAME#j``, has its
    original's)."""
    if not torque:
        return None
    return torque.get(name.split("#", 1)[0])


def model_torque(params: dict[str, float], flight: FlightSamples,
                 rotor_radii_m: dict[str, float] | None = None) -> np.ndarray:
    """(m, 3) the jet's mean torque on the follower's disks at the flight's samples, N·m, body
    FRD."""
    jet = build_jet(params, geometry_with(flight, rotor_radii_m or {}))
    return jet.mean_disk_torque_nm(flight.leader, flight.follower)


def torque_rms(params: dict[str, float], flights: Sequence[FlightSamples],
               torque: Mapping[str, TorqueResidual] | None,
               rotor_radii_m: dict[str, float] | None = None) -> float:
    """The RMS of the torque residual (:meth:`TorqueResidual.residual_mps2`) over the flights
    with labels, m/s² (nan: none has them)."""
    parts = [lab.residual_mps2(model_torque(params, f, rotor_radii_m))
             for f in flights if (lab := labels_for(torque, f.name)) is not None]
    return float(np.sqrt(np.mean(np.concatenate(parts) ** 2))) if parts else float("nan")


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
def serial_blas(fit: Callable[..., Any]) -> Callable[..., Any]:
    """``fit`` run with one BLAS thread: a threaded BLAS sums in another order, and one run of
    the mean's least squares, in its flat valley, followed that last bit elsewhere (``width0_ratio``
    0.7323 with two threads, 0.7353 with one, before the fit settled its least squares:
    :func:`settled_least_squares`)."""

    @wraps(fit)
    def one_thread(*args: Any, **kwargs: Any) -> Any:
        import scipy.optimize  # noqa: F401  (SciPy's own BLAS loaded first, so it is limited too)
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1, user_api="blas"):
            return fit(*args, **kwargs)

    return one_thread


SETTLE_RTOL = 1e-9
"""A fit's least squares is restarted from its result until a restart lowers the cost by less
than this fraction (:func:`settled_least_squares`)."""
SETTLE_RESTARTS = 10
"""At most this many restarts (four settle the shared flights' fit)."""


def settled_least_squares(fun: Callable[[np.ndarray], np.ndarray], x0: Sequence[float],
                          **kwargs: Any) -> Any:
    """``scipy.optimize.least_squares(fun, x0, **kwargs)``, restarted from its result until a
    restart lowers the cost by less than :data:`SETTLE_RTOL` (at most :data:`SETTLE_RESTARTS`
    times). In the mean's flat valley (width, spread and coefficient trade off) one run stops
    where its step scales lead it, and that follows the machine's rounding: on the shared flights
    one run stopped at ``width0_ratio`` 0.7353 on one processor and 0.7253 on another (cost
    6837.51 and 6837.71); restarted, both settled at 6837.43 there. A restart does not leave
    every floor: an AVX-512 processor stays at 0.7353 (6837.511) however it is restarted or
    however tight the tolerances, so :func:`fit_mean` also starts from :data:`OTHER_START`."""
    from scipy.optimize import least_squares

    result = least_squares(fun, x0, **kwargs)
    for _ in range(SETTLE_RESTARTS):
        again = least_squares(fun, result.x, **kwargs)
        settled = again.cost >= result.cost * (1.0 - SETTLE_RTOL)
        if again.cost <= result.cost:
            result = again
        if settled:
            break
    return result


@serial_blas
def fit_mean(flights: Sequence[FlightSamples], start: dict[str, float] | None = None,
             estimate_rotor_for: Sequence[str] = (),
             rotor_start_m: dict[str, float] | None = None,
             torque: Mapping[str, TorqueResidual] | None = None,
             ) -> tuple[dict[str, float], dict[str, float], float]:
    """Least squares of the de-biased residual (vertical and radial) against the jet's mean;
    with ``torque`` (labels by flight name, :func:`~aerodock.identify.torque_labels.
    torque_labels`), of the inward torque too, and :data:`TORQUE_PARAMS` are fitted alongside.

    Returns:
        ``(params, rotor_radii_m, rms)`` (the start: ``start``'s parameters, else both
        :data:`START` and :data:`OTHER_START`, the lower cost kept; ``rotor_start_m``'s radii,
        else the logs'): the mean parameters (and
        with ``torque`` the torque's), the estimated rotor radii of
        ``estimate_rotor_for`` (vehicle ids), and the vertical residual's RMS, m/s² (each
        vehicle pair weighs the same in the fit).
    """
    starts = [START, {**START, **OTHER_START}] if start is None else [{**START, **start}]
    rotors = list(estimate_rotor_for)
    for vid in rotors:
        if not any(vid in f.vehicles.values() for f in flights):
            raise WakeFitError(f"--estimate-rotor {vid}: no log has a vehicle {vid!r}")
    labels = [labels_for(torque, f.name) for f in flights]
    names = MEAN_PARAMS + (TORQUE_PARAMS if any(x is not None for x in labels) else ())
    radii0 = [(rotor_start_m or {}).get(v) or _logged_radius(flights, v) for v in rotors]
    low = [BOUNDS[k][0] for k in names] + [ROTOR_BOUNDS_M[0]] * len(rotors)
    high = [BOUNDS[k][1] for k in names] + [ROTOR_BOUNDS_M[1]] * len(rotors)
    x0s = [np.clip([s[k] if k in s else TORQUE_START[k] for k in names] + radii0, low, high)
           for s in starts]
    units = [_radial_unit(f.offset_m) for f in flights]
    # Each vehicle pair weighs the same, however many samples its flights hold.
    counts: dict[str, int] = {}
    for f in flights:
        counts[f.pair] = counts.get(f.pair, 0) + f.label_mps2.shape[0]
    total = sum(counts.values())
    weights = [np.sqrt(total / (len(counts) * counts[f.pair])) for f in flights]
    fixed = {k: v for k, v in starts[0].items() if k not in names}

    def unpack(x: np.ndarray) -> tuple[dict[str, float], dict[str, float]]:
        params = {**fixed, **dict(zip(names, x[:len(names)], strict=True))}
        return params, dict(zip(rotors, x[len(names):], strict=True))

    def residual(x: np.ndarray) -> np.ndarray:
        params, radii = unpack(x)
        parts = []
        for f, unit, w, lab in zip(flights, units, weights, labels, strict=True):
            jet = build_jet(params, geometry_with(f, radii))  # the force's and the torque's
            err = f.label_mps2 - jet.mean_acceleration(f.leader, f.follower)
            parts.append(w * err[:, 2])
            parts.append(w * (err[:, 0] * unit[:, 0] + err[:, 1] * unit[:, 1]))
            if lab is not None:  # the torque, weighed as the force is
                parts.append(w * lab.residual_mps2(
                    jet.mean_disk_torque_nm(f.leader, f.follower)))
        return np.concatenate(parts)

    result = min((settled_least_squares(residual, x0, bounds=(low, high), x_scale="jac")
                  for x0 in x0s), key=lambda r: r.cost)
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


@serial_blas
def fit_turbulence(params: dict[str, float], flights: Sequence[FlightSamples],
                   rotor_radii_m: dict[str, float] | None = None) -> dict[str, float]:
    """The turbulence parameters, given the mean ones: the vertical intensity and the disks'
    shared share (length ratio) from the vertical spread per pair and offset band, the lateral
    intensity from the lateral spread, the correlation time from the autocorrelation."""
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
    res = settled_least_squares(vertical, np.clip(x0, low, high), bounds=(low, high),
                                x_scale="jac")
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
        cov = autocovariance(entry["parts"])
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


@serial_blas
def fit_correlation_time(params: dict[str, float], flights: Sequence[FlightSamples],
                         rotor_radii_m: dict[str, float] | None = None) -> float:
    """``turb_time_ratio`` of the real vertical autocorrelation near the axis at lags 10-80 ms
    (:func:`autocorrelations`, all pairs together), read as a fast exponential (the jet's
    turbulence, its correlation time ``turb_time_ratio * b / w_c`` at each sample) on a
    plateau: each pair's ``A exp(-lag / tau) + (1 - A)``, where the plateau ``1 - A`` is what
    varies more slowly than 80 ms (the mean's own error along a pass; the model does not read it
    as turbulence's time scale)."""
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
    res = settled_least_squares(residual, x0, bounds=(low, high))
    return float(np.exp(res.x[0]))


def fit_wake(flights: Sequence[FlightSamples], *, estimate_rotor_for: Sequence[str] = (),
             bootstrap: int = 0, seed: int = 0,
             progress: Callable[[int, int], None] | None = None,
             torque: Mapping[str, TorqueResidual] | None = None) -> WakeFit:
    """The whole fit: mean (with ``torque``'s labels, the torque too: :func:`fit_mean`), then
    turbulence, then (``bootstrap`` > 0) the spread of every parameter over refits on flights
    resampled with replacement.

    Raises:
        WakeFitError: no flights.
    """
    flights = list(flights)
    if not flights:
        raise WakeFitError("no flights to fit")
    mean, radii, rms = fit_mean(flights, estimate_rotor_for=estimate_rotor_for, torque=torque)
    turb = fit_turbulence(mean, flights, radii)
    params = {**mean, **turb}
    seen = sorted({f.flight for f in flights if labels_for(torque, f.name) is not None})
    fit = WakeFit(params=params, rotor_radii_m=radii, flights=sorted({f.flight for f in flights}),
                  samples=int(sum(f.label_mps2.shape[0] for f in flights)), mean_rms_mps2=rms,
                  turbulence_bins=turbulence_bins(params, flights, radii),
                  autocorrelation=autocorrelations(params, flights, radii),
                  torque_flights=seen,
                  torque_rms_mps2=torque_rms(params, flights, torque, radii))
    if bootstrap > 0:
        fit.bootstrap_draws = _bootstrap(flights, fit, estimate_rotor_for, bootstrap, seed,
                                         progress, torque)
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
               torque: Mapping[str, TorqueResidual] | None = None) -> list[dict[str, float]]:
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
                                      rotor_start_m=fit.rotor_radii_m, torque=torque)
            turb = fit_turbulence({**fit.params, **mean}, sample, radii)
        except (WakeFitError, ValueError):
            continue
        draw = {k: v for k, v in {**mean, **turb}.items() if k in fit.keys}
        draw.update({f"rotor_radius_m[{k}]": v for k, v in radii.items()})
        draws.append(draw)
        if progress:
            progress(run + 1, runs)
    return draws
