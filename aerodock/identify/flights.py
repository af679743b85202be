"""The wake fit's samples: each flight log's de-biased labels in the interaction region below
its leader, with the follower vehicle's free-air noise (:func:`prepare_flights`).

The labels' own noise and bias are accounted for (:mod:`aerodock.learning.labels`): each
flight's residual is de-biased by its free-air median (flights without free-air samples borrow
their follower vehicle's other flights'), and the free-air variance (and autocovariance) of each
follower vehicle's residual about that bias is kept for the fit to subtract
(:mod:`aerodock.identify.wake_fit`). The leader's logged thrust is scaled so that its flight
median is its weight.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.learning.labels import estimate_biases, free_air_mask, raw_labels, valid_mask

GRAVITY_MPS2 = 9.81
GEOMETRY_KEYS = ("leader_rotor_radius_m", "leader_n_rotors", "follower_rotor_radius_m",
                 "follower_n_rotors", "follower_diagonal_m", "leader_mass_kg", "follower_mass_kg")
REGION_RADII = 6.0  # the interaction region: horizontally within 6 leader equivalent radii
LAGS = 9  # autocorrelation lags 0..8 (0-80 ms at 100 Hz)


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
            free_auto = autocovariance(auto_parts)
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


def autocovariance(parts: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
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

