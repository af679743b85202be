"""Training on a known equivariant field, evaluation, sample efficiency and the CLI commands."""

from __future__ import annotations

import json

import numpy as np
import pytest
import typer
from learning_synth import make_logs
from typer.testing import CliRunner

from aerodock.cli.learning import evaluate_command, export_command, train_command
from aerodock.experiments.sample_efficiency import sample_efficiency
from aerodock.flightlog import save_flightlogs
from aerodock.learning.datafiles import save_dataset
from aerodock.learning.dataset import build_dataset
from aerodock.learning.evaluate import evaluate, regression_metrics
from aerodock.learning.runtime import Predictor
from aerodock.learning.train import (
    MIN_FLIGHTS_FOR_FLIGHT_SPLIT,
    train_model,
    validation_split,
)


@pytest.fixture(scope="module")
def held_out():
    """Flights the models never see (different random draws)."""
    return build_dataset(make_logs(np.random.default_rng(99), n_flights=4, duration_s=15.0))


def test_so2_learns_the_equivariant_field(trained_so2, held_out):
    res = evaluate(trained_so2.predictor(), held_out)
    inter = res["interaction"]
    assert inter["n"] > 200
    model_rmse = inter["model"]["rmse_mps2"]["overall"]
    zero_rmse = inter["zero"]["rmse_mps2"]["overall"]
    floor = inter["error_floor"]["rmse_mps2"]["overall"]
    assert model_rmse < 0.4 * zero_rmse
    assert model_rmse < floor + 0.1  # close to the noise floor (noise sd 0.3 m/s^2)
    assert inter["model_vs_true_mean"]["rmse_mps2"]["overall"] < 0.2
    assert inter["model"]["r2"]["overall"] > inter["error_floor"]["r2"]["overall"] - 0.1
    assert inter["zero"]["r2"]["overall"] < 0.0
    assert res["all"]["n"] == held_out.n
    assert trained_so2.info["split"] == "time-blocks"  # 6 flights: too few to split by flight
    assert trained_so2.info["val_flights"] == []


@pytest.mark.parametrize("kind", ["so2-ext", "mlp"])
def test_other_kinds_learn_too(synth_ds, held_out, kind):
    trained = train_model(kind, synth_ds, seed=0, max_epochs=25, patience=8)
    inter = evaluate(trained.predictor(), held_out)["interaction"]
    assert inter["model"]["rmse_mps2"]["overall"] < 0.6 * inter["zero"]["rmse_mps2"]["overall"]


def test_training_is_deterministic(synth_ds):
    small = synth_ds.subset(np.arange(0, synth_ds.n, 4))
    a = train_model("so2", small, seed=5, max_epochs=3)
    b = train_model("so2", small, seed=5, max_epochs=3)
    c = train_model("so2", small, seed=6, max_epochs=3)
    wa, wb, wc = a.model.weights(), b.model.weights(), c.model.weights()
    assert all(np.array_equal(x[0], y[0]) for x, y in zip(wa, wb))
    assert not np.array_equal(wa[0][0], wc[0][0])
    assert a.history["val_loss"] == b.history["val_loss"]


def test_validation_split_by_flight_or_time_blocks(synth_ds):
    rng = np.random.default_rng(0)
    tr, va, method = validation_split(synth_ds, 0.2, rng, "flight")
    assert method == "flight"
    assert not set(synth_ds.flight_id[tr]) & set(synth_ds.flight_id[va])
    # "auto": by flight only with MIN_FLIGHTS_FOR_FLIGHT_SPLIT flights or more.
    tr, va, method = validation_split(synth_ds, 0.2, rng)
    assert method == "time-blocks" and len(va) and len(tr)
    many = build_dataset(make_logs(np.random.default_rng(5), n_flights=MIN_FLIGHTS_FOR_FLIGHT_SPLIT,
                                   duration_s=4.0))
    tr, va, method = validation_split(many, 0.2, rng)
    assert method == "flight"
    assert 4 <= len(np.unique(many.flight_id[va])) <= 5
    assert not set(many.flight_id[tr]) & set(many.flight_id[va])
    tr, va, method = validation_split(many, 0.2, rng, "time-blocks")
    assert method == "time-blocks"
    with pytest.raises(ValueError, match="unknown split"):
        validation_split(many, 0.2, rng, "random")
    with pytest.raises(ValueError, match="unknown split"):
        train_model("so2", many, split="random")
    one = synth_ds.subset(synth_ds.flight_id == 1)
    tr, va, method = validation_split(one, 0.2, rng)
    assert method == "time-blocks" and len(va) and len(tr)
    assert len(np.intersect1d(tr, va)) == 0
    trained = train_model("so2", one, max_epochs=2)
    assert trained.info["split"] == "time-blocks"


