"""The docking mission: N trials flown as one batch, phase by phase, and their outcomes."""

from aerodock.mission.batch import (
    Decision,
    Flown,
    MissionBatch,
    Status,
    run_campaign,
    settle_trials,
)
from aerodock.mission.outcome import CampaignResult, wilson_interval
from aerodock.mission.settle import SettledStart
from aerodock.mission.spec import AbortReason, MissionSpec, Phase

__all__ = ["AbortReason", "CampaignResult", "Decision", "Flown", "MissionBatch", "MissionSpec",
           "Phase", "SettledStart", "Status", "run_campaign", "settle_trials", "wilson_interval"]
