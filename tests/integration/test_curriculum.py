"""Curriculum collection: stages get closer, each deploys the previous stage's model."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.collect.curriculum import curriculum_stages, run_curriculum
from aerodock.flightlog import load_flightlogs
from aerodock.learning.runtime import Predictor


def test_default_stages_follow_the_paper_then_go_deep(cfg):
    stages = curriculum_stages(cfg, deep=False)
    assert (stages[0].depth_min_m, stages[0].depth_max_m) == (1.5, 1.8)
    assert np.allclose([s.depth_max_m for s in stages], [1.8, 1.5, 1.2, 0.9, 0.6])
    assert stages[-1].depth_min_m == 0.5
    deep = curriculum_stages(cfg)
    assert deep[:5] == stages
    assert [(s.index, s.depth_min_m, s.depth_max_m, s.deep) for s in deep[5:]] == [
        (5, 0.3, 0.5, True), (6, 0.27, 0.3, True)]


@pytest.fixture(scope="module")
def collected(short_cfg, tmp_path_factory):
    """A small curriculum: stage 0 at 0.6-0.9 m without a model, stage 1 (the paper's last) at
    0.3-0.6 m, then one deep stage at 0.27-0.3 m (the docking depth), 2 + 2 + 3 flights; its
    folder, summary and configuration. (The bookkeeping and the flights' pattern hold whatever
    the settled start's length: the short one of tests/short_mission.py.)"""
    cfg = short_cfg.with_overrides({"curriculum": {
        "flights_per_stage": 2, "stage0_depth_m": [0.6, 0.9], "min_depth_m": 0.3,
        "deep_depths_m": [0.27], "deep_flights_per_stage": 3}})
    out = tmp_path_factory.mktemp("curriculum")
    summary = run_curriculum(cfg, out, seed=0, train_kwargs={"max_epochs": 5})
    return out, summary, cfg


def test_deep_stages_fly_the_bar_above_the_follower(cfg, collected):
    from aerodock.collect.curriculum import bar_out_of_the_way

    assert bar_out_of_the_way(cfg, 0.5).platform.cable_length_m == 0.36  # paper's stages as is
    out, _, flown = collected
    logs = load_flightlogs(out / "stage2.npz")  # the deep stage, 0.27-0.3 m
    gp = flown.gripper
    gate_top_depth = 0.27 - gp.mount_height_m - gp.gate_height_m  # at the shallowest depth
    for log in logs:
        assert log.meta["cable_length_m"] < 0.2
        bar_depth = log.extra["bar_pos_m"][:, 2] - log.leader_pos_m[:, 2]
        assert np.all(bar_depth < gate_top_depth + 0.005)  # the bar hangs above the gate


def test_excitation_flights_sweep_through_the_wake(collected):
    out, _, _ = collected
    logs = load_flightlogs(out / "stage0.npz")  # 0.6-0.9 m below the leader, without a model
    for log in logs:
        rel = log.follower_pos_m - log.leader_pos_m
        lateral = np.linalg.norm(rel[:, :2], axis=1)
        assert lateral.max() > 0.8  # free air for the bias estimate
        assert lateral.min() < 0.2  # through the wake
        assert 0.5 < np.median(rel[:, 2]) < 1.0
        assert log.extra["true_field_mean_mps2"][:, 2].max() > 1.0


def test_run_curriculum_writes_logs_and_deploys_models(collected):
    out, summary, _ = collected
    assert [s["stage"] for s in summary["stages"]] == [0, 1, 2]
    assert np.allclose(summary["stages"][2]["depth_band_m"], [0.27, 0.3])
    # the paper's model: trained after the last paper stage, before the deep one
    assert summary["paper_model"].endswith("paper")
    paper = Predictor.load(out / "models" / "paper")
    stage1 = Predictor.load(out / "models" / "stage1")
    x = np.zeros((1, 9)) + [0, 0, 0.5, 0, 0, 0, 0, 0, 0]
    assert np.array_equal(paper.predict(x, np.eye(3)[None]), stage1.predict(x, np.eye(3)[None]))
    stage1 = load_flightlogs(out / "stage1.npz")
    assert all(lg.meta["compensation"] == "observer+model" for lg in stage1)
    assert np.abs(stage1[0].extra["feedforward_mps2"]).max() > 0  # the stage-0 model flew
    assert load_flightlogs(out / "stage0.npz")[0].meta["compensation"] == "observer"
    pred = Predictor.load(out / "models" / "final")
    assert pred.predict(np.zeros((1, 9)) + [0, 0, 0.8, 0, 0, 0, 0, 0, 0],
                        np.eye(3)[None]).shape == (1, 3)
    assert abs(summary["minutes"] - 7 * 12.5 / 60) < 0.01  # 2 + 2 + 3 (deep) flights


def test_the_fast_leader_curriculum_flies_the_targets_leader_speeds(short_cfg):
    """examples/curriculum_fast_leader.toml: the leader drifts at up to 0.6 m/s, covering the
    docking targets' 0.5 m/s; the default drifts at up to 0.3 m/s
    (docs/results/fitted-wake-targets.md)."""
    from pathlib import Path

    from aerodock.collect.curriculum import excitation_flights
    from aerodock.config import load_config

    example = Path(__file__).resolve().parents[2] / "examples" / "curriculum_fast_leader.toml"
    fast = load_config(example).curriculum
    overrides = {"curriculum": {"leader_drift_max_mps": fast.leader_drift_max_mps,
                                "drift_fraction": fast.drift_fraction}}
    assert short_cfg.curriculum.leader_drift_max_mps == 0.3
    logs = excitation_flights(short_cfg.with_overrides(overrides), 8, 0.6, 0.9, seed=3)
    speeds = np.array([log.meta["leader_speed_mps"] for log in logs])
    # the logged leader flies it (its mean velocity; it also sways under its own control)
    measured = np.array([np.linalg.norm(log.leader_vel_mps.mean(axis=0)) for log in logs])
    np.testing.assert_allclose(measured, speeds, rtol=0.15, atol=0.03)
    assert speeds.max() > 0.5 and speeds.max() <= 0.6, speeds
