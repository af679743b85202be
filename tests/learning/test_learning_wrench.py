"""The so2-wrench model: torque labels from simulated logs, SO(2) equivariance of the torque,
training, runtime, model files and ONNX export; and the torque feed-forward's choice."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from aerodock.config import load_config
from aerodock.control.torque_feedforward import feedforward_torque_nm, hub_torque_nm
from aerodock.downwash.base import BodyState
from aerodock.geometry import euler_to_rotmat, rot_z
from aerodock.learning.datafiles import load_dataset, save_dataset
from aerodock.learning.dataset import DataError, build_dataset
from aerodock.learning.features import N_FEATURES, feature_map
from aerodock.learning.labels import (
    OBS_TORQUE_KEY,
    labels_from_logs,
    raw_torque_labels,
    torque_labels_from_logs,
)
from aerodock.learning.modelfile import load_model_dir
from aerodock.learning.models import build_model, load_torch_model
from aerodock.learning.runtime import Predictor
from aerodock.learning.train import TrainedModel, check_trainable, train_model


@pytest.fixture(scope="module")
def sim_logs(ideal_cfg):
    """Eight short simulated wake-excitation flights at 0.5-0.8 m (rigid bodies, torques), on the
    idealised world (the true attitude, a noisy unfiltered gyro, nominal vehicles): the labels'
    and the models' mechanisms, before a flight computer's filters blur them."""
    from aerodock.collect.curriculum import excitation_flights

    return excitation_flights(ideal_cfg, 8, 0.5, 0.8, seed=11)


@pytest.fixture(scope="module")
def sim_ds(sim_logs):
    return build_dataset(sim_logs)


@pytest.fixture(scope="module")
def trained_wrench(sim_ds):
    return train_model("so2-wrench", sim_ds, seed=0, max_epochs=60, patience=15)


def _random_wrench(seed: int = 3) -> TrainedModel:
    """An untrained so2-wrench model with non-trivial normalisation."""
    torch.manual_seed(seed)
    model = build_model("so2-wrench")
    rng = np.random.default_rng(seed)
    model.set_normalisation(rng.normal(0, 0.5, (50, N_FEATURES["so2-wrench"])),
                            np.concatenate([rng.normal(0, 2.0, (50, 3)),
                                            rng.normal(0, 0.05, (50, 3))], axis=1))
    return TrainedModel("so2-wrench", model.eval(), {"note": "random"})


def _inputs(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform(-0.8, 0.8, (n, 2)), rng.uniform(-0.2, 1.8, (n, 1)),
                        rng.normal(0, 0.4, (n, 6))], axis=1)
    rot = euler_to_rotmat(rng.normal(0, 0.15, n), rng.normal(0, 0.15, n), rng.uniform(-3, 3, n))
    return x, rot


# -- torque labels ---------------------------------------------------------------------------

def test_torque_labels_recover_the_true_wake_torque(sim_logs):
    labels, biases, _ = torque_labels_from_logs(sim_logs)
    errors, truths = [], []
    for log, lab in zip(sim_logs, labels, strict=True):
        valid = log.extra["label_valid"].astype(bool)
        errors.append((lab - log.extra["true_wake_torque_nm"])[valid])
        truths.append(log.extra["true_wake_torque_nm"][valid])
    err, true = np.concatenate(errors), np.concatenate(truths)
    size = np.sqrt(np.mean(true[:, :2] ** 2))  # roll and pitch carry the wake's torque
    assert size > 0.01  # the flights do cross the wake
    assert np.max(np.abs(np.median(err, axis=0))) < 0.05 * size
    assert np.median(np.abs(err[:, :2])) < 0.3 * size  # per-sample: gyro noise only
    assert all(b.source == "own" for b in biases)


def test_torque_labels_need_the_torque_extras(sim_logs):
    log = sim_logs[0]
    bare = replace(log, extra={k: v for k, v in log.extra.items() if k != OBS_TORQUE_KEY})
    with pytest.raises(ValueError, match="lacks extra 'follower_obs_torque_nm'") as err:
        raw_torque_labels(bare)
    assert "\n" not in str(err.value)
    ds = build_dataset([bare])
    assert ds.y_torque is None and ds.y is not None  # the force labels are still there
    with pytest.raises(DataError, match="no torque labels"):
        check_trainable(ds, kind="so2-wrench")
    check_trainable(ds, kind="so2-ext")
    mixed = build_dataset([bare, sim_logs[1]])
    with pytest.raises(DataError, match=f"flight {bare.name} has no torque labels"):
        train_model("so2-wrench", mixed, max_epochs=1)


def _radial_means(logs) -> tuple[float, float]:
    """Mean radial (outward) component of the force labels and of the true mean wake force over
    the samples 5-25 cm off the wake's axis, below the leader, m/s²."""
    labels, _, _ = labels_from_logs(logs)
    lab_r, true_r = [], []
    for log, lab in zip(logs, labels, strict=True):
        dp = log.follower_pos_m - log.leader_pos_m
        r = np.hypot(dp[:, 0], dp[:, 1])
        near = log.extra["label_valid"].astype(bool) & (r > 0.05) & (r < 0.25) & (dp[:, 2] > 0)
        e_r = dp[:, :2] / np.maximum(r, 1e-9)[:, None]
        lab_r.append(np.einsum("ni,ni->n", lab[:, :2], e_r)[near])
        true_r.append(np.einsum("ni,ni->n", log.extra["true_field_mean_mps2"][:, :2], e_r)[near])
    return float(np.mean(np.concatenate(lab_r))), float(np.mean(np.concatenate(true_r)))


