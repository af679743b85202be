"""The leader-aware kind ``so2-leader``: wake scales, extrapolation to an unseen leader, runtime."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.downwash.base import BodyState
from aerodock.flightlog import FlightLog
from aerodock.learning.dataset import build_dataset, concat_datasets
from aerodock.learning.features import feature_map, hover_induced_velocity_mps, wake_scales
from aerodock.learning.runtime import Predictor
from aerodock.learning.train import train_model
from tests.learning.learning_synth import make_logs, scaled_field

MASS_KG, RADIUS_M, N_ROTORS = 0.7, 0.0635, 4
VEHICLES = {"leader_mass_kg": MASS_KG, "leader_rotor_radius_m": RADIUS_M,
            "leader_n_rotors": N_ROTORS, "follower_mass_kg": MASS_KG,
            "follower_rotor_radius_m": RADIUS_M, "follower_n_rotors": N_ROTORS}


def _leader_logs(seed: int, thrust_factor: float, n_flights: int = 6) -> list[FlightLog]:
    """Flights under a leader of thrust ``thrust_factor * m g`` (logged as
    ``extra["leader_thrust_n"]``), whose wake is the synthetic field times ``thrust_factor``:
    the induced velocity squared scales with the thrust at a fixed rotor geometry."""
    return [scaled_field(log, thrust_factor,
                         {**VEHICLES, "name": f"{log.name}_T{thrust_factor:g}"},
                         {"leader_thrust_n": np.full(log.n_samples,
                                                     thrust_factor * MASS_KG * 9.81)})
            for log in make_logs(np.random.default_rng(seed), n_flights=n_flights)]


def test_wake_scales_are_momentum_theory():
    """v_h = sqrt(T / (2 rho n pi R^2)); size sqrt(n) R; the follower's from m g."""
    scales = wake_scales([MASS_KG * 9.81], RADIUS_M, N_ROTORS, MASS_KG, RADIUS_M, N_ROTORS)
    v_h = np.sqrt(MASS_KG * 9.81 / (2 * 1.225 * N_ROTORS * np.pi * RADIUS_M**2))
    np.testing.assert_allclose(scales[0], [v_h, 2 * RADIUS_M, v_h, 2 * RADIUS_M], rtol=1e-12)
    assert 7.0 < v_h < 8.0  # 0.7 kg on four 5-inch propellers: 6.9 N over 0.051 m^2
    np.testing.assert_allclose(hover_induced_velocity_mps(4 * MASS_KG * 9.81, RADIUS_M, N_ROTORS),
                               2 * v_h)


def test_leader_kind_needs_wake_scales():
    x, rot = np.zeros((1, 9)), np.eye(3)[None]
    with pytest.raises(ValueError, match="wake_scales"):
        feature_map("so2-leader", x, rot)
    with pytest.raises(ValueError, match="positive"):
        feature_map("so2-leader", x, rot, wake_scales=np.array([[1.0, 0.0, 1.0]]))


def test_dataset_without_rotors_is_refused_by_name():
    logs = _leader_logs(0, 1.0, n_flights=2)
    bare = [FlightLog(**{k: getattr(log, k) for k in (
        "t_s", "leader_pos_m", "leader_vel_mps", "leader_quat", "follower_pos_m",
        "follower_vel_mps", "follower_quat", "follower_cmd_accel_mps2", "follower_thrust_n",
        "follower_obs_accel_mps2")}, meta={"name": "bare"}, extra={}) for log in logs[:1]]
    with pytest.raises(ValueError, match="bare.*leader_mass_kg"):
        train_model("so2-leader", build_dataset(bare), max_epochs=1)


@pytest.fixture(scope="module")
def two_leader_models():
    """so2 and so2-leader trained on leaders of 0.6 and 1.0 m g thrust (seed 0)."""
    train = concat_datasets([build_dataset(_leader_logs(1, 0.6)),
                             build_dataset(_leader_logs(2, 1.0))])
    return {kind: train_model(kind, train, seed=0, max_epochs=80) for kind in
            ("so2", "so2-leader")}


def test_leader_kind_extrapolates_to_an_unseen_leader(two_leader_models):
    """A third leader of 1.5 m g (beyond both training leaders): so2 predicts the training
    leaders' average wake, so2-leader scales it. Held-out RMSE against the true field:
    so2-leader's at most half of so2's, and at most 0.35 m/s^2 (the field's RMS is ~1 m/s^2)."""
    test = build_dataset(_leader_logs(3, 1.5))
    rmse = {}
    for kind, trained in two_leader_models.items():
        pred = trained.predictor()
        scales = test.wake_scales() if pred.needs_wake_scales else None
        err = pred.predict(test.x, test.leader_R, scales) - test.y_true_mean
        rmse[kind] = float(np.sqrt(np.mean(err**2)))
    true_rms = float(np.sqrt(np.mean(test.y_true_mean**2)))
    assert true_rms > 0.8, true_rms
    assert rmse["so2-leader"] <= 0.5 * rmse["so2"], rmse
    assert rmse["so2-leader"] <= 0.35, rmse


