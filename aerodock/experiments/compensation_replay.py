"""The disturbance compensations a follower can fly, replayed causally over real flight logs.

Each compensation runs over the logged flights as it would on the vehicle, at its controller's
rate, and what it leaves of the residual acceleration (the de-biased label ``a_obs - u_1:3 -
bias``, :mod:`aerodock.learning.labels`) is the disturbance the controller still has to reject:
``leftover = label - compensation`` (m/s², NED). The compensations (:data:`COMPENSATIONS`):

- ``none``: nothing subtracted (the leftover is the label);
- ``freyja``: the paper's bias observer as its flight stack publishes it
  (:class:`~aerodock.control.freyja_estimator.FreyjaBiasEstimator`), at the paper's controller
  rate, fed what it sees on a vehicle: every state message (each log sample) the position
  through Freyja's state filter (:class:`~aerodock.control.freyja_state_filter.FreyjaStateFilter`,
  when the settings have one) and the velocity it publishes; at every controller tick the
  latest command, which in a log is the acceleration the thrust explains (``u_1:3``);
- ``accel``: our accelerometer observer (:class:`~aerodock.control.accel_observer.AccelObserver`,
  ``tau`` and axes from the config) at our controller rate: at every tick the mean of the
  accelerometer and of the logged thrust over the period just flown and the attitude at its end;
  the logged per-motor thrust is taken as the thrust (no motor lag on top of it);
- ``model``: the learnt model's prediction from the state at the tick (our controller's rate);
- ``model+accel``: the model plus the accelerometer observer on what the model leaves (the
  model's prediction is the observer's feed-forward), as our controller flies them;
- ``model+freyja``: the model plus Freyja's estimator told the model's feed-forward as part of
  the command (``control.freyja_estimator_input = "command-without-feedforward"``), at the
  paper's rate. Told only the controller's command it would estimate the whole disturbance again
  and, without the closed loop to absorb it, count the model twice; this open-loop replay
  cannot represent that variant.

Causality: a tick at sample ``k`` uses samples ``<= k`` and its compensation applies to samples
``k + 1 .. k + h`` (``h`` samples per controller period): the compensation scored at a sample
uses only the samples before it (the command computed from a state message acts on the
acceleration of the next one; a one-step delay), and is held between ticks.

Constant offsets: the labels have each flight's constant bias removed (the free-air median of
the raw label; thrust-scale and accelerometer biases the paper's footnote treats as constant).
An observer reads the raw signals, so its estimate carries a constant of its own (the
accelerometer observer its bias, Freyja only the part motion capture sees); each observer's
output is offset by its own median over the flight's free-air samples, as the labels are, before
it is compared with them. That constant is the only thing not computed causally.

Time: one sample is one nominal period (the median step of the logs); a gap longer than
``max_gap_s`` splits a flight into segments, each replayed from a fresh start; the first
``warmup_s`` of each segment are not scored (Freyja's estimate ramps in over 1.5 s).

Everything is batch-first: the segments of all flights are padded to one length and run as one
batch (one batch per follower mass for the accelerometer observer, which takes one mass); the
loop is over time only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.accel_observer import AccelObserver
from aerodock.control.freyja_estimator import FreyjaBiasEstimator, FreyjaEstimatorParams
from aerodock.control.freyja_state_filter import FreyjaStateFilter, FreyjaStateFilterParams
from aerodock.control.profiles import controller_config
from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.ingest.neural_swarm import VEHICLE_MASSES_KG
from aerodock.learning.dataset import INTERACTION_RADIUS_M, Dataset
from aerodock.learning.labels import FREE_AIR_RADIUS_M, free_air_mask

COMPENSATIONS = ("none", "freyja", "accel", "model", "model+accel", "model+freyja")
"""Every compensation, in table order (see the module docstring)."""
WITH_MODEL = ("model", "model+accel", "model+freyja")
"""The compensations that need a model's prediction."""
DEFAULT_WARMUP_S = 2.0
DEFAULT_MAX_GAP_S = 0.25
REGIONS = ("interaction", "all")