def test_thrust_basis_labels_are_the_force_on_the_body():
    """Off the axis the wake pushes the follower outwards, and its torque tilts it inwards. The
    paper's labels (``a_obs - u``) count the thrust that tilt redirects as wake force and read the
    outward push as an inward one; along the measured thrust axis the labels find the push. (The
    jet fitted to real flights has almost no planar part, so the wake here is given DESIGN.md's
    outward 15 %: the label bases are what is tested. The settled start cut to 1 s: measured,
    the thrust basis within 3.6 % of the true push (3.4 % after 3 s), the command basis at 14 %
    of it (10 %).)"""
    from aerodock.collect.curriculum import excitation_flights

    base = load_config(None).with_overrides({"downwash": {"params": {"planar_ratio": 0.15}},
                                             "mission": {"settle_s": 1.0}}, source="test")
    means = {}
    for basis in ("command", "thrust"):
        cfg = base.with_overrides({"curriculum": {"label_basis": basis}}, source="test")
        logs = excitation_flights(cfg, 4, 0.3, 0.5, seed=11)
        assert {log.meta["label_basis"] for log in logs} == {basis}
        means[basis] = _radial_means(logs)
    label_cmd, true_r = means["command"]
    label_thrust, true_again = means["thrust"]
    assert true_r > 0.2 and true_again > 0.2  # the flights cross the wake's outward push
    assert abs(label_thrust - true_again) < 0.25 * true_again
    assert label_cmd < 0.5 * true_r  # the torque-induced tilt hides most of it


def test_recorder_torque_extras_have_the_right_shapes(sim_logs):
    log = sim_logs[0]
    for key in ("follower_obs_torque_nm", "follower_rotor_torque_nm",
                "follower_body_rates_radps", "true_wake_torque_nm"):
        arr = log.extra[key]
        assert arr.shape == (log.n_samples, 3), key
        assert np.all(np.isfinite(arr)), key
    # the gyro sees the vehicle turning (it is not the zeros of a missing reading)
    assert np.std(log.extra["follower_body_rates_radps"][5:], axis=0).min() > 1e-3


def test_dataset_torque_labels_are_world_frame_and_round_trip(sim_ds, sim_logs, tmp_path):
    assert sim_ds.y_torque is not None and sim_ds.y_torque_true is not None
    assert "torque_bias_nm" in sim_ds.meta["flights"][0]
    # the labels are the body-frame labels turned by the follower's attitude
    from aerodock.geometry import quat_to_rotmat

    log = sim_logs[0]
    labels = torque_labels_from_logs(sim_logs)[0][0]
    keep = log.extra["label_valid"].astype(bool)
    world = np.einsum("nij,nj->ni", quat_to_rotmat(log.follower_quat), labels)[keep]
    np.testing.assert_allclose(sim_ds.y_torque[sim_ds.flight_id == 0], world, atol=1e-12)
    again = load_dataset(save_dataset(tmp_path / "ds.npz", sim_ds))
    np.testing.assert_array_equal(again.y_torque, sim_ds.y_torque)
    np.testing.assert_array_equal(again.subset(np.arange(5)).y_torque_true,
                                  sim_ds.y_torque_true[:5])


# -- the model -------------------------------------------------------------------------------

