"""The docking mission: N trials flown as one batch, phase by phase, and their outcomes."""

from aerodock.mission.batch import (
    AbortReason,
    CampaignResult,
    MissionBatch,
    MissionSpec,
    Phase,
    run_campaign,
    wilson_interval,
)

__all__ = ["AbortReason", "CampaignResult", "MissionBatch", "MissionSpec", "Phase",
           "run_campaign", "wilson_interval"]
