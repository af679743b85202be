"""How well the wake fit carries to flights it has not seen: cross-validation over flights, and
the real turbulence flight by flight.

One held-out split (``aerodock field fit --holdout``) scores the fit on those flights only, and
real flights differ from each other: a pair's turbulence sd near the axis moves by a quarter or
more from flight to flight, so one split's pass or miss of a 20 % target is one draw of that
spread. Here every flight is held out once (:func:`cross_validate`): each vehicle pair's flights,
in name order, are dealt round-robin into ``folds`` folds, and each fold is scored
(:func:`aerodock.identify.wake_score.score_wake`) by a fit on all the other flights (every pair's).
Per pair and target: the relative error of every fold that has data, and how many meet the
target. :func:`flight_turbulence` reads the real turbulence sd of each flight alone, the spread a
single fitted intensity must cover.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from aerodock.identify.flights import FlightSamples, WakeFitError
from aerodock.identify.wake_fit import TorqueResidual, fit_wake
from aerodock.identify.wake_score import TARGETS, score_wake, signed_worst

TARGET_KEYS = ("mean_vertical", "half_width", "vertical_sd", "lateral_sd")


def assign_folds(flights: Sequence[FlightSamples], folds: int) -> dict[str, int]:
    """Flight key -> fold: each pair's flights in name order, dealt round-robin, the deal
    carried on from one pair to the next (a flight with logs in two pairs takes the fold its
    first pair gives it). With ``folds`` no more than the largest pair's flights, every fold
    holds out at least one flight, and fold sizes differ by at most one.

    Raises:
        WakeFitError: ``folds`` below 2, or above the flights of every pair.
    """
    by_pair: dict[str, list[str]] = {}
    for f in flights:
        keys = by_pair.setdefault(f.pair, [])
        if f.flight not in keys:
            keys.append(f.flight)
    most = max((len(k) for k in by_pair.values()), default=0)
    if folds < 2 or folds > most:
        raise WakeFitError(f"folds must be between 2 and the flights of the largest pair "
                           f"({most}), got {folds}")
    out: dict[str, int] = {}
    deal = 0  # the deal goes on from one pair to the next, so the folds stay even
    for _, keys in sorted(by_pair.items()):
        for key in sorted(keys):
            if key not in out:
                out[key] = deal % folds
                deal += 1
    return out


def cross_validate(flights: Sequence[FlightSamples], folds: int = 3, *,
                   estimate_rotor_for: Sequence[str] = (),
                   progress: Callable[[int, int], None] | None = None,
                   torque: Mapping[str, TorqueResidual] | None = None) -> dict[str, Any]:
    """Every flight held out once, in ``folds`` folds (module docstring); each fold's fit takes
    the logged torque of its training flights where ``torque`` has it (as ``field fit`` does).

    Returns:
        ``folds``: per fold the held-out flights, the fit's parameters and rotor radii, and its
        scores on them (:func:`score_wake`'s ``pairs``, with the real and fitted figures);
        ``summary``: per pair and target, ``rel_errors`` (one per fold with data, in fold
        order), ``met`` and ``scored`` (folds), and the same for the data's own reference
        (``reference_rel_errors``, ``reference_met``): the fold's training flights' real figure
        taken as the prediction, what a model that matched its training flights exactly would
        score on the held-out ones (the flights' own spread; no jet can beat it on average).

    Raises:
        WakeFitError: see :func:`assign_folds`.
    """
    flights = list(flights)
    fold_of = assign_folds(flights, folds)
    out_folds = []
    for k in range(folds):
        held = [f for f in flights if fold_of[f.flight] == k]
        train = [f for f in flights if fold_of[f.flight] != k]
        wanted = [v for v in estimate_rotor_for
                  if any(v in f.vehicles.values() for f in train)]
        fit = fit_wake(train, estimate_rotor_for=wanted, torque=torque)
        scores = score_wake(fit.params, held, fit.rotor_radii_m)
        own = score_wake(fit.params, train, fit.rotor_radii_m)
        out_folds.append({"fold": k, "held_out": sorted({f.flight for f in held}),
                          "params": fit.field_params(), "rotor_radii_m": fit.rotor_radii_m,
                          "pairs": scores["pairs"], "fitted_pairs": own["pairs"]})
        if progress:
            progress(k + 1, folds)
    return {"folds": out_folds, "summary": _summary(out_folds), "targets": TARGETS}


def _summary(folds: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    pairs = sorted({p for f in folds for p in f["pairs"]})
    out: dict[str, dict[str, Any]] = {}
    for pair in pairs:
        row: dict[str, Any] = {}
        for key in TARGET_KEYS:
            errs, met, ref, ref_met = [], 0, [], 0
            for f in folds:
                entry = f["pairs"].get(pair)
                if entry is None:
                    continue
                err = (signed_worst([b["rel_error"] for b in entry["separation_bins"]])
                       if key == "mean_vertical" else entry[key]["rel_error"])
                if not np.isfinite(err):
                    continue
                errs.append(float(err))
                met += bool(entry[key]["met"])
                own = f["fitted_pairs"].get(pair)
                r = _reference_error(key, entry, own) if own is not None else float("nan")
                ref.append(r)
                ref_met += bool(np.isfinite(r) and abs(r) <= TARGETS[key])
            row[key] = {"rel_errors": errs, "met": met, "scored": len(errs),
                        "reference_rel_errors": ref, "reference_met": ref_met}
        out[pair] = row
    return out


def _reference_error(key: str, held: dict[str, Any], train: dict[str, Any]) -> float:
    """The training flights' real figure as the prediction of the held-out flights' (the mean
    per separation bin: the worst of the bins both have)."""
    if key == "mean_vertical":
        own = {tuple(b["separation_m"]): b["real_mps2"] for b in train["separation_bins"]}
        return signed_worst([(own[tuple(b["separation_m"])] - b["real_mps2"])
                             / abs(b["real_mps2"]) for b in held["separation_bins"]
                             if tuple(b["separation_m"]) in own and b["real_mps2"]])
    unit = "real_m" if key == "half_width" else "real_mps2"
    real, pred = held[key][unit], train[key][unit]
    if not (np.isfinite(real) and np.isfinite(pred)) or real == 0:
        return float("nan")
    return float((pred - real) / real)


def flight_turbulence(params: dict[str, float], flights: Sequence[FlightSamples],
                      rotor_radii_m: dict[str, float] | None = None) -> dict[str, list[dict]]:
    """Per pair, each flight alone: its real vertical and lateral turbulence sd near the axis
    (as :func:`score_wake` reads it: about the jet's mean and the flight's own offset, less the
    free-air noise) and the jet's there, m/s². Flights with too few samples near the axis, or
    whose spread there is all noise, are left out of that figure (``nan``)."""
    out: dict[str, list[dict]] = {}
    keys = sorted({f.flight for f in flights})
    for key in keys:
        scores = score_wake(params, [f for f in flights if f.flight == key], rotor_radii_m)
        for pair, entry in scores["pairs"].items():
            out.setdefault(pair, []).append({
                "flight": key, "core_samples": entry["core_samples"],
                "vertical_real_mps2": entry["vertical_sd"]["real_mps2"],
                "vertical_fitted_mps2": entry["vertical_sd"]["fitted_mps2"],
                "lateral_real_mps2": entry["lateral_sd"]["real_mps2"],
                "lateral_fitted_mps2": entry["lateral_sd"]["fitted_mps2"]})
    return out
