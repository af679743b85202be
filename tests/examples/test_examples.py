"""Every script in examples/ runs, at its ``--smoke`` size, as a user runs it (a separate
process), and does what its docstring says: the campaign is ``aerodock dock``'s, the model
trained on logs beats the zero model on held-out flights and loads where every reader loads it,
the deployed model pushes hardest on the leader's axis and its ONNX file agrees with NumPy, and
PPO's run is long enough to end episodes and report their returns."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from cli_process import aerodock

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
TESTED_HERE = {"fly_campaign.py", "train_on_logs.py", "deploy_predictor.py", "ppo_sb3.py"}
TESTED_ELSEWHERE = {"residual_ars.py": "tests/envs/test_envs.py"}


def run_example(name: str, *args: object, cwd: Path) -> subprocess.CompletedProcess:
    """``python examples/NAME ARGS`` in ``cwd``, this interpreter and environment."""
    return subprocess.run([sys.executable, str(EXAMPLES / name), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=600)


def json_out(proc: subprocess.CompletedProcess) -> dict:
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_every_example_script_is_run_by_a_test():
    scripts = {p.name for p in EXAMPLES.glob("*.py")}
    assert scripts == TESTED_HERE | set(TESTED_ELSEWHERE)
    for name, where in TESTED_ELSEWHERE.items():
        assert name in (EXAMPLES.parent / where).read_text()


def test_fly_campaign_is_the_dock_command(tmp_path):
    summary = json_out(run_example("fly_campaign.py", "--smoke", "--json", cwd=tmp_path))
    proc = aerodock("dock", "--trials", 4, "--offset", 0.36, "--controller", "ours",
                    "--compensation", "observer", "--seed", 0, "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    dock = json.loads(proc.stdout)
    assert summary["trials"] == 4
    assert summary["docked"] + summary["missed"] + summary["aborts"] + summary[
        "slip_throughs"] >= 1
    for key in ("docked", "success_rate", "success_wilson95", "missed", "aborts",
                "slip_throughs", "terminal_err_down_median_m", "min_clearance_m"):
        assert summary[key] == dock[key], key


def test_fly_campaign_refuses_a_missing_model_in_one_line(tmp_path):
    proc = run_example("fly_campaign.py", "--smoke", "--compensation", "model", "--model",
                       tmp_path / "nothing", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.startswith("error: ") and len(proc.stderr.strip().splitlines()) == 1


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """examples/train_on_logs.py at its smoke size on simulated flights: (its result, the
    model directory)."""
    pytest.importorskip("torch")
    where = tmp_path_factory.mktemp("train")
    result = json_out(run_example("train_on_logs.py", "--smoke", "--source", "simulated",
                                  "--out", where / "model", "--json", cwd=where))
    return result, where / "model"


def test_train_on_simulated_logs_beats_the_zero_model_on_a_held_out_flight(trained):
    from aerodock.learning.runtime import Predictor

    result, model_dir = trained
    assert result["source"] == "simulated" and result["kind"] == "so2"
    assert result["train_flights"] == 2 and result["test_flights"] == 1
    assert result["epochs"] == 5 and result["heldout_interaction_samples"] > 0
    assert result["heldout_rmse_down_mps2"] < 0.5 * result["zero_model_rmse_down_mps2"]
    assert Predictor.load(model_dir).kind == "so2"


def test_train_on_the_real_flights_in_the_data_location(tmp_path, shared_data):
    pytest.importorskip("torch")
    data_dir = shared_data("neural-swarm", "swap_ss").parents[1]
    result = json_out(run_example("train_on_logs.py", "--smoke", "--data-dir", data_dir,
                                  "--out", tmp_path / "model", "--json", cwd=tmp_path))
    assert result["source"] == "real"  # auto: the location holds the flights
    assert result["train_flights"] == 10 and result["test_flights"] == 4  # 00-04 | 05-06, x2
    assert result["heldout_rmse_down_mps2"] < result["zero_model_rmse_down_mps2"]


def test_train_on_real_logs_without_them_is_one_line(tmp_path):
    (tmp_path / "empty").mkdir()
    proc = run_example("train_on_logs.py", "--source", "real", "--data-dir", tmp_path / "empty",
                       "--out", tmp_path / "model", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"error: {tmp_path / 'empty' / 'neural-swarm'}: no "
                                   "neural-swarm/swap_ss flights (give --data-dir or set "
                                   "AERODOCK_DATA_DIR; docs/real-logs.md)")
    assert not (tmp_path / "model").exists()


def test_deploy_predicts_the_strongest_push_on_the_axis_and_onnx_agrees(trained, tmp_path):
    _, model_dir = trained
    args = ["--model", model_dir, "--json"]
    onnx = tmp_path / "model.onnx"
    with_onnx = True
    try:
        import onnx as _onnx  # noqa: F401
        import onnxruntime  # noqa: F401
    except ImportError:
        with_onnx = False
    result = json_out(run_example("deploy_predictor.py", *args,
                                  *(["--onnx", onnx] if with_onnx else []), cwd=tmp_path))
    assert result["kind"] == "so2"
    for depth, row in zip(result["depths_m"], result["accel_down_mps2"], strict=True):
        if depth <= 0.6:  # the depths it was trained on (0.3-0.6 m below the leader)
            on_axis, off_axis = row[0], row[-1]
            assert on_axis > 1.0 and on_axis > off_axis, (depth, row)
    if with_onnx:
        assert onnx.is_file() and result["max_abs_diff_vs_numpy_mps2"] < 1e-4


def test_fly_campaign_with_the_trained_model_applies_its_feed_forward(trained, tmp_path):
    _, model_dir = trained
    without = json_out(run_example("fly_campaign.py", "--smoke", "--json", cwd=tmp_path))
    with_model = json_out(run_example("fly_campaign.py", "--smoke", "--json", "--compensation",
                                      "model", "--model", model_dir, cwd=tmp_path))
    assert without["ff_down_int_0p5s_mps"] == 0.0
    assert with_model["ff_down_int_0p5s_mps"] > 0.0  # the model's push, fed forward downward


def _have_tensorboard() -> bool:
    try:
        import tensorboard  # noqa: F401
    except ImportError:
        return False
    return True


@pytest.fixture(scope="module")
def ppo_smoke(tmp_path_factory) -> tuple[subprocess.CompletedProcess, Path]:
    """One ``ppo_sb3.py --smoke`` run for both PPO tests (the run is the example's longest):
    ``--json``, and ``--tensorboard`` when tensorboard is installed (logging to TensorBoard
    does not change the training: same seed, same steps, same numbers)."""
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("torch")
    tmp = tmp_path_factory.mktemp("ppo")
    tb = ("--tensorboard", tmp / "tb") if _have_tensorboard() else ()
    proc = run_example("ppo_sb3.py", "--smoke", "--json", tmp / "ppo.json", *tb, cwd=tmp)
    return proc, tmp


def test_ppo_smoke_run_ends_episodes_and_reports_their_returns(ppo_smoke):
    proc, tmp_path = ppo_smoke
    assert proc.returncode == 0, proc.stderr
    result = json.loads((tmp_path / "ppo.json").read_text())
    assert result["env_steps"] == 1792
    assert result["episodes_ended"] >= result["settings"]["envs"]  # every environment's first
    curve = result["returns_by_rollout"]
    assert curve and sum(p["episodes"] for p in curve) == result["episodes_ended"]
    assert all(math.isfinite(p["mean_return"]) for p in curve)
    assert "mean return" in proc.stdout and "no episode ended" not in proc.stdout


def test_ppo_tensorboard_logs_or_says_what_is_missing(tmp_path, request):
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("torch")
    if not _have_tensorboard():
        proc = run_example("ppo_sb3.py", "--smoke", "--tensorboard", tmp_path / "tb",
                           cwd=tmp_path)
        assert proc.returncode == 2
        assert proc.stderr.strip() == ("error: --tensorboard needs tensorboard: pip install "
                                       "'aerodock[gym]'")
        return
    proc, run_dir = request.getfixturevalue("ppo_smoke")  # the run with --tensorboard
    assert proc.returncode == 0, proc.stderr
    assert list((run_dir / "tb").rglob("events.out.tfevents.*"))