def test_trained_wrench_points_the_torque_towards_the_wake_axis(trained_wrench):
    """Off the axis the wake pushes the rotors nearer the axis down: the torque is along +e_t
    (a3 x e_r), and the model learnt it from the torque labels."""
    pred = trained_wrench.predictor()
    assert pred.has_torque
    n = 8
    az = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x = np.zeros((n, 9))
    x[:, 0], x[:, 1], x[:, 2] = 0.1 * np.cos(az), 0.1 * np.sin(az), 0.6
    rot = np.tile(np.eye(3), (n, 1, 1))
    torque = pred.predict_torque(x, rot)
    e_t = np.stack([-np.sin(az), np.cos(az), np.zeros(n)], axis=1)
    along = np.sum(torque * e_t, axis=1)
    assert np.all(along > 0.01), along  # N m: the true torque there is several hundredths
    assert np.all(along > 3 * np.linalg.norm(torque - along[:, None] * e_t, axis=1))
    info = trained_wrench.info
    assert info["val_torque_vs_true_rmse_nm"] < 0.6 * info["val_true_torque_rms_nm"]
    assert info["val_rmse_torque_nm"] > 0 and info["val_rmse_mps2"] > 0


def test_wrench_force_fits_as_well_as_so2_ext(sim_ds, trained_wrench):
    ext = train_model("so2-ext", sim_ds, seed=0, max_epochs=60, patience=15)
    assert trained_wrench.info["val_rmse_mps2"] < 1.1 * ext.info["val_rmse_mps2"]


angle = st.floats(-np.pi, np.pi, allow_nan=False)
coord = st.floats(-1.5, 1.5, allow_nan=False)
tilt = st.floats(-0.5, 0.5, allow_nan=False)


@settings(max_examples=50, deadline=None)
@given(dp=st.lists(coord, min_size=3, max_size=3),
       v=st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=6, max_size=6),
       roll=tilt, pitch=tilt, yaw=angle, theta=angle)
def test_torque_is_so2_equivariant(dp, v, roll, pitch, yaw, theta):
    """Rotating the scene about the leader's axis rotates the world torque and leaves the
    follower's body-frame torque unchanged (its attitude turns with the scene)."""
    model, pred = _WRENCH
    x = np.array([*dp, *v], dtype=float)[None, :]
    rot = euler_to_rotmat(np.array([roll]), np.array([pitch]), np.array([yaw]))
    q = rot[0] @ rot_z(np.array(theta)) @ rot[0].T
    x2 = np.concatenate([x[:, 0:3] @ q.T, x[:, 3:6] @ q.T, x[:, 6:9] @ q.T], axis=1)
    rot2 = (q @ rot[0])[None]
    f1, t1 = pred.predict_wrench(x, rot)
    f2, t2 = pred.predict_wrench(x2, rot2)
    np.testing.assert_allclose(f2, f1 @ q.T, atol=1e-9)
    np.testing.assert_allclose(t2, t1 @ q.T, atol=1e-9)
    with torch.no_grad():
        force, torque = model.wrench(torch.as_tensor(x2), torch.as_tensor(rot2))
    np.testing.assert_allclose(torque.numpy(), t1 @ q.T, atol=1e-9)
    fol_r = euler_to_rotmat(np.array([0.1]), np.array([-0.2]), np.array([0.3]))
    ones = np.ones(1)

    def body_torque(xx, lead_r, f_r):
        lead = BodyState(np.zeros((1, 3)), xx[:, 3:6], lead_r, 7 * ones, ones)
        fol = BodyState(xx[:, 0:3], xx[:, 6:9], f_r, 7 * ones, ones)
        return pred.predict_torque_bodies(lead, fol)

    np.testing.assert_allclose(body_torque(x2, rot2, q @ fol_r), body_torque(x, rot, fol_r),
                               atol=1e-9)


_WRENCH = (_random_wrench().model.double(), _random_wrench().predictor())