@dataclass(frozen=True)
class ReplaySettings:
    """The rates and constants the compensations fly with.

    Attributes:
        paper_rate_hz: the paper's controller rate (Freyja's ``controller_rate``), Hz.
        freyja: Freyja's bias estimator's constants.
        state_filter: Freyja's state filter's constants, or None to feed the logged position
            and velocity to the estimator directly.
        ours_rate_hz: our controller's rate (``control.command_rate_hz``), Hz.
        accel_tau_s: the accelerometer observer's time constant, s.
        accel_axes: ``"down"`` (vertical only) or ``"all"``.
        warmup_s: seconds at the start of each segment left out of the scores.
    """

    paper_rate_hz: float = 50.0
    freyja: FreyjaEstimatorParams = field(default_factory=FreyjaEstimatorParams)
    state_filter: FreyjaStateFilterParams | None = field(default_factory=FreyjaStateFilterParams)
    ours_rate_hz: float = 100.0
    accel_tau_s: float = 0.08
    accel_axes: str = "down"
    warmup_s: float = DEFAULT_WARMUP_S

    @classmethod
    def from_config(cls, cfg: Config, warmup_s: float = DEFAULT_WARMUP_S) -> ReplaySettings:
        """The paper's controller profile's rates and Freyja constants, and our profile's
        rate and accelerometer observer, from ``cfg`` (:mod:`aerodock.control.profiles`)."""
        paper = controller_config(cfg, "paper").control
        ours = controller_config(cfg, "ours").control
        return cls(
            paper_rate_hz=paper.command_rate_hz,
            freyja=FreyjaEstimatorParams.from_control(paper),
            state_filter=(FreyjaStateFilterParams.from_control(paper)
                          if paper.state_filter == "freyja" else None),
            ours_rate_hz=ours.command_rate_hz, accel_tau_s=ours.accel_observer_tau_s,
            accel_axes=ours.accel_observer_axes, warmup_s=warmup_s)

    def describe(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "paper_rate_hz": self.paper_rate_hz,
            "freyja_propagation_rate_hz": self.freyja.propagation_rate_hz,
            "freyja_process_noise": list(self.freyja.process_noise),
            "freyja_measurement_noise": list(self.freyja.measurement_noise),
            "freyja_bias_limit_mps2": list(self.freyja.bias_limit_mps2),
            "freyja_state_filter": self.state_filter is not None,
            "ours_rate_hz": self.ours_rate_hz, "accel_tau_s": self.accel_tau_s,
            "accel_axes": self.accel_axes, "warmup_s": self.warmup_s,
        }


@dataclass(frozen=True, eq=False)
class ReplayFlights:
    """Flight segments padded to one length ``T``, batch-first (``n`` segments), world NED, SI.

    Attributes:
        names: the flights' names (one per flight).
        pairings: each flight's pairing, e.g. ``"small-under-large"`` (follower first).
        segment_flight: (n,) index into ``names`` of each segment.
        valid: (n, T) real samples (False: padding).
        t_s: (n, T) time since the segment's first sample.
        p_m, v_mps: (n, T, 3) the follower's logged position and velocity.
        rot: (n, T, 3, 3) the follower's attitude, body to world.
        accel_mps2: (n, T, 3) its observed (kinematic) acceleration.
        thrust_n: (n, T) its logged collective thrust.
        cmd_mps2: (n, T, 3) the acceleration the thrust explains (``u_1:3``).
        label_mps2: (n, T, 3) the de-biased label.
        prediction_mps2: (n, T, 3) the model's prediction at each sample (zeros without one).
        interaction: (n, T) follower below the leader within the lateral radius.
        free_air: (n, T) follower out of the leader's wake (the labels' free-air samples).
        mass_kg: (n,) the follower's mass.
        gravity_mps2: gravity.
        dt_s: the nominal sample period, s.
        has_model: whether ``prediction_mps2`` is a model's.
    """

    names: tuple[str, ...]
    pairings: tuple[str, ...]
    segment_flight: np.ndarray
    valid: np.ndarray
    t_s: np.ndarray
    p_m: np.ndarray
    v_mps: np.ndarray
    rot: np.ndarray
    accel_mps2: np.ndarray
    thrust_n: np.ndarray
    cmd_mps2: np.ndarray
    label_mps2: np.ndarray
    prediction_mps2: np.ndarray
    interaction: np.ndarray
    free_air: np.ndarray
    mass_kg: np.ndarray
    gravity_mps2: float
    dt_s: float
    has_model: bool = False

    @property
    def n(self) -> int:
        """Number of segments."""
        return int(self.valid.shape[0])


