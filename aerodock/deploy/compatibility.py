"""Warnings for flying a model on vehicles or with a controller it was not trained for.

Pure functions returning one-line messages; the ``dock`` and ``targets`` commands and the ROS
node print them. A model file records the vehicles it was trained on
(:mod:`aerodock.learning.training_vehicles`) and its labels' basis (``training.data.label_bases``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from aerodock.learning.training_vehicles import (
    VEHICLE_KEYS,
    configured_vehicles,
    normalise_vehicles,
)

# Relative difference of a vehicle parameter above which a model is flagged as trained on
# other vehicles (the wake scales with the thrust, i.e. the mass, and the rotor disc area).
VEHICLE_TOLERANCE = 0.1


def vehicle_mismatches(model_vehicles: Mapping[str, Any] | None,
                       configured: Mapping[str, Any]) -> list[str]:
    """One-line notes where a model's training vehicles differ from the configured ones.

    A mass or rotor radius more than :data:`VEHICLE_TOLERANCE` (relative) off, or another rotor
    count, is noted. A model that records none of them (saved before aerodock recorded them)
    gets one note saying so; parameters some logs do not carry (simulated logs record masses
    only) are compared where known.
    """
    model = normalise_vehicles(model_vehicles)
    config = normalise_vehicles(configured)
    notes: list[str] = []
    unknown: list[str] = []
    for role in ("leader", "follower"):
        for key in VEHICLE_KEYS:
            have, want = model[role][key], config[role][key]
            if want is None:
                continue
            if have is None:
                unknown.append(f"{role} {key}")
                continue
            values = have if isinstance(have, list) else [have]
            if key == "n_rotors":
                off = any(int(v) != int(want) for v in values)
            else:
                off = any(abs(v - want) > VEHICLE_TOLERANCE * want for v in values)
            if off:
                shown = "/".join(f"{v:g}" for v in values)
                notes.append(f"model trained with {role} {key} = {shown}, configured {want:g}")
    known = sum(model[role][key] is not None for role in model for key in VEHICLE_KEYS)
    if unknown and not known:
        notes.append("model does not record the vehicles it was trained on (saved before "
                     "aerodock recorded them, or trained on logs without masses)")
    return notes


def model_vehicle_warnings(predictor_or_doc: Any, cfg: Any) -> list[str]:
    """Warnings for running a model (a Predictor or a ``model.json`` dict) on ``cfg``'s vehicles.

    The ``dock`` command and the ROS node print these; an empty list means the vehicles match.
    """
    doc = getattr(predictor_or_doc, "meta", predictor_or_doc)
    if not isinstance(doc, Mapping) or doc.get("kind") == "zero":
        return []  # the zero model predicts nothing, whatever the vehicles
    return vehicle_mismatches(doc.get("vehicles"), configured_vehicles(cfg))


def model_pairing_warnings(predictor_or_doc: Any, cfg: Any) -> list[str]:
    """Warnings for flying a model with ``cfg``'s torque feed-forward when its force labels were
    made on the paper's command basis (``a_obs - u_1:3``): such a model already counts the tilt
    the wake's torque causes as force, and cancelling the torque as well holds the follower off
    the wake's axis (README, *Label basis*). Models that do not record their labels' basis pass.
    """
    doc = getattr(predictor_or_doc, "meta", predictor_or_doc)
    control = getattr(cfg, "control", None)
    if not isinstance(doc, Mapping) or not getattr(control, "torque_feedforward", False):
        return []
    data = doc.get("training", {}).get("data", {}) if isinstance(doc.get("training"),
                                                                   Mapping) else {}
    bases = data.get("label_bases") if isinstance(data, Mapping) else None
    if isinstance(bases, list) and "command" in bases:
        return ["the model's force labels are on the command basis (a_obs - u_1:3, which counts "
                "the tilt the wake's torque causes); with control.torque_feedforward that torque "
                "is compensated twice: train on curriculum.label_basis = \"thrust\" flights"]
    return []


def model_warnings(predictor_or_doc: Any, cfg: Any) -> list[str]:
    """Every warning for flying a model on ``cfg``: other vehicles
    (:func:`model_vehicle_warnings`) and a torque feed-forward its labels do not suit
    (:func:`model_pairing_warnings`). ``dock``, ``targets`` and the ROS node print these."""
    return model_vehicle_warnings(predictor_or_doc, cfg) + model_pairing_warnings(
        predictor_or_doc, cfg)
