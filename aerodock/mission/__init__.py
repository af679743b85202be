"""The docking mission: N trials flown as one batch, phase by phase, and their outcomes.

The names below load their modules on first use: the batch imports the compiled world (numba),
which a command refusing its input (a fault file, a mission's size), or one reading only the
mission's specification, should not wait for."""

from __future__ import annotations

from aerodock.lazy import lazy_names

_HOMES = {
    "AbortReason": "aerodock.mission.spec",
    "CampaignResult": "aerodock.mission.outcome",
    "Decision": "aerodock.mission.batch",
    "Flown": "aerodock.mission.batch",
    "MissionBatch": "aerodock.mission.batch",
    "MissionSpec": "aerodock.mission.spec",
    "Phase": "aerodock.mission.spec",
    "SettledStart": "aerodock.mission.settle",
    "Status": "aerodock.mission.batch",
    "run_campaign": "aerodock.mission.batch",
    "settle_trials": "aerodock.mission.batch",
    "wilson_interval": "aerodock.mission.outcome",
}

__all__ = sorted(_HOMES)

__getattr__ = lazy_names(__name__, _HOMES)
