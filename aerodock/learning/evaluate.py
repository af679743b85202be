"""Held-out evaluation of a downwash model against the labels, beside the zero model.

Metrics (all in m/s², NED axes x = north, y = east, z = down):

* ``rmse_mps2``: root mean square error per axis, and ``overall`` = sqrt of the mean over the
  three axes (the RMS of one error component);
* ``r2``: coefficient of determination per axis, and ``overall`` = 1 - (sum of squared errors
  over all axes) / (sum of squared deviations of the labels from their per-axis means); None when
  undefined (fewer than two samples or constant labels). The zero model's R² is <= 0.

Each is reported over all samples and over the *interaction region*: follower below the leader
(``dp_z > 0``) within ``lateral_radius_m`` (0.2 m) horizontally, where the downwash matters.
With simulated data (``y_true_mean``), the *error floor* is the same metrics for the simulator's
true mean field used as the prediction: no model of the mean can beat it, because what remains is
turbulence and sensor noise. ``model_vs_true_mean`` measures how well the model recovers the mean
field itself.

A model that predicts the torque (``so2-wrench``) on data with torque labels (``y_torque``) adds
``torque``: the same regions with RMSE in N m (world NED), the zero model, and with simulated data
``true_torque`` (the simulator's wake torque over the same periods used as the prediction: what
remains is the labels' sensor noise, a floor below any model's, which cannot predict the
turbulence), ``model_vs_true`` and ``true_rms_nm`` (the RMS of one component of the true torque).
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from aerodock.learning.dataset import INTERACTION_RADIUS_M, Dataset
from aerodock.learning.footprint import footprint_radius_m

AXES = ("x", "y", "z")


class SupportsPredict(Protocol):
    """Anything with a batched ``predict(x (n, 9), leader_R (n, 3, 3)) -> (n, 3)``."""

    def predict(self, x: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
        """Predicted acceleration (n, 3)."""
        ...


def regression_metrics(pred: np.ndarray, y: np.ndarray, unit: str = "mps2") -> dict[str, Any]:
    """RMSE (key ``rmse_{unit}``) and R² per axis and overall of predictions ``pred`` (n, 3) for
    labels ``y`` (n, 3)."""
    pred = np.asarray(pred, dtype=float)
    y = np.asarray(y, dtype=float)
    n = int(y.shape[0])
    key = f"rmse_{unit}"
    if n == 0:
        none = {a: None for a in (*AXES, "overall")}
        return {"n": 0, key: dict(none), "r2": dict(none)}
    sse = np.sum((pred - y) ** 2, axis=0)
    sst = np.sum((y - y.mean(axis=0)) ** 2, axis=0)
    rmse = np.sqrt(sse / n)

    def r2(e: float, t: float) -> float | None:
        return None if n < 2 or t <= 1e-12 * max(n, 1) else float(1.0 - e / t)

    return {
        "n": n,
        key: {**{a: float(v) for a, v in zip(AXES, rmse)},
                      "overall": float(np.sqrt(sse.sum() / (3 * n)))},
        "r2": {**{a: r2(e, t) for a, e, t in zip(AXES, sse, sst)},
               "overall": r2(float(sse.sum()), float(sst.sum()))},
    }


def _region(pred: np.ndarray, ds: Dataset, mask: np.ndarray) -> dict[str, Any]:
    y = ds.y[mask]
    out: dict[str, Any] = {
        "n": int(mask.sum()),
        "model": regression_metrics(pred[mask], y),
        "zero": regression_metrics(np.zeros_like(y), y),
        "error_floor": None,
        "model_vs_true_mean": None,
    }
    if ds.y_true_mean is not None:
        true = ds.y_true_mean[mask]
        ok = np.all(np.isfinite(true), axis=1)
        if ok.any():
            out["error_floor"] = regression_metrics(true[ok], y[ok])
            out["model_vs_true_mean"] = regression_metrics(pred[mask][ok], true[ok])
    return out


def _torque_region(pred: np.ndarray, ds: Dataset, mask: np.ndarray) -> dict[str, Any]:
    """Torque metrics (N m) over the samples of ``mask`` that have torque labels."""
    mask = mask & np.all(np.isfinite(ds.y_torque), axis=1)
    y = ds.y_torque[mask]
    out: dict[str, Any] = {
        "n": int(mask.sum()),
        "model": regression_metrics(pred[mask], y, "nm"),
        "zero": regression_metrics(np.zeros_like(y), y, "nm"),
        "true_torque": None, "model_vs_true": None, "true_rms_nm": None,
    }
    if ds.y_torque_true is not None:
        true = ds.y_torque_true[mask]
        ok = np.all(np.isfinite(true), axis=1)
        if ok.any():
            out["true_torque"] = regression_metrics(true[ok], y[ok], "nm")
            out["model_vs_true"] = regression_metrics(pred[mask][ok], true[ok], "nm")
            out["true_rms_nm"] = float(np.sqrt(np.mean(true[ok] ** 2)))
    return out


def footprint_diagonals_m(predictor: SupportsPredict, ds: Dataset) -> np.ndarray:
    """(n,) the followers' diagonals a footprint prediction of ``ds`` reads (m).

    Raises:
        ValueError: the model records no training follower's diagonal, or no flight of ``ds``
            records its follower's (the footprint would silently be no footprint).
    """
    if getattr(predictor, "trained_follower_diagonal_m", None) is None:
        raise ValueError("the rotor footprint needs a model that records its training "
                         "follower's diagonal (model.json vehicles.follower.diagonal_m: train it "
                         "on flights that record follower_diagonal_m)")
    diagonals = ds.follower_diagonals_m()
    if not np.isfinite(diagonals).any():
        raise ValueError("the rotor footprint needs flights that record follower_diagonal_m "
                         "(ingest them again)")
    return diagonals


def predict_dataset(predictor: SupportsPredict, ds: Dataset, *, footprint: bool = False
                    ) -> np.ndarray:
    """``predictor``'s prediction (n, 3), m/s², NED, at every sample of ``ds`` (a leader-aware
    model gets the data's wake scales, :meth:`Dataset.wake_scales`). ``footprint``: a follower
    larger than the model's training one gets the prediction over its wider rotor footprint
    (:mod:`aerodock.learning.footprint`; the followers' diagonals from the flights' metadata).

    Raises:
        ValueError: the predictor returned another shape, or ``footprint`` cannot apply
            (:func:`footprint_diagonals_m`).
    """
    return _predicted(predictor, ds, footprint_diagonals_m(predictor, ds) if footprint else None)


def _predicted(predictor: SupportsPredict, ds: Dataset,
               follower_diagonal_m: np.ndarray | None) -> np.ndarray:
    """:func:`predict_dataset` with the followers' diagonals already read (None: no
    footprint)."""
    extra: dict[str, Any] = {}
    if follower_diagonal_m is not None:
        extra["follower_diagonal_m"] = follower_diagonal_m
    if getattr(predictor, "needs_wake_scales", False):
        pred = np.asarray(predictor.predict(ds.x, ds.leader_R, ds.wake_scales(), **extra),
                          dtype=float)
    else:
        pred = np.asarray(predictor.predict(ds.x, ds.leader_R, **extra), dtype=float)
    if pred.shape != ds.y.shape:
        raise ValueError(f"predictor returned shape {pred.shape}, expected {ds.y.shape}")
    return pred


def evaluate(
    predictor: SupportsPredict, ds: Dataset, *, lateral_radius_m: float = INTERACTION_RADIUS_M,
    footprint: bool = False,
) -> dict[str, Any]:
    """Evaluate ``predictor`` on ``ds`` (JSON-ready dict).

    Args:
        predictor: a :class:`~aerodock.learning.runtime.Predictor` (or anything with a batched
            ``predict``).
        ds: held-out data.
        lateral_radius_m: horizontal radius of the interaction region.
        footprint: predict a follower larger than the training one over its rotor footprint
            (:func:`predict_dataset`; the result then holds ``footprint_radius_m``, the largest
            extra ring used, 0 where every follower is the training size or smaller).

    Returns:
        ``{"model": kind, "n_samples", "minutes", "interaction_region": description,
        "all": region, "interaction": region}``, where each region holds ``n``, ``model`` and
        ``zero`` metrics (see :func:`regression_metrics`), ``error_floor`` and
        ``model_vs_true_mean`` (None without ``y_true_mean``); and ``torque`` (``all`` and
        ``interaction`` torque regions, see the module docstring) when the predictor has a
        torque and the data torque labels.
    """
    diagonals = footprint_diagonals_m(predictor, ds) if footprint else None
    pred = _predicted(predictor, ds, diagonals)
    out: dict[str, Any] = {
        "model": getattr(predictor, "kind", type(predictor).__name__),
        "n_samples": ds.n,
        "minutes": round(ds.minutes, 4),
        "interaction_region": f"dp_z > 0 (follower below the leader) and horizontal distance "
                              f"<= {lateral_radius_m} m",
        "all": _region(pred, ds, np.ones(ds.n, dtype=bool)),
        "interaction": _region(pred, ds, ds.interaction_mask(lateral_radius_m)),
    }
    if diagonals is not None:  # the largest extra ring the followers were predicted over
        out["footprint_radius_m"] = float(np.max(footprint_radius_m(
            predictor.trained_follower_diagonal_m, diagonals), initial=0.0))
    if getattr(predictor, "has_torque", False) and ds.y_torque is not None:
        torque = np.asarray(predictor.predict_torque(ds.x, ds.leader_R), dtype=float)
        out["torque"] = {
            "units": "N m, world NED",
            "all": _torque_region(torque, ds, np.ones(ds.n, dtype=bool)),
            "interaction": _torque_region(torque, ds, ds.interaction_mask(lateral_radius_m)),
        }
    return out
