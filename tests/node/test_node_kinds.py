"""The node runs every model kind of the registry alike, the deep-sets kind among them: one tick
for each kind's model folder, and ``aerodock node`` end to end on a trained deep-sets model (its
four wake scales from the model file, as with the other leader-aware kinds)."""

from __future__ import annotations

import numpy as np
import pytest
from node_helpers import orbit_log, random_model

from aerodock.config import load_config
from aerodock.geometry import euler_to_rotmat
from aerodock.learning.kinds import get_kind, trained_kinds
from aerodock.learning.runtime import Predictor
from aerodock.node.core import (
    VehicleState,
    configured_wake_scales,
    model_inputs,
    prediction_step,
)


def _state(stamp_s: float, p=(0.0, 0.0, -2.0), v=(0.0, 0.0, 0.0), rot=None) -> VehicleState:
    return VehicleState(np.array(p, dtype=float), np.array(v, dtype=float),
                        np.eye(3) if rot is None else rot, received_s=stamp_s, stamp_s=stamp_s)


@pytest.mark.parametrize("kind", trained_kinds())
def test_one_tick_of_every_kind_is_its_predictor(kind, tmp_path):
    """A model folder of each kind: the tick's output is the predictor's on the node's inputs,
    given the configured vehicles' wake scales when the kind reads them (all four for
    ``deepsets``), finite and not zero."""
    predictor = Predictor.load(random_model(tmp_path / kind, kind=kind))
    cfg = load_config()
    scales = configured_wake_scales(predictor, cfg.leader, cfg.vehicle)
    record = get_kind(kind)
    assert (scales is None) == (record.n_wake_scales == 0)
    if scales is not None:
        assert scales.shape == (record.n_wake_scales,)
    leader = _state(1.0, rot=euler_to_rotmat(0.05, -0.03, 0.7))
    follower = _state(1.0, p=(0.2, -0.1, -1.4), v=(0.0, 0.3, 0.1))
    out = prediction_step(predictor, leader, follower, 1.01, max_age_s=0.05,
                          wake_scales=scales)
    x, rot = model_inputs(leader, follower)
    want = predictor.predict(x[None], rot[None], None if scales is None else scales[None])[0]
    assert not out.stale and out.reason == ""
    np.testing.assert_allclose(out.f_ext_mps2, want, rtol=1e-12, atol=1e-12)
    assert np.all(np.isfinite(out.f_ext_mps2)) and np.linalg.norm(out.f_ext_mps2) > 1e-3


@pytest.fixture(scope="module")
def deepsets_model(tmp_path_factory):
    """A small deep-sets model trained on a small and a large follower, saved (its model file
    records the training flights' wake scales)."""
    pytest.importorskip("torch")
    from aerodock.learning.dataset import build_dataset, concat_datasets
    from aerodock.learning.train import train_model
    from tests.learning.test_learning_pair import LARGE, _follower_logs

    train = concat_datasets([build_dataset(_follower_logs(1, 1.0)),
                             build_dataset(_follower_logs(2, LARGE))])
    trained = train_model("deepsets", train, seed=0, max_epochs=5, hidden=(16, 16))
    return trained.save(tmp_path_factory.mktemp("node") / "deepsets")


def test_aerodock_node_runs_a_deepsets_model_folder(deepsets_model, tmp_path):
    """``aerodock node --model DEEPSETS`` over ROS 2 on localhost: it names the kind and its
    four wake scales, and each fresh output is the offline predictor's on the inputs the node
    reports it used."""
    pytest.importorskip("rclpy")
    pytest.importorskip("nav_msgs.msg")
    pytest.importorskip("diagnostic_msgs.msg")
    from aerodock.node.core import to_output_frame
    from aerodock.node.replay import free_domain_id, replay, start_node, write_mapping

    pred = Predictor.load(deepsets_model)
    assert pred.kind == "deepsets" and pred.default_wake_scales.shape == (4,)
    mapping = write_mapping(tmp_path / "mapping.toml", "/alpha/odom", "/bravo/odom")
    domain = free_domain_id()
    proc = start_node(deepsets_model, mapping, domain, max_age_s=0.05, duration_s=40.0)
    try:
        rec = replay(orbit_log(1.5), domain, leader_topic="/alpha/odom",
                     follower_topic="/bravo/odom")
    finally:
        proc.kill()
        _, stderr = proc.communicate(timeout=30)
    assert "aerodock node: deepsets model" in stderr
    assert "follower size" in stderr and "from the training flights" in stderr
    outputs = {row[1]: row for row in rec.outputs}
    fresh = [(outputs[stamp], v) for _, stamp, v in rec.diagnostics
             if stamp in outputs and v["stale"] == "false"]
    assert len(fresh) > 50, f"only {len(fresh)} fresh outputs"
    for row, values in fresh:
        leader = rec.sent["leader"][float(values["leader_stamp"])]
        follower = rec.sent["follower"][float(values["follower_stamp"])]
        want = to_output_frame(pred.predict_one(*model_inputs(leader, follower)), "enu")
        np.testing.assert_allclose(row[2:], want, rtol=0, atol=1e-9)
    assert np.median([np.linalg.norm(row[2:]) for row, _ in fresh]) > 0.01
