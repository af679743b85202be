"""How big each of ``aerodock reproduce``'s experiments is: the full run, ``--quick`` and
``--smoke`` (:data:`FULL`, :data:`QUICK`, :data:`SMOKE`), and the mission's waiting times the
smoke run cuts (:data:`SHORT_MISSION`). :mod:`aerodock.experiments.reproduce` and the steps it
delegates (:mod:`aerodock.experiments.docking_runs`) both read them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from aerodock.experiments.cable_study import CABLE_OFFSETS_M
from aerodock.experiments.controller_costs import (
    GATE_HEIGHTS_M,
    OBSERVER_TAUS_S,
    TERMINAL_MIX,
    CostSize,
)


@dataclass(frozen=True)
class RunSize:
    """How big each experiment is (``--quick`` or full)."""

    cable_reps: int
    cable_offsets_m: tuple[float, ...]
    hover_trials: int
    moving_trials: int
    se_minutes: tuple[float, ...]
    se_seeds: tuple[int, ...]
    se_pool_flights: int
    test_flights_per_stage: int
    # the sample-efficiency trainings' epoch limit (None: train's own stopping rule): an epoch
    # count, not a wall-clock budget, so that a run's numbers do not depend on the machine
    se_max_epochs: int | None
    costs: CostSize  # the sweeps of the levers the paper leaves unstated
    target_trials: int
    target_all_rows: bool  # every controller + model row (quick: the paper's and ours only)
    # [curriculum] keys changed for this size ({}: the configuration's curriculum) and the
    # training epochs of each stage's model (None: train's own stopping rule)
    curriculum: dict[str, Any] = field(default_factory=dict)
    train_max_epochs: int | None = None
    tuned_row: bool = True  # the tuned controller's experiments (its code is ours' minus one term)
    # config overrides for this size ({}: the configuration's own): the smoke run cuts the
    # mission's waiting times (:data:`SHORT_MISSION`)
    overrides: dict[str, Any] = field(default_factory=dict)


SHORT_MISSION: dict[str, dict[str, float]] = {
    "mission": {"settle_s": 1.0, "post_dock_s": 0.5, "dock_window_s": 1.0, "backoff_s": 1.0,
                "leader_ramp_s": 1.0},
    "planner": {"hold_s": 2.0}}
"""The mission's waiting times cut: settled start 1 s (configured: 3), hold after capture 0.5 s,
docking window and back-off 1 s, a moving leader's ramp 1 s and hold 2 s. A docked hover trial
flies 5.1 simulated seconds instead of 8.1 (settled start included); what the mission achieves
changes, every step it takes does not. ``reproduce --smoke`` flies it (it checks that a field
or a config goes through, not a figure), and the tests of properties that hold whatever the
timing."""

QUICK = RunSize(cable_reps=2, cable_offsets_m=(0.36, 0.87, 1.35), hover_trials=24,
                moving_trials=8, se_minutes=(0.5, 2),
                se_seeds=(0,), se_pool_flights=0, test_flights_per_stage=2, se_max_epochs=20,
                costs=CostSize(trials=8, taus_s=(4.0,), mixes=(0.0, 1.0),
                               cable_offsets_m=(0.36,), cable_reps=2, gate_heights_m=(0.10,)),
                target_trials=4,
                target_all_rows=False)
# The smallest run that crosses every step (one offset, a handful of trials, one sample-efficiency
# point, one observer setting): for checking that a plug-in field or a config goes through the
# whole pipeline, not for any figure.
SMOKE = RunSize(cable_reps=1, cable_offsets_m=(0.36,), hover_trials=4, moving_trials=2,
                se_minutes=(0.5,), se_seeds=(0,), se_pool_flights=0, test_flights_per_stage=1,
                se_max_epochs=8,
                costs=CostSize(trials=2, taus_s=(), mixes=(0.0,), cable_offsets_m=(0.36,),
                               cable_reps=1, gate_heights_m=()),
                target_trials=2, target_all_rows=False,
                # two paper stages and one deep stage of two flights each (the configuration's
                # curriculum flies seven stages of five to ten): every step, at its smallest
                curriculum={"stage_step_m": 0.65, "deep_depths_m": [0.27],
                            "flights_per_stage": 2, "deep_flights_per_stage": 2},
                train_max_epochs=5, tuned_row=False, overrides=SHORT_MISSION)
FULL = RunSize(cable_reps=10, cable_offsets_m=CABLE_OFFSETS_M, hover_trials=200, moving_trials=100,
               se_minutes=(0.5, 1, 2, 5, 10), se_seeds=(0, 1, 2), se_pool_flights=25,
               test_flights_per_stage=4, se_max_epochs=None,
               costs=CostSize(trials=60, taus_s=OBSERVER_TAUS_S, mixes=TERMINAL_MIX,
                              cable_offsets_m=CABLE_OFFSETS_M, cable_reps=10,
                              gate_heights_m=GATE_HEIGHTS_M),
               target_trials=100, target_all_rows=True)