def test_train_rejects_bad_input(synth_ds):
    with pytest.raises(ValueError, match="unknown model kind"):
        train_model("resnet", synth_ds)
    with pytest.raises(ValueError, match="too few"):
        train_model("so2", synth_ds.subset(np.arange(5)))


def test_regression_metrics():
    y = np.array([[1.0, 0, 2], [3, 0, 4], [5, 0, 6]])
    m = regression_metrics(y, y)
    assert m["rmse_mps2"]["overall"] == 0.0 and m["r2"]["x"] == 1.0
    assert m["r2"]["y"] is None  # constant labels: undefined
    z = regression_metrics(np.zeros_like(y), y)
    np.testing.assert_allclose(z["rmse_mps2"]["x"], np.sqrt(35 / 3))


def test_sample_efficiency_writes_json_and_figure(tmp_path, synth_ds, held_out):
    small = synth_ds.subset(np.arange(0, synth_ds.n, 2))  # 1 min at 50 Hz
    res = sample_efficiency(
        small, held_out, kinds=("so2", "mlp"), minutes=(0.25, 0.5, 30), seeds=(0, 1),
        out_dir=tmp_path, train_kwargs={"max_epochs": 3},
    )
    assert res["minutes"] == [0.25, 0.5] and res["skipped_minutes"] == [30.0]
    assert "available" in res["skip_reason"]
    for kind in ("so2", "mlp"):
        entry = res["models"][kind]
        assert len(entry["runs"]) == 4 and len(entry["rmse_mean"]) == 2
        assert all(np.isfinite(entry["rmse_mean"])) and all(s >= 0 for s in entry["rmse_sd"])
    assert res["zero"]["all"] > 0 and res["error_floor"]["all"] > 0
    doc = json.loads((tmp_path / "sample_efficiency.json").read_text())
    assert doc["models"]["so2"]["rmse_mean"] == res["models"]["so2"]["rmse_mean"]
    png = (tmp_path / "sample_efficiency.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000


# -- CLI commands ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cli():
    app = typer.Typer()
    app.command("train")(train_command)
    app.command("evaluate")(evaluate_command)
    app.command("export")(export_command)
    return app, CliRunner()


def test_cli_train_evaluate_export(tmp_path, cli, synth_logs, held_out):
    app, runner = cli
    save_flightlogs(tmp_path / "logs" / "train.npz", synth_logs[:3])
    save_flightlogs(tmp_path / "logs" / "more.npz", synth_logs[3:])
    save_dataset(tmp_path / "test.npz", held_out)
    res = runner.invoke(app, ["train", "--model", "so2-ext", "--data", str(tmp_path / "logs"),
                              "--out", str(tmp_path / "model"), "--minutes", "1",
                              "--max-epochs", "3", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["kind"] == "so2-ext" and out["minutes"] == pytest.approx(1.0, abs=0.01)
    assert Predictor.load(tmp_path / "model").kind == "so2-ext"
    assert len(out["history"]["train_loss"]) == len(out["history"]["val_loss"]) == 3
    assert out["learning_curve"] is None
    saved = json.loads((tmp_path / "model" / "model.json").read_text())
    assert saved["training"]["history"] == out["history"]

    res = runner.invoke(app, ["train", "--model", "mlp", "--data", str(tmp_path / "logs"),
                              "--out", str(tmp_path / "mlp"), "--max-epochs", "4",
                              "--split", "flight", "--curve", str(tmp_path / "curve.png"),
                              "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["split"] == "flight" and len(out["history"]["val_loss"]) == out["epochs"]
    assert (tmp_path / "curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out["learning_curve"] == str(tmp_path / "curve.png")
    for bad, msg in ((["--split", "random"], "'random' is not one of"),
                     (["--curve", str(tmp_path / "mlp" / "c.png")], "not inside the model")):
        res = runner.invoke(app, ["train", "--model", "mlp", "--data", str(tmp_path / "logs"),
                                  "--out", str(tmp_path / "mlp"), "--max-epochs", "1", *bad])
        assert res.exit_code == 2 and msg in res.output, res.output

    res = runner.invoke(app, ["evaluate", "--model", str(tmp_path / "model"),
                              "--data", str(tmp_path / "test.npz"), "--json"])
    assert res.exit_code == 0, res.output
    ev = json.loads(res.stdout)
    assert ev["interaction"]["zero"]["rmse_mps2"]["overall"] > 0
    res = runner.invoke(app, ["evaluate", "--model", str(tmp_path / "model"),
                              "--data", str(tmp_path / "test.npz")])
    assert res.exit_code == 0 and "interaction region" in res.stdout and "zero" in res.stdout

    res = runner.invoke(app, ["export", "--model", str(tmp_path / "model"),
                              "--out", str(tmp_path / "m.onnx"), "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["max_abs_diff_vs_numpy_mps2"] < 1e-5


def test_cli_errors_are_one_line(tmp_path, capsys):
    """Through the command line as users run it (``aerodock.cli.app.run``: usage errors, such as
    a kind that is not one of the choices, are one line too)."""
    from aerodock.cli.app import run

    (tmp_path / "junk.npz").write_bytes(b"junk")
    cases = [
        ["train", "--model", "cnn", "--data", str(tmp_path), "--out", str(tmp_path / "m")],
        ["train", "--data", str(tmp_path / "junk.npz"), "--out", str(tmp_path / "m")],
        ["train", "--data", str(tmp_path / "nothing"), "--out", str(tmp_path / "m")],
        ["evaluate", "--model", str(tmp_path / "nomodel"), "--data", str(tmp_path)],
        ["export", "--model", str(tmp_path), "--out", str(tmp_path / "x.onnx")],
    ]
    for args in cases:
        capsys.readouterr()
        assert run(args) == 2, args
        out, err = capsys.readouterr()
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), err
        assert "Traceback" not in out + err


def test_so2_ext_expresses_a_tangential_force_the_paper_model_cannot():
    """A swirl along e_t proportional to the follower's tangential velocity: only so2-ext fits."""
    from learning_synth import true_field

    from aerodock.geometry import euler_to_rotmat
    from aerodock.learning.dataset import Dataset
    from aerodock.learning.features import feature_map

    rng = np.random.default_rng(0)
    n, n_fl = 6000, 5
    rot = euler_to_rotmat(rng.normal(0, 0.05, n), rng.normal(0, 0.05, n), rng.uniform(-3, 3, n))
    dp = np.concatenate([rng.uniform(-0.4, 0.4, (n, 2)), rng.uniform(0.3, 1.0, (n, 1))], 1)
    x = np.concatenate([dp, np.zeros((n, 3)), rng.normal(0, 0.4, (n, 3))], 1)
    _, out_map = feature_map("so2-ext", x, rot)
    e_t = out_map[:, :, 1]
    rho = np.hypot(*np.einsum("nij,ni->nj", rot, dp)[:, :2].T)
    swirl = np.einsum("ni,ni->n", e_t, x[:, 6:9]) * np.exp(-0.5 * (rho / 0.2) ** 2)
    true = true_field(dp, rot) + swirl[:, None] * e_t
    fid = np.repeat(np.arange(n_fl), n // n_fl)
    ds = Dataset(x=x, leader_R=rot, y=true + 0.1 * rng.normal(size=(n, 3)), flight_id=fid,
                 t_s=np.tile(np.arange(n // n_fl) * 0.01, n_fl), y_true_mean=true,
                 meta={"flights": [{"name": f"f{i}", "dt_s": 0.01} for i in range(n_fl)]})
    train, test = ds.subset(fid < n_fl - 1), ds.subset(fid == n_fl - 1)
    err = {}
    for kind in ("so2", "so2-ext"):
        ev = evaluate(train_model(kind, train, max_epochs=40).predictor(), test)
        err[kind] = ev["all"]["model_vs_true_mean"]["rmse_mps2"]
    for axis in ("x", "y"):
        assert err["so2-ext"][axis] < 0.4 * err["so2"][axis], err
