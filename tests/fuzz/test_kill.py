"""kill -9 during ``ingest``, ``train``, ``export``, ``sweep`` and ``collect``: the old output stays
intact or the new one is complete, never a mix; temporary files of a killed write are removed by
the next write. Ctrl-C (SIGINT to the process group) during ``sweep``, serial and parallel, and
``dock``: one ``interrupted`` line, exit 130, no traceback, no process left, outputs whole, and
``sweep --resume`` finishes the interrupted study.

Each command first runs to completion (its output is the "old" one, and its duration sets the
range of kill moments); then it runs again and is killed with SIGKILL at random moments.
``sweep`` and ``collect`` first write the new folder in a subprocess (its duration, and what a
complete new folder holds), then the old one in-process; after a kill that let the new folder
in, the old one is copied back; the last write, in-process, removes the killed runs' leftovers.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from short_mission import short_mission_toml

ENTRY = "from aerodock.cli import main; main()"
# Widens the window between the two files of a model directory: sleeps after any os.replace
# whose target is a weights.npz, and says so on stderr (the test kills it then).
SLOW_MODEL_WRITE = (
    "import os, sys, time\n"
    "_replace = os.replace\n"
    "def _slow(src, dst, *a, **k):\n"
    "    _replace(src, dst, *a, **k)\n"
    "    if str(dst).endswith('weights.npz'):\n"
    "        print('WEIGHTS-REPLACED', file=sys.stderr, flush=True)\n"
    "        time.sleep(5)\n"
    "os.replace = _slow\n"
    "from aerodock.cli import main; main()\n"
)


def _start(args: list, code: str = ENTRY) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _run(args: list) -> float:
    t0 = time.perf_counter()
    proc = _start(args)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err
    return time.perf_counter() - t0


def _kill_at(args: list, delay_s: float) -> int | None:
    from fuzz_helpers import count

    count(f"kill-{args[0]}")
    proc = _start(args)
    try:
        proc.wait(timeout=delay_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGKILL)
    proc.communicate()
    return proc.returncode


def _digest(paths: list[Path]) -> str:
    h = hashlib.sha256()
    for p in paths:
        h.update(p.read_bytes() if p.exists() else b"<absent>")
    return h.hexdigest()


def _temps(folder: Path) -> list[Path]:
    return [p for p in folder.iterdir() if p.name.endswith(".tmp")]


def _moments(duration_s: float, n: int, seed: int) -> list[float]:
    """``n`` kill moments (scaled by AERODOCK_FUZZ_SCALE) spread over a run's duration."""
    from fuzz_helpers import n_cases

    n = n_cases(n)
    rng = random.Random(seed)
    return sorted(rng.uniform(0.05, 1.0) * duration_s for _ in range(n))


def test_kill_during_ingest(shared_data, tmp_path):
    from fuzz_helpers import run_cli

    from aerodock.flightlog import load_flightlogs

    files = sorted(shared_data("neural-swarm", "swap_ss").glob("cf5?_0*.csv"))
    out = tmp_path / "real.npz"
    old_args = ["ingest", "--format", "neural-swarm", *files[:4], "--out", out]
    new_args = ["ingest", "--format", "neural-swarm", *files, "--out", out]
    duration = _run(new_args)
    n_new = len(load_flightlogs(out))
    for delay in _moments(duration, 2, seed=1):
        assert run_cli(old_args).rc == 0
        old = _digest([out])
        assert len(load_flightlogs(out)) < n_new
        _kill_at(new_args, delay)
        logs = load_flightlogs(out)  # never a half-written file
        assert _digest([out]) == old or len(logs) == n_new, f"mixed output after {delay:.2f} s"
    assert run_cli(old_args).rc == 0
    assert not _temps(tmp_path), "a killed ingest's temporary file outlived the next write"


@pytest.fixture(scope="module")
def data_file(tmp_path_factory, short_cfg) -> Path:
    """Two trials' FlightLogs (the short mission: what the models learn is not the point)."""
    from aerodock.flightlog import save_flightlogs
    from aerodock.mission import MissionSpec, run_campaign

    result = run_campaign(short_cfg, MissionSpec(trials=2, seed=5), record="full")
    return save_flightlogs(tmp_path_factory.mktemp("kill") / "data.npz", result.logs)


@pytest.fixture(scope="module")
def models(data_file, tmp_path_factory) -> dict[str, Path]:
    """Two small trained models (in-process: only the runs that get killed are subprocesses)."""
    from fuzz_helpers import run_cli

    folder = tmp_path_factory.mktemp("models")
    out = {}
    for name, kind in (("old", "mlp"), ("new", "so2")):
        res = run_cli(["train", "--data", data_file, "--out", folder / name, "--model", kind,
                       "--max-epochs", "2", "--seed", "1"], family="setup")
        assert res.rc == 0, res.err
        out[name] = folder / name
    return out


