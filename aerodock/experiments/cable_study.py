"""The paper's cable-length study: the leader on a rigid stand, the follower docking at each cable
length (offset), a few repetitions each, with and without the model."""

from __future__ import annotations

from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.mission import MissionSpec, run_campaign

CABLE_OFFSETS_M = (0.36, 0.47, 0.64, 0.87, 1.11, 1.35)  # the paper's table of offsets


def offset_result(docked: int, attempts: int) -> str:
    """``"dock"`` when a strict majority of an offset's ``attempts`` docked, else ``"miss"``: a
    tie (1 of 2) is not a dock."""
    return "dock" if 2 * docked > attempts else "miss"


def cable_study(cfg: Config, offsets_m: tuple[float, ...], reps: int,
                predictor: AccelPredictor | None, seed: int, record: str = "summary"
                ) -> tuple[dict[str, Any], dict[str, dict[float, dict[str, np.ndarray]]]]:
    """Fly ``reps`` attempts at every offset, without (bias observer) and with the model.

    An offset's ``result`` is ``dock`` when most of its attempts docked (:func:`offset_result`;
    the paper made one attempt per offset).

    Returns:
        the study's record (``offsets_m``, ``repetitions``, ``without_model``, ``with_model``:
        one campaign summary per offset) and, with ``record = "trace"``, the traces by
        ``"without"``/``"with"`` and offset (empty otherwise).
    """
    study: dict[str, Any] = {"offsets_m": list(offsets_m), "repetitions": reps,
                             "without_model": [], "with_model": []}
    traces: dict[str, dict[float, dict[str, np.ndarray]]] = {"without": {}, "with": {}}
    for offset in offsets_m:
        for key, comp in (("without", Compensation.OBSERVER), ("with", Compensation.MODEL)):
            res = run_campaign(cfg, MissionSpec(
                trials=reps, offset_m=offset, leader_fixed=True, compensation=comp,
                seed=seed, start_azimuths_deg=(0.0,)), predictor, record=record)
            rec = res.summary()
            rec["arrival_s"] = res.arrival_s
            rec["offset_m"] = offset
            rec["result"] = offset_result(rec["docked"], rec["trials"])
            study[f"{key}_model"].append(rec)
            if record == "trace":
                traces[key][offset] = res.trace
    return study, traces
