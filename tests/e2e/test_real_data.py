"""Issue 6 acceptance on the real Neural-Swarm flights, as a new user runs it from the CLI."""

from __future__ import annotations

import json

from cli_process import aerodock as run_cli


def aerodock(*args, cwd):
    return run_cli(*args, check=True, cwd=cwd).stdout


def test_ingest_train_on_00_04_evaluate_on_05_06(tmp_path, shared_data):
    folder = shared_data("neural-swarm", "swap_ss")
    train = sorted(str(p) for p in folder.glob("cf5?_0[0-4].csv"))
    test = sorted(str(p) for p in folder.glob("cf5?_0[56].csv"))
    aerodock("ingest", "--format", "neural-swarm", str(folder), "--out", "real.npz", cwd=tmp_path)
    aerodock("ingest", "--format", "neural-swarm", *train, "--out", "train.npz", cwd=tmp_path)
    aerodock("ingest", "--format", "neural-swarm", *test, "--out", "test.npz", cwd=tmp_path)
    aerodock("train", "--model", "so2", "--data", "train.npz", "--out", "so2", cwd=tmp_path)
    out = json.loads(aerodock("evaluate", "--model", "so2", "--data", "test.npz", "--json",
                              cwd=tmp_path))
    inter = out["interaction"]
    model_z = inter["model"]["rmse_mps2"]["z"]
    zero_z = inter["zero"]["rmse_mps2"]["z"]
    assert inter["n"] > 500
    assert model_z <= 0.5 * zero_z  # at least 50 % below the zero model