def test_saved_leader_model_runs_the_same_and_from_bodies(two_leader_models, tmp_path):
    """The model file round trip, the default scales (the training data's median) and
    predict_bodies (the leader's thrust from its BodyState, the rotors from model.json)."""
    trained = two_leader_models["so2-leader"]
    path = trained.save(tmp_path / "m")
    pred = Predictor.load(path)
    assert pred.needs_wake_scales and pred.rotor_geometry == {
        "leader": (RADIUS_M, N_ROTORS), "follower": (RADIUS_M, N_ROTORS)}
    rng = np.random.default_rng(4)
    n = 20
    x = np.concatenate([rng.normal(0, 0.2, (n, 2)), rng.uniform(0.3, 1.0, (n, 1)),
                        rng.normal(0, 0.3, (n, 6))], axis=1)
    rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    thrust = np.full(n, 1.3 * MASS_KG * 9.81)
    scales = wake_scales(thrust, RADIUS_M, N_ROTORS, MASS_KG, RADIUS_M, N_ROTORS)
    want = trained.predict(x, rot, scales)
    np.testing.assert_allclose(pred.predict(x, rot, scales), want, atol=1e-5)
    np.testing.assert_allclose(pred.predict_one(x[0], rot[0], scales[0]), want[0], atol=1e-5)
    leader = BodyState(p=np.zeros((n, 3)), v=x[:, 3:6], R=rot, thrust_n=thrust,
                       mass_kg=np.full(n, MASS_KG))
    follower = BodyState(p=x[:, 0:3], v=x[:, 6:9], R=rot, thrust_n=np.full(n, 6.9),
                         mass_kg=np.full(n, MASS_KG))
    np.testing.assert_allclose(pred.predict_bodies(leader, follower), want, atol=1e-5)
    # no thrust known: the leader's hover thrust m g
    hover = BodyState(p=leader.p, v=leader.v, R=rot, thrust_n=np.full(n, np.nan),
                      mass_kg=leader.mass_kg)
    hover_scales = wake_scales(np.full(n, MASS_KG * 9.81), RADIUS_M, N_ROTORS, MASS_KG,
                               RADIUS_M, N_ROTORS)
    np.testing.assert_allclose(pred.predict_bodies(hover, follower),
                               pred.predict(x, rot, hover_scales), atol=1e-12)
    # no scales given: the training data's median
    np.testing.assert_allclose(pred.predict(x, rot),
                               pred.predict(x, rot, pred.default_wake_scales), atol=1e-12)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_leader_model_exports_to_onnx_with_its_scales(two_leader_models, tmp_path, dtype):
    """The ONNX graph takes a third input, wake_scales (n, 3), and passes the export's own
    parity check against the NumPy predictor (random leaders of 2-9 m/s induced velocity)."""
    pytest.importorskip("onnxruntime")
    from aerodock.deploy.export import export_checked, onnx_differences

    model_dir = two_leader_models["so2-leader"].save(tmp_path / "m")
    out, diffs = export_checked(model_dir, tmp_path / f"m_{dtype}.onnx", dtype=dtype)
    assert diffs is not None
    assert max(diffs.values()) < (1e-5 if dtype == "float32" else 1e-10), diffs
    import onnxruntime as ort

    sess = ort.InferenceSession(str(out), providers=["CPUExecutionProvider"])
    assert [i.name for i in sess.get_inputs()] == ["x", "leader_R", "wake_scales"]
    # a so2 model's file keeps its two inputs
    so2_out, _ = export_checked(two_leader_models["so2"].save(tmp_path / "s"),
                                tmp_path / "s.onnx", dtype=dtype)
    so2_sess = ort.InferenceSession(str(so2_out), providers=["CPUExecutionProvider"])
    assert [i.name for i in so2_sess.get_inputs()] == ["x", "leader_R"]
    assert max(onnx_differences(so2_out, Predictor.load(tmp_path / "s")).values()) < 1e-5


def test_node_step_passes_the_scales_and_defaults_to_the_model_file(two_leader_models,
                                                                     tmp_path):
    from aerodock.node.core import VehicleState, model_inputs, prediction_step

    pred = Predictor.load(two_leader_models["so2-leader"].save(tmp_path / "m"))
    lead = VehicleState(np.array([0.0, 0.0, -2.0]), np.zeros(3), np.eye(3), 1.0)
    fol = VehicleState(np.array([0.05, 0.02, -1.5]), np.array([0.1, 0.0, 0.0]), np.eye(3), 1.0)
    x, rot = model_inputs(lead, fol)
    default = prediction_step(pred, lead, fol, 1.01, max_age_s=0.05)
    np.testing.assert_allclose(default.f_ext_mps2, pred.predict(x[None], rot[None])[0],
                               atol=1e-12)
    strong = wake_scales([1.5 * MASS_KG * 9.81], RADIUS_M, N_ROTORS, MASS_KG, RADIUS_M,
                         N_ROTORS)[0]
    given = prediction_step(pred, lead, fol, 1.01, max_age_s=0.05, wake_scales=strong)
    np.testing.assert_allclose(given.f_ext_mps2, pred.predict(x[None], rot[None], strong)[0],
                               atol=1e-12)
    assert not default.stale and not given.stale
    assert np.linalg.norm(given.f_ext_mps2 - default.f_ext_mps2) > 0.1