def _model_state(model: Path) -> tuple[bool, str | None]:
    """(whether both files load together as one model, its kind)."""
    from aerodock.learning.modelfile import ModelFileError
    from aerodock.learning.runtime import Predictor

    try:
        return True, Predictor.load(model).kind
    except ModelFileError:
        return False, None


def test_kill_during_train(data_file, models, tmp_path):
    """The old model (mlp) stays, or the new one (so2) is complete; never a mix."""
    model = tmp_path / "model"
    new_args = ["train", "--data", data_file, "--out", model, "--model", "so2",
                "--max-epochs", "3"]
    shutil.copytree(models["old"], model)
    duration = _run(new_args)
    assert _model_state(model) == (True, "so2")
    for delay in _moments(duration, 2, seed=2):
        shutil.rmtree(model)
        shutil.copytree(models["old"], model)
        old = _digest([model / "model.json", model / "weights.npz"])
        _kill_at(new_args, delay)
        intact = _digest([model / "model.json", model / "weights.npz"]) == old
        assert intact or _model_state(model) == (True, "so2"), (
            f"mixed model directory after a kill at {delay:.2f} s")


def test_kill_between_the_two_model_files(data_file, models, tmp_path):
    """A kill right after weights.npz is replaced (the window a slow disk widens)."""
    model = tmp_path / "model"
    shutil.copytree(models["old"], model)
    old = _digest([model / "model.json", model / "weights.npz"])
    proc = _start(["train", "--data", data_file, "--out", model, "--model", "so2",
                   "--max-epochs", "2"], SLOW_MODEL_WRITE)
    deadline = time.monotonic() + 300
    for line in proc.stderr:
        if "WEIGHTS-REPLACED" in line or time.monotonic() > deadline:
            break
    if proc.poll() is None:
        proc.send_signal(signal.SIGKILL)
    proc.communicate()
    intact = _digest([model / "model.json", model / "weights.npz"]) == old
    assert intact or _model_state(model) == (True, "so2"), (
        "weights.npz and model.json do not belong together")


def test_kill_during_export(models, tmp_path):
    import onnx
    from fuzz_helpers import run_cli

    out = tmp_path / "m.onnx"
    new_args = ["export", "--model", models["new"], "--out", out]
    duration = _run(new_args)
    new = _digest([out])
    for delay in _moments(duration, 2, seed=3):
        assert run_cli(["export", "--model", models["old"], "--out", out]).rc == 0
        old = _digest([out])
        assert old != new
        _kill_at(new_args, delay)
        assert _digest([out]) in (old, new), f"mixed ONNX file after a kill at {delay:.2f} s"
        onnx.checker.check_model(onnx.load(str(out)))


# ---- folders of several files: sweep --out and collect --out ------------------------------

# What a kill leaves does not depend on what the runs fly: the mission's waiting times cut
# (tests/short_mission.py) in both, and the world at its cheapest (the point-mass vehicles, the
# physics stepped at the control rate), for fewer and cheaper simulated seconds per run: the
# runs fly, train and write the same folders, in less time.
FAST_WORLD = '[vehicle]\nmodel = "point-mass"\n[sim]\nphysics_rate_hz = 100.0\n'
SWEEP_SPEC = ("[sweep]\ntrials = 1\nseeds = [{seed}]\nconfig = \"short.toml\"\n"
              "[axes]\ncompensation = [\"observer\", \"oracle\"]\n")
COLLECT_CONFIG = ("[curriculum]\nflights_per_stage = 1\nstage0_depth_m = [0.9, 1.2]\n"
                  "min_depth_m = 0.9\ndeep_depths_m = []\nmodel = \"mlp\"\n"
                  + FAST_WORLD + short_mission_toml())


