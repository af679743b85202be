"""The labels' own noise against the follower's speed, and the wake's turbulence read above it.

The wake fit (:mod:`aerodock.identify.wake_fit`) reads the turbulence as the spread of a
flight's residual near the leader's axis less the follower vehicle's free-air label variance,
pooled over all its free-air samples. On the real swap flights that noise grows with the
follower's speed (its own manoeuvres: at rest 0.12-0.13 m/s² sideways, at 0.5-0.7 m/s 0.17-0.27),
and the follower crosses the wake at 0.2-1 m/s while most free-air samples are at rest. So the
pooled noise is too small where the turbulence is read, and what is left over is read as
turbulence. This module bins the free-air noise by speed (:func:`noise_by_speed`) and reads the
turbulence with each sample's own noise (:func:`speed_matched_turbulence`), beside the pooled
reading, with a bootstrap over flights. :func:`with_speed_noise` gives the fit itself each
sample's noise (``aerodock field fit --noise speed``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.identify.flights import REGION_RADII, FlightSamples, WakeFitError
from aerodock.identify.wake_fit import CORE_RADII, centred, model_mean, model_turbulence
from aerodock.learning.labels import free_air_mask, raw_labels

SPEED_EDGES_MPS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0, np.inf)
MIN_NOISE_SAMPLES = 30


@dataclass(frozen=True)
class NoiseTable:
    """One follower vehicle's free-air label variance per axis (NED) by its speed."""

    edges_mps: tuple[float, ...]
    var_mps4: np.ndarray
    """(bins, 3); a bin with fewer than ``MIN_NOISE_SAMPLES`` samples takes the nearest slower
    bin's (or, for the slowest, the nearest faster one's)."""
    samples: np.ndarray
    """(bins,) free-air samples in each bin."""

    def at(self, speed_mps: np.ndarray) -> np.ndarray:
        """(m, 3) the noise variance at each speed."""
        b = np.clip(np.digitize(speed_mps, self.edges_mps) - 1, 0, len(self.edges_mps) - 2)
        return self.var_mps4[b]


def noise_by_speed(logs: Sequence[FlightLog], edges_mps: Sequence[float] = SPEED_EDGES_MPS,
                   ) -> dict[str, NoiseTable]:
    """Per follower vehicle id, its free-air label variance binned by its speed: each flight's
    raw label less its free-air median (its bias), in free air as the wake fit takes it (out
    of ``REGION_RADII`` leader equivalent radii, or above the leader).

    Raises:
        WakeFitError: no vehicle with enough free-air samples.
    """
    edges = tuple(float(e) for e in edges_mps)
    parts: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for log in logs:
        meta = log.meta
        try:
            radius = (REGION_RADII * float(meta["leader_rotor_radius_m"])
                      * np.sqrt(float(meta["leader_n_rotors"])))
        except (KeyError, TypeError, ValueError):
            continue
        free = free_air_mask(log, radius)
        if free.sum() < MIN_NOISE_SAMPLES:
            continue
        label = raw_labels(log)
        label = label - np.median(label[free], axis=0)
        speed = np.linalg.norm(log.follower_vel_mps, axis=1)
        parts.setdefault(str(meta.get("follower_id")), []).append((label[free], speed[free]))
    out = {}
    for vid, chunks in sorted(parts.items()):
        label, speed = (np.concatenate(c) for c in zip(*chunks))
        b = np.clip(np.digitize(speed, edges) - 1, 0, len(edges) - 2)
        counts = np.bincount(b, minlength=len(edges) - 1)
        var = np.full((len(edges) - 1, 3), np.nan)
        for k in range(len(edges) - 1):
            if counts[k] >= MIN_NOISE_SAMPLES:
                var[k] = label[b == k].var(axis=0)
        filled = np.flatnonzero(np.isfinite(var[:, 0]))
        if filled.size == 0:
            continue
        for k in range(len(edges) - 1):
            if not np.isfinite(var[k, 0]):
                slower = filled[filled < k]
                var[k] = var[slower[-1] if slower.size else filled[0]]
        out[vid] = NoiseTable(edges, var, counts)
    if not out:
        raise WakeFitError("no follower vehicle has free-air samples to read its noise from")
    return out


