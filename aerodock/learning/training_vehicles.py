"""The vehicles a model was trained on: each role's mass, rotor radius, rotor count and
motor-to-motor diagonal.

A model file (``model.json``'s ``vehicles``) and a data set's summary record them as
``{"leader": {mass_kg, rotor_radius_m, n_rotors, diagonal_m}, "follower": {...}}``, each value a
positive number, a sorted list of them (when the training flights disagree) or ``None`` (when
the logs did not say). :mod:`aerodock.deploy.compatibility` compares such a record with the
vehicles a config flies (:func:`configured_vehicles`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

VEHICLE_KEYS = ("mass_kg", "rotor_radius_m", "n_rotors", "diagonal_m")
"""What is recorded of each vehicle (the diagonal sets a follower's rotor footprint,
:mod:`aerodock.learning.footprint`)."""


def _number(value: Any) -> float | None:
    try:
        out = float(value)
    except (TypeError, ValueError):
        return None
    return out if math.isfinite(out) and out > 0 else None


def normalise_vehicles(vehicles: Mapping[str, Any] | None) -> dict[str, dict[str, Any]]:
    """``{"leader": {mass_kg, rotor_radius_m, n_rotors, diagonal_m}, "follower": {...}}``, None
    if unknown.

    A value that is not a positive finite number (or a list of them, when the training flights
    disagree) becomes ``None``.
    """
    out: dict[str, dict[str, Any]] = {}
    for role in ("leader", "follower"):
        given = vehicles.get(role) if isinstance(vehicles, Mapping) else None
        given = given if isinstance(given, Mapping) else {}
        entry: dict[str, Any] = {}
        for key in VEHICLE_KEYS:
            value = given.get(key)
            if isinstance(value, list | tuple):
                values = [_number(v) for v in value]
                entry[key] = values if values and all(v is not None for v in values) else None
            else:
                entry[key] = _number(value)
            if key == "n_rotors" and entry[key] is not None:
                entry[key] = ([int(v) for v in entry[key]] if isinstance(entry[key], list)
                              else int(entry[key]))
        out[role] = entry
    return out


def flight_vehicle_fields(meta: Mapping[str, Any]) -> dict[str, float | None]:
    """A FlightLog ``meta``'s ``{leader,follower}_{mass_kg,rotor_radius_m,n_rotors,diagonal_m}``
    (or None)."""
    return {f"{role}_{key}": _number(meta.get(f"{role}_{key}"))
            for role in ("leader", "follower") for key in VEHICLE_KEYS}


def vehicles_from_flights(flights: Iterable[Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """The vehicles of training flights (their ``leader_mass_kg``, ``follower_rotor_radius_m``...).

    A parameter that every flight gives with one value is that value; one that differs between
    flights is the sorted list of values; one that any flight lacks is ``None``.
    """
    flights = list(flights)
    out: dict[str, dict[str, Any]] = {}
    for role in ("leader", "follower"):
        entry: dict[str, Any] = {}
        for key in VEHICLE_KEYS:
            values = [_number(f.get(f"{role}_{key}")) for f in flights]
            if not values or any(v is None for v in values):
                entry[key] = None
                continue
            unique = sorted(set(values))
            entry[key] = unique[0] if len(unique) == 1 else unique
        out[role] = entry
    return normalise_vehicles(out)


def configured_vehicles(cfg: Any) -> dict[str, dict[str, Any]]:
    """The vehicles of an aerodock config: the leader its ``[leader]`` (``[vehicle]`` where the
    leader is alike), the follower its ``[vehicle]``."""
    def entry(v: Any) -> dict[str, Any]:
        return {"mass_kg": v.mass_kg, "rotor_radius_m": v.rotor_radius_m,
                "n_rotors": v.n_rotors, "diagonal_m": v.diagonal_m}
    return normalise_vehicles({"leader": entry(cfg.leader), "follower": entry(cfg.vehicle)})