def test_runtime_file_and_torch_agree(tmp_path):
    trained = _random_wrench()
    x, rot = _inputs(200)
    pred = Predictor.load(trained.save(tmp_path / "w"))
    spec, _, doc = load_model_dir(tmp_path / "w")
    assert spec.layer_sizes[0] == 10 and spec.layer_sizes[-1] == 6
    assert doc["torque_units"] == "N m NED" and len(doc["outputs"]) == 6
    with torch.no_grad():
        model64 = load_torch_model(tmp_path / "w").double()
        force, torque = model64.wrench(torch.as_tensor(x), torch.as_tensor(rot))
    got_f, got_t = pred.predict_wrench(x, rot)
    np.testing.assert_allclose(got_f, force.numpy(), atol=1e-10)
    np.testing.assert_allclose(got_t, torque.numpy(), atol=1e-10)
    np.testing.assert_allclose(pred.predict(x, rot), got_f, atol=0)
    single = np.stack([pred.predict_one(x[i], rot[i]) for i in range(20)])
    np.testing.assert_allclose(single, got_f[:20], atol=1e-12)
    # the force part is exactly so2-ext's computation on the first three outputs
    _, out_map = feature_map("so2-ext", x, rot)
    assert out_map.shape == (200, 3, 3)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_onnx_export_has_both_outputs_and_matches(tmp_path, dtype):
    pytest.importorskip("onnxruntime")
    import onnx

    from aerodock.deploy.export import (
        check_onnx,
        export_onnx,
        onnx_differences,
        read_onnx_metadata,
    )

    model_dir = _random_wrench().save(tmp_path / "w")
    path = export_onnx(model_dir, tmp_path / "w.onnx", dtype=dtype)
    graph = onnx.load(str(path)).graph
    assert [o.name for o in graph.output] == ["f_ext_mps2", "tau_ext_nm"]
    pred = Predictor.load(model_dir)
    diffs = onnx_differences(path, pred, n=300)
    tol = 1e-5 if dtype == "float32" else 1e-10
    assert set(diffs) == {"f_ext_mps2", "tau_ext_nm"}
    assert max(diffs.values()) < tol
    assert check_onnx(path, pred) == max(onnx_differences(path, pred).values())
    assert read_onnx_metadata(path)["aerodock.torque_units"] == "N m NED"
    with pytest.raises(ValueError, match="do not match"):  # a force-only model's predictor
        onnx_differences(path, _force_only_predictor())


def _force_only_predictor() -> Predictor:
    torch.manual_seed(0)
    model = build_model("so2-ext").eval()
    return Predictor(model.spec(), model.weights())


def test_force_only_models_have_no_torque():
    pred = _force_only_predictor()
    assert not pred.has_torque
    x, rot = _inputs(3)
    with pytest.raises(ValueError, match="predicts no torque"):
        pred.predict_torque(x, rot)


# -- the torque feed-forward -----------------------------------------------------------------

def test_feedforward_uses_the_learnt_torque_when_there_is_one():
    wrench = _random_wrench().predictor()
    force_only = _force_only_predictor()
    x, rot = _inputs(4)
    ones = np.ones(4)
    fol_r = euler_to_rotmat(0.1 * ones, -0.1 * ones, ones)
    lead = BodyState(np.zeros((4, 3)), x[:, 3:6], rot, 7 * ones, 0.7 * ones)
    fol = BodyState(x[:, 0:3], x[:, 6:9], fol_r, 7 * ones, 0.7 * ones)
    offsets = load_config(None).vehicle.diagonal_m / 2 * np.array(
        [[0.7071, 0.7071, 0], [-0.7071, 0.7071, 0], [-0.7071, -0.7071, 0], [0.7071, -0.7071, 0]])
    learnt = feedforward_torque_nm(wrench, lead, fol, offsets)
    want = np.einsum("nji,nj->ni", fol_r, wrench.predict_torque(np.concatenate(
        [x[:, 0:3], x[:, 3:6], x[:, 6:9]], axis=1), rot))
    np.testing.assert_allclose(learnt, want, atol=1e-12)
    np.testing.assert_allclose(feedforward_torque_nm(force_only, lead, fol, offsets),
                               hub_torque_nm(force_only, lead, fol, offsets), atol=0)


# -- the command line ------------------------------------------------------------------------

