"""The one validation of a campaign's set-up, shared by ``dock``, ``sweep`` and the Gymnasium
environments: a value any of them accepts, the others accept too, and one they refuse is refused
with the same rule (named as each caller calls it: ``--leader-speed``, ``axes.leader_speed_mps``,
``leader_speed_mps``).

The configuration itself is checked when it is loaded (:mod:`aerodock.config.loader`: ranges,
integer keys, choices such as ``curriculum.label_basis``); this module checks what a campaign
adds to it: the cable length (applied to the config and checked by the config's rules, so a
docking point below the ground is refused), the leader's speed and turn rate, the leader-state
dropout and the injected faults (:func:`aerodock.mission.faults.check_fault`), and the size of
the run (:mod:`aerodock.mission.limits`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import Compensation
from aerodock.mission.faults import Fault, FaultFileError, check_fault
from aerodock.mission.limits import check_campaign_size
from aerodock.mission.spec import MissionSpec

MAX_OFFSET_M = 100.0
"""Longest cable length d_p a campaign may ask for, m (``platform.cable_length_m``'s bound)."""
MAX_LEADER_SPEED_MPS = 100.0
"""Fastest leader, m/s (either direction)."""
MAX_TURN_RATE_RADPS = 10.0
"""Fastest turn of a moving leader's path, rad/s (either direction)."""

FIELD_NAMES = {"trials": "trials", "offset_m": "offset_m", "leader_speed_mps": "leader_speed_mps",
               "leader_turn_rate_radps": "leader_turn_rate_radps",
               "leader_dropout_s": "leader_dropout_s", "compensation": "compensation",
               "faults": "faults"}
"""How each checked field is named in messages unless the caller names it otherwise."""
DOCK_NAMES = {**FIELD_NAMES, "trials": "--trials", "offset_m": "--offset",
              "leader_speed_mps": "--leader-speed", "compensation": "--compensation",
              "faults": "--faults"}
"""The names ``aerodock dock`` gives the fields (its options)."""


class MissionSpecError(ValueError):
    """A campaign's set-up is invalid; the message names the value as the caller calls it."""


def check_number(name: str, value: Any, low: float, high: float) -> float:
    """``value`` as a float, refused unless it is a finite number in ``[low, high]``.

    The wording is the command line's (``--leader-speed must be between -100 and 100, got
    1000000.0``), whatever ``name`` is.

    Raises:
        MissionSpecError: not a number, not finite, or out of range.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MissionSpecError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise MissionSpecError(f"{name} must be a finite number, got {value}")
    if not low <= value <= high:
        raise MissionSpecError(f"{name} must be between {low:g} and {high:g}, got {value!r}")
    return float(value)


def check_positive(name: str, value: Any, high: float) -> float:
    """``value`` as a float, refused unless it is a finite number with ``0 < value <= high``.

    Raises:
        MissionSpecError: not a number, not finite, not positive, or above ``high``.
    """
    number = check_number(name, value, -math.inf, math.inf)
    if not number > 0:
        raise MissionSpecError(f"{name} must be > 0, got {value!r}")
    return check_number(name, number, 0.0, high)


def check_seed(value: Any, name: str = "seed") -> int:
    """A campaign seed: an integer >= 0 (the per-trial streams of :class:`aerodock.rng.TrialRNG`
    are seeded with it).

    Raises:
        MissionSpecError: not an integer, or negative.
    """
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise MissionSpecError(f"{name} must be an integer >= 0, got {value!r}")
    return int(value)


def check_leader_speed(value: Any, name: str = "leader_speed_mps") -> float:
    """A leader speed, m/s: finite, at most :data:`MAX_LEADER_SPEED_MPS` either way."""
    return check_number(name, value, -MAX_LEADER_SPEED_MPS, MAX_LEADER_SPEED_MPS)


def check_offset(value: Any, name: str = "offset_m") -> float:
    """A cable length d_p, m: finite, > 0 and at most :data:`MAX_OFFSET_M` (the config's rules,
    such as the docking point above the ground, are applied by :func:`config_with_offset`)."""
    offset = check_number(name, value, -math.inf, math.inf)
    if not offset > 0:
        raise MissionSpecError(f"{name} must be > 0 m, got {value!r}")
    return check_number(name, offset, 0.0, MAX_OFFSET_M)


def check_dropout(value: Any, name: str = "leader_dropout_s") -> tuple[float, float]:
    """A leader-state dropout ``(start_s, duration_s)``, checked as the ``leader_state_lost``
    fault it becomes (finite, start >= 0, 0 < duration <= 600 s)."""
    ok = (isinstance(value, list | tuple) and len(value) == 2
          and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value))
    if not ok:
        raise MissionSpecError(f"{name} must be [start_s, duration_s], got {value!r}")
    start, duration = float(value[0]), float(value[1])
    if not (math.isfinite(start) and math.isfinite(duration)):
        raise MissionSpecError(f"{name}: start and duration must be finite, got {value!r}")
    try:
        check_fault(Fault("leader dropout", "leader_state_lost", 1.0, (start, start), duration),
                    name)
    except FaultFileError as err:
        raise MissionSpecError(str(err).replace("'start_s'", "start").replace(
            "'duration_s'", "duration")) from None
    return start, duration


def config_with_offset(cfg: Config, offset_m: float | None, name: str = "offset_m") -> Config:
    """``cfg`` with the cable length ``offset_m`` (None: ``cfg`` as it is), validated by the
    config's own rules and named ``name`` in a message (``--offset 30``)."""
    if offset_m is None:
        return cfg
    offset = check_offset(offset_m, name)
    return cfg.with_overrides({"platform": {"cable_length_m": offset}},
                              source=f"{name} {offset:g}")


def check_mission(cfg: Config, spec: MissionSpec, names: Mapping[str, str] | None = None,
                  size: bool = False, keep_logs: bool = False) -> Config:
    """Check ``spec`` against ``cfg``; the config the campaign flies (its cable length applied).

    Args:
        cfg: the loaded (valid) configuration.
        spec: the campaign.
        names: how the caller names each field in messages (default :data:`FIELD_NAMES`).
        size: also check the run's size (:func:`aerodock.mission.limits.check_campaign_size`).
        keep_logs: the run keeps every FlightLog (a lower size limit).

    Raises:
        MissionSpecError: a value out of its range (the message names it).
        aerodock.config.ConfigError: the cable length breaks a rule of the config.
        aerodock.mission.limits.LimitError: the run is too large (with ``size``).
    """
    n = {**FIELD_NAMES, **(names or {})}
    if isinstance(spec.trials, bool) or not isinstance(spec.trials, int) or spec.trials < 1:
        raise MissionSpecError(f"{n['trials']} must be >= 1, got {spec.trials}")
    check_leader_speed(spec.leader_speed_mps, n["leader_speed_mps"])
    check_number(n["leader_turn_rate_radps"], spec.leader_turn_rate_radps,
                 -MAX_TURN_RATE_RADPS, MAX_TURN_RATE_RADPS)
    try:
        Compensation(spec.compensation)
    except ValueError:
        raise MissionSpecError(f"{n['compensation']} must be one of "
                               f"{'|'.join(c.value for c in Compensation)}, "
                               f"got {spec.compensation!r}") from None
    if spec.leader_dropout_s is not None:
        check_dropout(spec.leader_dropout_s, n["leader_dropout_s"])
    for i, fault in enumerate(spec.faults):
        try:
            check_fault(fault, f"{n['faults']}: fault {i + 1} ({fault.name})")
        except FaultFileError as err:
            raise MissionSpecError(str(err)) from None
    flown = config_with_offset(cfg, spec.offset_m, n["offset_m"])
    if size:
        check_campaign_size(flown, spec.trials, keep_logs=keep_logs)
    return flown