def vehicle_type(mass_kg: float | None) -> str:
    """``"small"``/``"large"`` for a Neural-Swarm vehicle's mass, else the mass in kg."""
    if mass_kg is None:
        return "unknown"
    for name, mass in VEHICLE_MASSES_KG.items():
        if abs(float(mass_kg) - mass) < 1e-9:
            return name
    return f"{float(mass_kg):.3g} kg"


def pairing(log: FlightLog) -> str:
    """The follower's and the leader's vehicle types: ``"<follower>-under-<leader>"``."""
    return (f"{vehicle_type(log.meta.get('follower_mass_kg'))}-under-"
            f"{vehicle_type(log.meta.get('leader_mass_kg'))}")


def _segments(t_s: np.ndarray, max_gap_s: float) -> list[tuple[int, int]]:
    """``[start, stop)`` sample ranges between gaps longer than ``max_gap_s``."""
    cuts = np.flatnonzero(np.diff(t_s) > max_gap_s) + 1
    edges = [0, *cuts.tolist(), len(t_s)]
    return [(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]


def replay_flights(
    logs: Sequence[FlightLog],
    ds: Dataset,
    prediction_mps2: np.ndarray | None = None,
    *,
    lateral_radius_m: float = INTERACTION_RADIUS_M,
    free_air_radius_m: float = FREE_AIR_RADIUS_M,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
) -> ReplayFlights:
    """The flights ``logs`` as padded segments, with ``ds``'s labels (and a model's prediction).

    Args:
        logs: the flights, in the order of ``ds``'s flights.
        ds: their data set (:func:`~aerodock.learning.dataset.build_dataset` of ``logs``), every
            sample valid: it gives the de-biased labels and the interaction region.
        prediction_mps2: (ds.n, 3) a model's prediction at each sample of ``ds``, or None.
        lateral_radius_m: the interaction region's radius, m.
        free_air_radius_m: the free-air radius the labels were de-biased with, m.
        max_gap_s: a longer gap between two samples splits a flight into segments.

    Raises:
        ValueError: ``ds`` does not hold exactly the samples of ``logs``, flights that disagree
            on gravity or lack the follower's mass, or a bad argument.
    """
    logs = list(logs)
    if not logs:
        raise ValueError("no flights to replay")
    if not max_gap_s > 0:
        raise ValueError(f"max_gap_s must be positive, got {max_gap_s}")
    counts = np.bincount(ds.flight_id, minlength=len(logs))
    if len(counts) != len(logs) or any(int(c) != lg.n_samples for c, lg in zip(counts, logs)):
        raise ValueError("the data set does not hold every sample of the flights (flights with "
                         "invalid samples cannot be replayed)")
    if prediction_mps2 is not None and np.shape(prediction_mps2) != (ds.n, 3):
        raise ValueError(f"prediction has shape {np.shape(prediction_mps2)}, expected {(ds.n, 3)}")
    inter_all = ds.interaction_mask(lateral_radius_m)
    pieces: list[dict[str, np.ndarray]] = []
    seg_flight: list[int] = []
    steps: list[np.ndarray] = []
    gravity = {float(lg.meta.get("gravity_mps2", 9.81)) for lg in logs}
    if len(gravity) != 1:
        raise ValueError(f"the flights disagree on gravity ({sorted(gravity)} m/s²)")
    for i, log in enumerate(logs):
        rows = np.flatnonzero(ds.flight_id == i)
        if not np.allclose(ds.t_s[rows], log.t_s):
            raise ValueError(f"{log.name}: the data set's flight {i} is another flight")
        whole = {
            "t_s": log.t_s, "p_m": log.follower_pos_m, "v_mps": log.follower_vel_mps,
            "rot": quat_to_rotmat(log.follower_quat), "accel_mps2": log.follower_obs_accel_mps2,
            "thrust_n": log.follower_thrust_n, "cmd_mps2": log.follower_cmd_accel_mps2,
            "label_mps2": ds.y[rows],
            "prediction_mps2": (np.zeros((len(rows), 3)) if prediction_mps2 is None
                                else np.asarray(prediction_mps2, float)[rows]),
            "interaction": inter_all[rows], "free_air": free_air_mask(log, free_air_radius_m),
            "mass_kg": np.full(log.n_samples, float(log.meta.get("follower_mass_kg", np.nan))),
        }
        if not np.isfinite(whole["mass_kg"][0]):
            raise ValueError(f"{log.name}: the log does not give the follower's mass")
        steps.append(np.diff(log.t_s))
        for a, b in _segments(log.t_s, max_gap_s):
            piece = {k: v[a:b] for k, v in whole.items()}
            piece["t_s"] = piece["t_s"] - piece["t_s"][0]
            pieces.append(piece)
            seg_flight.append(i)
    dt = float(np.median(np.concatenate(steps))) if sum(len(s) for s in steps) else 0.01
    length = max(len(p["t_s"]) for p in pieces)

    def pad(key: str) -> np.ndarray:  # edge padding: the observers see no jump
        arrs = [p[key] for p in pieces]
        out = np.empty((len(arrs), length, *arrs[0].shape[1:]), dtype=arrs[0].dtype)
        for j, arr in enumerate(arrs):
            out[j, :len(arr)] = arr
            out[j, len(arr):] = arr[-1]
        return out

    valid = np.zeros((len(pieces), length), dtype=bool)
    for j, p in enumerate(pieces):
        valid[j, :len(p["t_s"])] = True
    return ReplayFlights(
        names=tuple(lg.name for lg in logs), pairings=tuple(pairing(lg) for lg in logs),
        segment_flight=np.asarray(seg_flight, dtype=np.int64), valid=valid,
        t_s=pad("t_s"), p_m=pad("p_m"), v_mps=pad("v_mps"), rot=pad("rot"),
        accel_mps2=pad("accel_mps2"), thrust_n=pad("thrust_n"), cmd_mps2=pad("cmd_mps2"),
        label_mps2=pad("label_mps2"), prediction_mps2=pad("prediction_mps2"),
        interaction=pad("interaction") & valid, free_air=pad("free_air") & valid,
        mass_kg=pad("mass_kg")[:, 0], gravity_mps2=gravity.pop(),
        dt_s=dt, has_model=prediction_mps2 is not None,
    )


@dataclass(frozen=True, eq=False)
class Replayed:
    """One compensation over the segments: its feed-forward and observer parts (n, T, 3), each
    held over the controller period after the tick that computed it, and its rate."""

    feedforward_mps2: np.ndarray
    observer_mps2: np.ndarray
    rate_hz: float | None


def samples_per_period(rate_hz: float, dt_s: float) -> int:
    """Samples of period ``dt_s`` per controller period at ``rate_hz`` (at least one)."""
    if not (rate_hz > 0 and dt_s > 0):
        raise ValueError(f"rate and sample period must be positive, got {rate_hz}, {dt_s}")
    return max(1, int(round(1.0 / (rate_hz * dt_s))))


def hold_ticks(at_tick: np.ndarray, h: int) -> np.ndarray:
    """Values computed at ticks ``k = 0, h, 2h, ...`` (``at_tick[:, k]``; the rest ignored) as
    applied: to samples ``k + 1 .. k + h``; sample 0 gets zeros. Shape (n, T, ...) kept."""
    length = at_tick.shape[1]
    out = np.zeros_like(at_tick)
    j = np.arange(1, length)
    out[:, 1:] = at_tick[:, ((j - 1) // h) * h]
    return out


def _period_mean(x: np.ndarray, k: int, h: int) -> np.ndarray:
    """Mean of ``x[:, k - h + 1 .. k]`` (the period that ends at sample ``k``)."""
    return x[:, max(0, k - h + 1):k + 1].mean(axis=1)


def replay_freyja(flights: ReplayFlights, settings: ReplaySettings,
                  input_feedforward_mps2: np.ndarray | None = None) -> np.ndarray:
    """Freyja's published bias estimate at each tick of the paper's rate (n, T, 3), held.

    ``input_feedforward_mps2`` (n, T, 3), when given, is added to the command Freyja is told
    (a feed-forward counted as known); it is read at the ticks only.
    """
    n, length = flights.valid.shape
    dt = flights.dt_s
    h = samples_per_period(settings.paper_rate_hz, dt)
    est = FreyjaBiasEstimator(n, dt, settings.freyja)
    sf = None if settings.state_filter is None else FreyjaStateFilter(n, dt, settings.state_filter)
    p, v = flights.p_m, flights.v_mps
    if sf is not None:
        sf.reset(p[:, 0], v[:, 0])
    est.reset(p[:, 0], v[:, 0])
    command = flights.cmd_mps2 if input_feedforward_mps2 is None else (
        flights.cmd_mps2 + input_feedforward_mps2)
    at_tick = np.zeros((n, length, 3))
    for k in range(length):
        pm, vm = sf.measure(p[:, k]) if sf is not None else (p[:, k], v[:, k])
        est.measure(pm, vm)  # every state message
        if k % h == 0:  # a controller tick: the estimate it flies, then the command it hands over
            at_tick[:, k] = est.bias_mps2
            est.set_input(command[:, k])
    return hold_ticks(at_tick, h)


def replay_accel(flights: ReplayFlights, settings: ReplaySettings,
                 feedforward_mps2: np.ndarray | None = None) -> np.ndarray:
    """The accelerometer observer's estimate at each tick of our rate (n, T, 3), held.

    ``feedforward_mps2`` (n, T, 3): the model's prediction at each sample; the tick at ``k``
    flies ``feedforward_mps2[:, k]``, and the observer estimates what it leaves.
    """
    n, length = flights.valid.shape
    h = samples_per_period(settings.ours_rate_hz, flights.dt_s)
    ff = np.zeros((n, length, 3)) if feedforward_mps2 is None else feedforward_mps2
    at_tick = np.zeros((n, length, 3))
    for mass in np.unique(flights.mass_kg):  # the observer takes one mass: one batch per mass
        idx = np.flatnonzero(flights.mass_kg == mass)
        obs = AccelObserver(len(idx), h * flights.dt_s, settings.accel_tau_s, 0.0, float(mass),
                            flights.gravity_mps2, settings.accel_axes)
        obs.reset(flights.thrust_n[idx, 0])
        accel, thrust = flights.accel_mps2[idx], flights.thrust_n[idx]
        rot, ff_g = flights.rot[idx], ff[idx]
        for k in range(0, length, h):
            if k > 0:  # fold in the period just flown under the last tick's feed-forward
                obs.commanded(_period_mean(thrust, k, h), ff_g[:, k - h])
                obs.update(_period_mean(accel, k, h), rot[:, k])
            at_tick[idx, k] = obs.residual_mps2
    return hold_ticks(at_tick, h)


def replay(flights: ReplayFlights, settings: ReplaySettings,
           compensations: Sequence[str] = COMPENSATIONS) -> dict[str, Replayed]:
    """Each of ``compensations`` replayed over ``flights`` (see the module docstring).

    Raises:
        ValueError: an unknown compensation, or one with a model on flights without one.
    """
    unknown = [c for c in compensations if c not in COMPENSATIONS]
    if unknown:
        raise ValueError(f"unknown compensation {unknown[0]!r} (expected one of "
                         f"{', '.join(COMPENSATIONS)})")
    if not flights.has_model and any(c in WITH_MODEL for c in compensations):
        raise ValueError("the model's compensations need a model's prediction")
    dt = flights.dt_s
    zero = np.zeros_like(flights.label_mps2)
    pred = flights.prediction_mps2
    h_paper = samples_per_period(settings.paper_rate_hz, dt)
    h_ours = samples_per_period(settings.ours_rate_hz, dt)
    out: dict[str, Replayed] = {}
    for name in compensations:
        if name == "none":
            out[name] = Replayed(zero, zero, None)
        elif name == "freyja":
            out[name] = Replayed(zero, replay_freyja(flights, settings), settings.paper_rate_hz)
        elif name == "model+freyja":
            out[name] = Replayed(hold_ticks(pred, h_paper),
                                 replay_freyja(flights, settings, pred), settings.paper_rate_hz)
        elif name == "accel":
            out[name] = Replayed(zero, replay_accel(flights, settings), settings.ours_rate_hz)
        elif name == "model":
            out[name] = Replayed(hold_ticks(pred, h_ours), zero, settings.ours_rate_hz)
        else:  # model+accel
            out[name] = Replayed(hold_ticks(pred, h_ours), replay_accel(flights, settings, pred),
                                 settings.ours_rate_hz)
    return out


def scored_mask(flights: ReplayFlights, warmup_s: float) -> np.ndarray:
    """(n, T) the samples scored: real, and at least ``warmup_s`` into their segment."""
    return flights.valid & (flights.t_s >= warmup_s)


def observer_offsets(flights: ReplayFlights, observer_mps2: np.ndarray,
                     scored: np.ndarray) -> np.ndarray:
    """(n_flights, 3) each flight's constant offset of an observer's output: its median over the
    flight's scored free-air samples (the pooled median where a flight has none; 0 if no flight
    has any)."""
    fa = flights.free_air & scored
    pooled = observer_mps2[fa]
    fallback = np.median(pooled, axis=0) if len(pooled) else np.zeros(3)
    out = np.tile(fallback, (len(flights.names), 1))
    for i in range(len(flights.names)):
        mine = fa & (flights.segment_flight == i)[:, None]
        if mine.any():
            out[i] = np.median(observer_mps2[mine], axis=0)
    return out


def leftovers(flights: ReplayFlights, replayed: dict[str, Replayed],
              scored: np.ndarray) -> dict[str, np.ndarray]:
    """``label - compensation`` (n, T, 3) of each replayed compensation, each observer's output
    offset by its free-air median (:func:`observer_offsets`)."""
    out = {}
    for name, rep in replayed.items():
        offset = observer_offsets(flights, rep.observer_mps2, scored)[flights.segment_flight]
        comp = rep.feedforward_mps2 + rep.observer_mps2 - offset[:, None, :]
        out[name] = flights.label_mps2 - comp
    return out


def _rms(x: np.ndarray) -> float | None:
    return float(np.sqrt(np.mean(x))) if len(x) else None


def _removed(rms: float | None, base: float | None) -> float | None:
    return None if rms is None or not base else 1.0 - rms / base


def score(flights: ReplayFlights, left: dict[str, np.ndarray], scored: np.ndarray
          ) -> dict[str, Any]:
    """The disturbance each compensation leaves, per pairing (and ``"all"``) and region.

    Returns:
        ``{group: {region: {"n", "compensations": {name: {"vertical_rms_mps2",
        "planar_rms_mps2", "vertical_removed", "planar_removed"}}}}}``, the groups ``"all"``
        and each pairing, the regions ``"interaction"`` and ``"all"``; ``*_removed`` is the
        fraction of the ``none`` RMS removed (None without ``none`` or data).
    """
    seg_pairing = np.array([flights.pairings[i] for i in flights.segment_flight])
    groups = {"all": np.ones(flights.n, dtype=bool)}
    for name in sorted(set(flights.pairings)):
        groups[name] = seg_pairing == name
    out: dict[str, Any] = {}
    for group, segs in groups.items():
        out[group] = {}
        for region in REGIONS:
            mask = scored & segs[:, None]
            if region == "interaction":
                mask = mask & flights.interaction
            entry: dict[str, Any] = {"n": int(mask.sum()), "compensations": {}}
            for name, e in left.items():
                sel = e[mask]
                entry["compensations"][name] = {
                    "vertical_rms_mps2": _rms(sel[:, 2] ** 2),
                    "planar_rms_mps2": _rms(sel[:, 0] ** 2 + sel[:, 1] ** 2),
                }
            base = entry["compensations"].get("none")
            for rec in entry["compensations"].values():
                for axis in ("vertical", "planar"):
                    rec[f"{axis}_removed"] = _removed(
                        rec[f"{axis}_rms_mps2"], base and base[f"{axis}_rms_mps2"])
            out[group][region] = entry
    return out

