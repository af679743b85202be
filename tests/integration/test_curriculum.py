"""Curriculum collection: stages get closer, each deploys the previous stage's model."""

from __future__ import annotations

import numpy as np

from aerodock.flightlog import load_flightlogs
from aerodock.learning.curriculum import curriculum_stages, excitation_flights, run_curriculum
from aerodock.learning.runtime import Predictor


def test_default_stages_follow_the_paper(cfg):
    stages = curriculum_stages(cfg)
    assert (stages[0].depth_min_m, stages[0].depth_max_m) == (1.5, 1.8)
    assert np.allclose([s.depth_max_m for s in stages], [1.8, 1.5, 1.2, 0.9, 0.6])
    assert stages[-1].depth_min_m == 0.5


def test_excitation_flights_sweep_through_the_wake(cfg):
    logs = excitation_flights(cfg, 3, 0.6, 0.9, seed=1)
    for log in logs:
        rel = log.follower_pos_m - log.leader_pos_m
        lateral = np.linalg.norm(rel[:, :2], axis=1)
        assert lateral.max() > 0.8  # free air for the bias estimate
        assert lateral.min() < 0.2  # through the wake
        assert 0.5 < np.median(rel[:, 2]) < 1.0
        assert log.extra["true_field_mean_mps2"][:, 2].max() > 1.0


def test_run_curriculum_writes_logs_and_deploys_models(cfg, tmp_path):
    cfg = cfg.with_overrides({"curriculum": {"flights_per_stage": 2, "stage0_depth_m": [0.9, 1.2],
                                             "min_depth_m": 0.6}})
    summary = run_curriculum(cfg, tmp_path, seed=0, train_kwargs={"max_epochs": 5})
    assert [s["stage"] for s in summary["stages"]] == [0, 1]
    stage1 = load_flightlogs(tmp_path / "stage1.npz")
    assert all(lg.meta["compensation"] == "observer+model" for lg in stage1)
    assert np.abs(stage1[0].extra["feedforward_mps2"]).max() > 0  # the stage-0 model flew
    assert load_flightlogs(tmp_path / "stage0.npz")[0].meta["compensation"] == "observer"
    pred = Predictor.load(tmp_path / "models" / "final")
    assert pred.predict(np.zeros((1, 9)) + [0, 0, 0.8, 0, 0, 0, 0, 0, 0],
                        np.eye(3)[None]).shape == (1, 3)
    assert abs(summary["minutes"] - 4 * 12.5 / 60) < 0.01