def with_speed_noise(flights: Sequence[FlightSamples], noise: dict[str, NoiseTable],
                     ) -> list[FlightSamples]:
    """The flights with each sample's label noise the follower vehicle's free-air noise at the
    follower's speed then (:attr:`FlightSamples.noise_var_mps4`), so that the fit and its scores
    read the turbulence sd above it (the correlation time is still read above the pooled
    free-air autocovariance); a flight whose follower has no table keeps the pooled noise.
    """
    out = []
    for f in flights:
        table = noise.get(str(f.vehicles.get("follower")))
        if table is None:
            out.append(f)
            continue
        speed = np.linalg.norm(f.follower.v, axis=1)
        out.append(replace(f, noise_var_mps4=table.at(speed)))
    return out


def speed_matched_turbulence(params: dict[str, float], flights: Sequence[FlightSamples],
                             noise: dict[str, NoiseTable], *,
                             rotor_radii_m: dict[str, float] | None = None,
                             bootstrap: int = 200, seed: int = 0,
                             ) -> dict[str, dict[str, float]]:
    """Per pair, over the samples within ``CORE_RADII`` leader equivalent radii of the axis
    (each flight's residual about the jet's mean and its own offset there, as the fit reads
    it): the real turbulence sd less the pooled free-air noise (``*_pooled``) and less each
    sample's noise at its speed (``*_speed``), the jet's own (``*_model``), m/s², lateral per
    direction and vertical; and the 95th percentile of the speed-matched real sd over
    ``bootstrap`` draws of the pair's flights with replacement (``*_speed_p95``); and the
    samples' median speed.

    A real variance below zero (all of the spread is the labels' noise) is read as 0.
    """
    per: dict[str, list[dict[str, np.ndarray]]] = {}
    for f in flights:
        table = noise.get(str(f.vehicles.get("follower")))
        if table is None:
            continue
        dp = f.offset_m
        core = np.hypot(dp[:, 0], dp[:, 1]) < CORE_RADII * f.equivalent_radius_m
        if not core.any():
            continue
        err = centred(f.label_mps2 - model_mean(params, f, rotor_radii_m), core)[core]
        turb = model_turbulence(params, f, rotor_radii_m)
        speed_var = table.at(np.linalg.norm(f.follower.v, axis=1))[core]
        per.setdefault(f.pair, []).append({
            "lat_sq": 0.5 * (err[:, 0] ** 2 + err[:, 1] ** 2), "vert_sq": err[:, 2] ** 2,
            "lat_pooled": np.full(core.sum(), 0.5 * (f.free_var_mps4[0] + f.free_var_mps4[1])),
            "vert_pooled": np.full(core.sum(), f.free_var_mps4[2]),
            "lat_speed": 0.5 * (speed_var[:, 0] + speed_var[:, 1]),
            "vert_speed": speed_var[:, 2],
            "speed": np.linalg.norm(f.follower.v, axis=1)[core],
            "lat_model": turb["lateral_var_mps4"][core],
            "vert_model": turb["axial_var_mps4"][core]})
    rng = np.random.default_rng(seed)
    out = {}
    for pair, chunks in sorted(per.items()):
        def sd(chosen: Sequence[dict[str, np.ndarray]], axis: str, noise_key: str) -> float:
            total = np.concatenate([c[f"{axis}_sq"] for c in chosen]).mean()
            floor = np.concatenate([c[f"{axis}_{noise_key}"] for c in chosen]).mean()
            return float(np.sqrt(max(total - floor, 0.0)))

        row: dict[str, float] = {
            "samples": float(sum(c["lat_sq"].size for c in chunks)), "flights": float(len(chunks)),
            "median_speed_mps": float(np.median(np.concatenate([c["speed"] for c in chunks])))}
        for axis, name in (("lat", "lateral"), ("vert", "vertical")):
            row[f"{name}_pooled"] = sd(chunks, axis, "pooled")
            row[f"{name}_speed"] = sd(chunks, axis, "speed")
            row[f"{name}_model"] = float(np.sqrt(np.concatenate(
                [c[f"{axis}_model"] for c in chunks]).mean()))
            draws = [sd([chunks[i] for i in rng.integers(0, len(chunks), len(chunks))],
                        axis, "speed") for _ in range(bootstrap)]
            row[f"{name}_speed_p95"] = float(np.percentile(draws, 95)) if draws else float("nan")
        out[pair] = row
    return out