def _tree(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (relative name -> bytes); hidden temporaries excluded."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def _sweep_seeds(folder: Path) -> set[str]:
    """The campaign seeds a sweep folder's files speak for (table, summary), as 'csv:S' etc."""
    import csv
    import json

    seeds = set()
    with open(folder / "results.csv") as fh:
        seeds |= {f"csv:{row['seed']}" for row in csv.DictReader(fh)}
    summary = json.loads((folder / "summary.json").read_text())
    seeds |= {f"summary:{c['seed']}" for c in summary["cells"]}
    return seeds


def _in_process(args: list) -> None:
    """A run that is not killed, in this process (no interpreter start-up): it writes the old
    study or collection, or is the next write that removes killed runs' temporary folders."""
    from fuzz_helpers import run_cli

    res = run_cli(args, family="setup")
    assert res.rc == 0, res.err


def _restore(snapshot: Path, out: Path) -> None:
    """Put the old folder back, as its own run wrote it (after a kill that let the new one in)."""
    shutil.rmtree(out)
    shutil.copytree(snapshot, out)


def test_kill_during_sweep_leaves_one_study(tmp_path):
    """sweep --out killed at random moments: the folder is the old study, byte for byte, or the
    new one complete (its table and summary of the new seed, its figures); never a mix."""
    out = tmp_path / "study"
    specs = {}
    (tmp_path / "short.toml").write_text(FAST_WORLD + short_mission_toml())
    for seed in (0, 1):
        specs[seed] = tmp_path / f"spec{seed}.toml"
        specs[seed].write_text(SWEEP_SPEC.format(seed=seed))
    new_args = ["sweep", specs[1], "--out", out, "--jobs", "1"]
    old_args = ["sweep", specs[0], "--out", out, "--jobs", "1"]
    duration = _run(new_args)
    new_names = set(_tree(out))
    new_figures = {k: v for k, v in _tree(out).items() if k.startswith("figures")}
    assert _sweep_seeds(out) == {"csv:1", "summary:1"}
    _in_process(old_args)  # the old study replaces the new one
    old = _tree(out)
    assert _sweep_seeds(out) == {"csv:0", "summary:0"}
    snapshot = shutil.copytree(out, tmp_path / "old-study")
    for delay in _moments(duration, 2, seed=4):
        _kill_at(new_args, delay)
        now = _tree(out)
        if now != old:
            assert set(now) == new_names, f"files of two runs after a kill at {delay:.2f} s"
            assert _sweep_seeds(out) == {"csv:1", "summary:1"}, f"mixed at {delay:.2f} s"
            assert {k: v for k, v in now.items() if k.startswith("figures")} == new_figures
            _restore(snapshot, out)
    _in_process(old_args)
    assert not _temps(tmp_path), "a killed sweep's temporary folder outlived the next sweep"


def _collect_seeds(folder: Path) -> dict[str, int]:
    """The seed each file of a collect folder comes from (stage logs and every model)."""
    import json

    from aerodock.flightlog import load_flightlogs

    seeds = {}
    for path in sorted(folder.glob("stage*.npz")):
        stage = int(path.stem[len("stage"):])
        seeds[path.name] = load_flightlogs(path)[0].meta["seed"] - 1000 * stage
    for model in sorted((folder / "models").iterdir()):
        seeds[f"models/{model.name}"] = json.loads((model / "model.json").read_text())[
            "training"]["seed"]
    return seeds


def test_kill_during_collect_leaves_one_collection(tmp_path):
    """collect --out killed at random moments: every stage log and model in the folder comes
    from one seed, old or new, and the set is complete."""
    cfg = tmp_path / "tiny.toml"
    cfg.write_text(COLLECT_CONFIG)
    out = tmp_path / "collected"
    new_args = ["collect", "--out", out, "--config", cfg, "--seed", "2"]
    old_args = ["collect", "--out", out, "--config", cfg, "--seed", "1"]
    duration = _run(new_args)
    complete = set(_collect_seeds(out))
    assert set(_collect_seeds(out).values()) == {2}
    _in_process(old_args)  # the old collection replaces the new one
    assert _collect_seeds(out) == dict.fromkeys(complete, 1)
    snapshot = shutil.copytree(out, tmp_path / "old-collection")
    for delay in _moments(duration, 2, seed=5):
        _kill_at(new_args, delay)
        seeds = _collect_seeds(out)
        assert set(seeds) == complete, f"incomplete folder after a kill at {delay:.2f} s"
        assert len(set(seeds.values())) == 1, f"two seeds mixed after a kill at {delay:.2f} s"
        if set(seeds.values()) == {2}:
            _restore(snapshot, out)
    _in_process(old_args)
    assert not _temps(tmp_path), "a killed collect's temporary folder outlived the next one"


# ---- Ctrl-C: one 'interrupted' line, exit 130, no traceback, no process left, outputs whole ---

def _group_running(pgid: int) -> list[int]:
    """The processes of group ``pgid`` still running (a zombie waiting for its reaper is done)."""
    running = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            raw = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = raw[raw.rindex(")") + 2:].split()  # state, ppid, pgrp, ...
        if int(fields[2]) == pgid and fields[0] != "Z":
            running.append(int(entry))
    return running


def _cpu_s(pid: int) -> float:
    """CPU time used so far by ``pid`` (user + system), s."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _terminal_sigint() -> None:
    """In the child: SIGINT's default action, as a command started at a terminal has it (a
    suite run in the background of a non-interactive shell inherits SIGINT ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _ctrl_c(args: list, ready) -> tuple[int, str, str]:
    """Run ``aerodock ARGS`` in its own process group, wait until ``ready(pid)``, then send
    SIGINT to the whole group (what a terminal's Ctrl-C does: the workers get it too).

    Returns (exit code, stdout, stderr) once every process of the group has ended.
    """
    from fuzz_helpers import count

    count(f"ctrl-c-{args[0]}")
    proc = subprocess.Popen([sys.executable, "-c", ENTRY, *map(str, args)], text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, preexec_fn=_terminal_sigint)
    try:
        deadline = time.monotonic() + 300
        while proc.poll() is None and not ready(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert proc.poll() is None, f"{args[0]} ended before the interrupt: {proc.stderr.read()}"
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=120)  # the pipes close when every holder is gone
        deadline = time.monotonic() + 30
        while _group_running(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _group_running(proc.pid), "a process of the command outlived it"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    return proc.returncode, out, err


def _interrupted(rc: int, out: str, err: str) -> None:
    assert "Traceback" not in err and "Error" not in err, err
    assert (rc, err) == (130, "interrupted\n"), (rc, err)
    assert out == ""


def _a_cell_finished(folder: Path):
    return lambda pid: folder.is_dir() and any(folder.glob("*.json"))


@pytest.mark.parametrize("jobs", [2, 1])
def test_ctrl_c_in_a_sweep_is_one_line_and_resume_finishes_it(tmp_path, jobs):
    """Ctrl-C once a cell has finished: workers and all (``--jobs 2``) stop without a
    traceback, --out is untouched (here: never made), and ``--resume`` reuses the finished
    cells and gives the table an uninterrupted run gives. Three points of two seeds: three
    batches (a point's seeds fly as one), so some are still flying when the first is saved."""
    (tmp_path / "short.toml").write_text(FAST_WORLD + short_mission_toml())
    spec = tmp_path / "spec.toml"
    spec.write_text(SWEEP_SPEC.format(seed="0, 1").replace(', "oracle"', "")
                    + "mocap_noise_scale = [1.0, 2.0, 3.0]\n")
    out = tmp_path / "study"
    result = _ctrl_c(["sweep", spec, "--out", out, "--jobs", jobs],
                     _a_cell_finished(tmp_path / ".study.cells"))
    _interrupted(*result)
    assert not out.exists() and not _temps(tmp_path)
    kept = len(list((tmp_path / ".study.cells").glob("*.json")))
    assert 1 <= kept < 6
    _in_process(["sweep", spec, "--out", out, "--jobs", "1", "--resume"])
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["reused"], summary["flown"]) == (kept, 6 - kept)
    _in_process(["sweep", spec, "--out", tmp_path / "whole", "--jobs", "1"])
    assert (out / "results.csv").read_bytes() == (tmp_path / "whole/results.csv").read_bytes()


def test_ctrl_c_leaves_the_old_study_whole(tmp_path):
    (tmp_path / "short.toml").write_text(FAST_WORLD + short_mission_toml())
    specs = {}
    for seed in (0, 1):
        specs[seed] = tmp_path / f"spec{seed}.toml"
        specs[seed].write_text(SWEEP_SPEC.format(seed=seed))
    out = tmp_path / "study"
    _in_process(["sweep", specs[0], "--out", out, "--jobs", "1"])
    old = _tree(out)
    _interrupted(*_ctrl_c(["sweep", specs[1], "--out", out, "--jobs", "2"],
                          _a_cell_finished(tmp_path / ".study.cells")))
    assert _tree(out) == old and not _temps(tmp_path)


def _numpy_loaded(pid: int) -> bool:
    """The command's modules are loading (NumPy is mapped)."""
    with contextlib.suppress(OSError):
        return "numpy" in Path(f"/proc/{pid}/maps").read_text()
    return False


@pytest.mark.parametrize("moment", ["loading", "flying"])
def test_ctrl_c_in_dock_is_one_line(tmp_path, moment):
    """While the commands load, and in the middle of a campaign (2 s of CPU into it: loading
    takes well under that; 256 trials take over 6 s, even compiled, so the campaign cannot
    end between the check and the signal)."""
    ready = _numpy_loaded if moment == "loading" else (lambda pid: _cpu_s(pid) >= 2.0)
    _interrupted(*_ctrl_c(["dock", "--trials", "256", "--json"], ready))