def test_cli_trains_evaluates_and_exports_a_wrench_model(tmp_path, sim_logs):
    import json

    import typer
    from typer.testing import CliRunner

    from aerodock.cli.learning import evaluate_command, export_command, train_command
    from aerodock.flightlog import save_flightlogs

    app = typer.Typer()
    app.command("train")(train_command)
    app.command("evaluate")(evaluate_command)
    app.command("export")(export_command)
    runner = CliRunner()
    save_flightlogs(tmp_path / "train.npz", sim_logs[:6])
    save_flightlogs(tmp_path / "test.npz", sim_logs[6:])
    res = runner.invoke(app, ["train", "--model", "so2-wrench", "--data",
                              str(tmp_path / "train.npz"), "--out", str(tmp_path / "w"),
                              "--max-epochs", "3", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["kind"] == "so2-wrench"
    assert out["val_rmse_torque_nm"] > 0 and out["val_true_torque_rms_nm"] > 0
    res = runner.invoke(app, ["evaluate", "--model", str(tmp_path / "w"), "--data",
                              str(tmp_path / "test.npz"), "--json"])
    assert res.exit_code == 0, res.output
    torque = json.loads(res.stdout)["torque"]["interaction"]
    assert torque["model_vs_true"]["rmse_nm"]["overall"] > 0 and torque["true_rms_nm"] > 0
    res = runner.invoke(app, ["export", "--model", str(tmp_path / "w"), "--out",
                              str(tmp_path / "w.onnx"), "--json"])
    if res.exit_code == 0:  # onnx installed
        assert json.loads(res.stdout)["max_abs_diff_vs_numpy_torque_nm"] < 1e-5
    # logs without torque observations: one line, naming the missing extra, nothing written
    bare = [replace(log, extra={k: v for k, v in log.extra.items() if k != OBS_TORQUE_KEY})
            for log in sim_logs[:2]]
    save_flightlogs(tmp_path / "bare.npz", bare)
    res = runner.invoke(app, ["train", "--model", "so2-wrench", "--data",
                              str(tmp_path / "bare.npz"), "--out", str(tmp_path / "none")])
    assert res.exit_code == 2 and not (tmp_path / "none").exists()
    assert "follower_obs_torque_nm" in res.stderr and res.stderr.count("\n") == 1


def test_saved_docking_logs_follow_the_label_basis(short_cfg):
    """``dock --save-logs`` writes the basis the configuration asks for: the thrust along the
    logged (measured) attitude, which real logs without a command log give too. The basis changes
    what is logged, never the flight. (The mission's waiting times cut: the gap's medians 0.088
    and 0.064 m/s², 0.103 and 0.086 with the configured timing.)"""
    from aerodock.control.compensation import Compensation
    from aerodock.geometry import quat_to_rotmat, thrust_accel
    from aerodock.mission import MissionSpec, run_campaign

    base = short_cfg
    spec = MissionSpec(trials=2, compensation=Compensation.OBSERVER, seed=4)
    logs = {basis: run_campaign(base.with_overrides({"curriculum": {"label_basis": basis}},
                                                    source="test"), spec, record="full").logs
            for basis in ("command", "thrust")}
    for cmd_log, log in zip(logs["command"], logs["thrust"], strict=True):
        assert (cmd_log.meta["label_basis"], log.meta["label_basis"]) == ("command", "thrust")
        np.testing.assert_array_equal(cmd_log.follower_obs_accel_mps2,
                                      log.follower_obs_accel_mps2)  # the same flight
        want = thrust_accel(quat_to_rotmat(log.follower_quat), log.follower_thrust_n,
                            log.meta["follower_mass_kg"])
        np.testing.assert_allclose(log.follower_cmd_accel_mps2, want, atol=1e-9)
        # the two bases differ by the attitude loop's tracking error (lag, disturbances)
        gap = np.abs(want[:, :2] - cmd_log.follower_cmd_accel_mps2[:, :2])
        assert 0.01 < np.median(gap) < 1.0


def test_a_torque_feedforward_on_command_basis_labels_is_warned_about(sim_ds, trained_wrench,
                                                                       tmp_path):
    """The model file records its labels' basis; flying command-basis labels with the torque
    feed-forward draws a warning (README: Label basis), the thrust basis or no feed-forward none."""
    from aerodock.deploy.compatibility import model_warnings

    assert sim_ds.summary()["label_bases"] == ["command"]
    trained_wrench.save(tmp_path / "model")
    pred = Predictor.load(tmp_path / "model")
    assert pred.meta["training"]["data"]["label_bases"] == ["command"]
    cfg = load_config(None)
    with_ff = cfg.with_overrides({"control": {"torque_feedforward": True}}, source="test")
    assert model_warnings(pred, cfg) == []
    (note,) = model_warnings(pred, with_ff)
    assert "command basis" in note and "label_basis" in note and "\n" not in note
    thrust_doc = {**pred.meta, "training": {**pred.meta["training"], "data": {
        **pred.meta["training"]["data"], "label_bases": ["thrust"]}}}
    assert model_warnings(thrust_doc, with_ff) == []
