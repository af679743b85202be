"""Inputs that are not files, or never end, or ask for too much (issue 25's audit).

Each input option is given ``/dev/zero`` (endless) and a FIFO (blocks a reader for ever) in a
subprocess with a timeout, so a hang fails the test instead of hanging the suite; every refusal
is exit code 2 with one ``error:`` line and no traceback. Then huge sweeps, long simulated times,
integer and enum keys, fault magnitudes, and the cases that used to exit 1.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fuzz_helpers import count

ENTRY = "from aerodock.cli import main; main()"
HANG_GUARD_S = 60  # generous on a loaded 2-core machine; a hang is for ever


# ENTRY, then a last stderr line naming the compiled world's and the heavy libraries' modules the
# run loaded (a refused input is refused before them: about half a second of every refusal)
ENTRY_LOADED = (
    "import atexit, sys\n"
    "HEAVY = ('numba', 'torch', 'scipy', 'matplotlib', 'aerodock.world')\n"
    "atexit.register(lambda: print('loaded:', *[m for m in HEAVY if m in sys.modules],"
    " file=sys.stderr))\n" + ENTRY)


def cli(args: list, family: str, cwd: Path | None = None,
        entry: str = ENTRY) -> subprocess.CompletedProcess:
    """Run the CLI in a subprocess, counted as a case of ``inputs-<family>`` in the fuzz tally;
    a run that does not end in time fails the test."""
    count(f"inputs-{family}")
    try:
        return subprocess.run([sys.executable, "-c", entry, *map(str, args)], cwd=cwd,
                              capture_output=True, text=True, timeout=HANG_GUARD_S)
    except subprocess.TimeoutExpired:
        pytest.fail(f"aerodock {' '.join(map(str, args))} did not finish in {HANG_GUARD_S} s")


def refused(res: subprocess.CompletedProcess, *needles: str) -> str:
    """Assert exit 2, one ``error:`` line, no traceback; the error line."""
    assert res.returncode == 2, (res.returncode, res.stderr)
    assert "Traceback" not in res.stderr, res.stderr
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1, res.stderr
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def log_file(tmp_path_factory, short_cfg) -> Path:
    """A FlightLog file (one trial on the short mission: an input, whatever it flew)."""
    from aerodock.flightlog import save_flightlogs
    from aerodock.mission import MissionSpec, run_campaign

    result = run_campaign(short_cfg, MissionSpec(trials=1, seed=3), record="full")
    return save_flightlogs(tmp_path_factory.mktemp("log") / "log.npz", result.logs)


@pytest.fixture()
def fifo(tmp_path) -> Path:
    path = tmp_path / "fifo"
    os.mkfifo(path)
    return path


def _cases(bad: Path, log: Path, tmp: Path) -> dict[str, list]:
    """One command line per input option, with ``bad`` as that input."""
    spec = tmp / "spec.toml"
    spec.write_text(f'[sweep]\ntrials = 1\nconfig = "{bad}"\n')
    return {
        "--config": ["field", "probe", "--separation", "1", "--radial", "0", "--config", bad],
        "--data": ["train", "--data", bad, "--out", tmp / "model"],
        "ingest csv": ["ingest", "--format", "csv", bad, "--out", tmp / "o.npz"],
        "ingest ulog": ["ingest", "--format", "ulog", "--single", bad, "--out", tmp / "o.npz"],
        "ingest rosbag": ["ingest", "--format", "rosbag", bad, "--out", tmp / "o.npz"],
        "--mapping": ["ingest", "--format", "rosbag", log, "--mapping", bad, "--out",
                      tmp / "o.npz"],
        "view": ["view", bad, "--out", tmp / "v.gif"],
        "--faults": ["dock", "--trials", "1", "--faults", bad],
        "faults": ["faults", bad, "--trials", "1"],
        "sweep": ["sweep", bad, "--out", tmp / "sweep"],
        "sweep config": ["sweep", spec, "--out", tmp / "sweep"],
        "--model": ["field", "probe", "--separation", "1", "--radial", "0", "--model", bad],
        "plot --model": ["field", "plot", "--out", tmp / "f.png", "--model", bad],
    }


@pytest.mark.parametrize("option", ["--config", "--data", "ingest csv", "ingest ulog",
                                    "ingest rosbag", "--mapping", "view", "--faults", "faults",
                                    "sweep", "sweep config", "--model", "plot --model"])
def test_dev_zero_is_refused_at_once(option, log_file, tmp_path):
    """/dev/zero as each input: refused at once in one line, before the command loads the
    compiled world or a heavy library (view, faults and field probe and plot with --model loaded
    them first)."""
    res = cli(_cases(Path("/dev/zero"), log_file, tmp_path)[option], "dev-zero",
              entry=ENTRY_LOADED)
    refused(res, "/dev/zero")
    assert res.stderr.splitlines()[-1] == "loaded:", res.stderr


@pytest.mark.parametrize("option", ["--config", "--data", "ingest csv", "ingest ulog",
                                    "ingest rosbag", "--mapping", "view", "--faults", "faults",
                                    "sweep", "sweep config"])
def test_a_fifo_is_refused_not_waited_on(option, fifo, log_file, tmp_path):
    refused(cli(_cases(fifo, log_file, tmp_path)[option], "fifo"), "not a regular file")


def test_a_fifo_inside_a_model_directory_is_refused(fifo, tmp_path):
    from aerodock.learning.modelfile import ModelFileError
    from aerodock.learning.runtime import Predictor

    model = tmp_path / "model"
    model.mkdir()
    (model / "model.json").write_text("{}")
    os.mkfifo(model / "weights.npz")
    with pytest.raises(ModelFileError):
        Predictor.load(model)
    (model / "model.json").unlink()
    os.mkfifo(model / "model.json")
    refused(cli(["field", "probe", "--separation", "1", "--radial", "0", "--model", model],
                "fifo"))


def test_view_rerun_to_a_fifo_or_a_device_is_refused(fifo, log_file, tmp_path):
    pytest.importorskip("rerun")
    for target in (fifo, Path("/dev/null")):
        refused(cli(["view", log_file, "--out", tmp_path / "v.gif", "--max-frames", "2",
                     "--rerun", target], "fifo"), str(target), "not a regular file")


def test_view_rerun_to_an_unwritable_path_exits_2(log_file, tmp_path):
    pytest.importorskip("rerun")
    blocker = tmp_path / "file"
    blocker.write_text("x")  # a file where a folder should be
    refused(cli(["view", log_file, "--out", tmp_path / "v.gif", "--max-frames", "2",
                 "--rerun", blocker / "sub" / "x.rrd"], "unwritable-output"))


def test_the_reader_refuses_big_and_odd_files_without_reading_them(tmp_path, fifo):
    from aerodock.fileio import InputError, read_input_bytes, read_input_text

    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * 2000)
    assert read_input_text(big, "x", max_bytes=2000) == "#" * 2000
    with pytest.raises(InputError, match="more than"):
        read_input_text(big, "x", max_bytes=1999)
    for odd in (fifo, Path("/dev/zero"), tmp_path):
        with pytest.raises(InputError):
            read_input_bytes(odd, "x", max_bytes=10)
    with pytest.raises(FileNotFoundError):
        read_input_bytes(tmp_path / "absent", "x")


def test_a_mapping_from_dev_zero_or_a_fifo_is_an_ingest_error(fifo):
    from aerodock.ingest.errors import IngestError
    from aerodock.ingest.rosbag.mapping import load_mapping

    for bad in (Path("/dev/zero"), fifo):
        with pytest.raises(IngestError, match="not a regular file"):
            load_mapping(bad)


# ---- sizes and simulated time -------------------------------------------------------------


@pytest.mark.parametrize("sweep, axes, needle", [
    ("trials = 100000000", "", "exceeds the limit of 10000"),
    ('kind = "random"\nsamples = 100000000\ntrials = 1', "", "over the limit of 10000"),
    ("trials = 1", "cable_length_m = {grid}\nleader_speed_mps = {grid}", "9000000 campaigns"),
    ("trials = 10000\nseeds = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, "
     "19, 20]", "", "over the limit of 200000"),
])
def test_huge_sweeps_are_refused_before_anything_runs(sweep, axes, needle, tmp_path):
    grid = "[" + ", ".join(f"{0.3 + i * 1e-5:.5f}" for i in range(3000)) + "]"
    spec = tmp_path / "spec.toml"
    spec.write_text(f"[sweep]\n{sweep}\n[axes]\n{axes.format(grid=grid)}\n")
    refused(cli(["sweep", spec, "--out", tmp_path / "out"], "huge-sweep"), needle)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("axes, needle", [
    ("leader_speed_mps = [0.0, 1e6]", "axes.leader_speed_mps must be between -100 and 100"),
    ("leader_speed_mps = [nan]", "axes.leader_speed_mps must be a finite number"),
    ("cable_length_m = [0.36, 90.0]", "at or below the ground"),
    ("cable_length_m = [0.0]", "axes.cable_length_m must be > 0 m"),
    ('leader_dropout_s = [[3.0, inf]]', "duration"),
    ("mocap_noise_scale = [1.0, 1e5]", "mocap.pos_noise_m"),
])
def test_a_sweep_axis_value_is_checked_as_dock_checks_it(axes, needle, tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(f"[sweep]\ntrials = 1\n[axes]\n{axes}\n")
    refused(cli(["sweep", spec, "--out", tmp_path / "out"], "sweep-axis"), needle)


def test_dock_refuses_the_leader_speed_the_sweep_refuses():
    refused(cli(["dock", "--trials", "1", "--leader-speed", "1e6"], "sweep-axis"),
            "--leader-speed must be between -100 and 100")


@pytest.mark.parametrize("toml", [
    "[mission]\nsettle_s = 600",
    "[mission]\ndock_window_s = 600",
    "[mission]\nbackoff_s = 600",
    "[sim]\nphysics_rate_hz = 20000",
])
def test_long_simulated_times_are_refused_even_for_two_trials(toml, tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(toml + "\n")
    refused(cli(["dock", "--trials", "2", "--config", cfg], "long-sim-time"), "physics steps",
            "over the limit of 100000")


def test_reproduce_refuses_a_long_trial_before_its_curriculum(tmp_path):
    """tools/audit.py found `reproduce --smoke` with backoff_s = 600 computing for over 60 s
    (a curriculum first) before its first campaign refused the trial."""
    cfg = tmp_path / "c.toml"
    cfg.write_text('[vehicle]\nmodel = "point-mass"\n[mission]\nbackoff_s = 600\n')
    refused(cli(["reproduce", "--smoke", "--no-real-data", "--out", tmp_path / "out",
                 "--config", cfg], "long-sim-time"), "physics steps", "over the limit of 100000")
    assert not (tmp_path / "out").exists()


def test_the_run_size_counts_every_mission_time(cfg):
    from aerodock.mission.limits import LimitError, check_campaign_size

    check_campaign_size(cfg, 2)  # the defaults fly
    for section, key in (("mission", "settle_s"), ("mission", "dock_window_s"),
                         ("mission", "backoff_s")):
        with pytest.raises(LimitError, match="physics steps"):
            check_campaign_size(cfg.with_overrides({section: {key: 600.0}}), 2)


def test_a_long_curriculum_flight_is_refused(cfg, tmp_path):
    from aerodock.collect.curriculum import run_curriculum
    from aerodock.mission.limits import LimitError

    with pytest.raises(LimitError, match="curriculum flight"):
        run_curriculum(cfg.with_overrides({"mission": {"settle_s": 600.0}}), tmp_path / "c")
    assert not (tmp_path / "c").exists()


# ---- keys: integers, choices, faults --------------------------------------------------------


@pytest.mark.parametrize("toml, needle", [
    ("[vehicle]\nn_rotors = 4.0", "'vehicle.n_rotors' must be an integer, got 4.0"),
    ("[curriculum]\nflights_per_stage = 2.0", "'curriculum.flights_per_stage' must be an integer"),
    ('[curriculum]\nlabel_basis = "banana"', "'curriculum.label_basis' must be one of"),
    ('[vehicle]\nmodel = "banana"', "'vehicle.model' must be one of"),
])
def test_integer_and_choice_keys(toml, needle, tmp_path):
    from aerodock.config import ConfigError, load_config

    cfg = tmp_path / "c.toml"
    cfg.write_text(toml + "\n")
    with pytest.raises(ConfigError, match=needle.replace("(", r"\(")):
        load_config(cfg)
    refused(cli(["field", "probe", "--separation", "1", "--radial", "0", "--config", cfg], "keys"),
            needle)


@pytest.mark.parametrize("entry, needle", [
    ('kind = "rotor_thrust_loss"\nmagnitude = 2.0', "between 0 and 1, got 2.0"),
    ('kind = "rotor_thrust_loss"\nmagnitude = -0.1', "finite and >= 0"),
    ('kind = "servo_slow"\nmagnitude = 0.5', "between 1 and 100"),
    ('kind = "latency_spike"\nmagnitude = 100.0', "between 0 and 10"),
    ('kind = "servo_jammed"\nmagnitude = 3.0', "has no 'magnitude'"),
    ('kind = "servo_slow"\nduration_s = inf', "'duration_s' must be finite"),
    ('kind = "servo_slow"\nduration_s = 0.0', "'duration_s' must be > 0"),
    ('kind = "servo_slow"\nstart_s = [1.0, 1e9]', "'start_s'"),
])
def test_fault_values_outside_their_physical_range(entry, needle, tmp_path):
    path = tmp_path / "f.toml"
    path.write_text(f"[[fault]]\n{entry}\n")
    refused(cli(["dock", "--trials", "1", "--faults", path], "fault-range"), needle)


def test_faults_built_in_code_are_checked_by_the_mission(cfg):
    from aerodock.mission import MissionSpec, run_campaign
    from aerodock.mission.checks import MissionSpecError
    from aerodock.mission.faults import Fault

    bad = Fault("too much", "rotor_thrust_loss", 1.0, (1.0, 2.0), 0.5, magnitude=2.0)
    with pytest.raises(MissionSpecError, match="between 0 and 1"):
        run_campaign(cfg, MissionSpec(trials=1, faults=(bad,)))
    with pytest.raises(MissionSpecError, match="duration"):
        run_campaign(cfg, MissionSpec(trials=1, leader_dropout_s=(1.0, float("inf"))))


def test_the_environment_checks_what_dock_checks(cfg):
    pytest.importorskip("gymnasium")
    from aerodock.envs.spaces import make_batch
    from aerodock.mission.checks import MissionSpecError

    with pytest.raises(MissionSpecError, match="leader_speed_mps must be between"):
        make_batch(1, cfg, leader_speed_mps=1e6)
    with pytest.raises(ValueError, match="ground"):
        make_batch(1, cfg, offset_m=90.0)


# ---- the cases that exited 1 ----------------------------------------------------------------


def _csv_text(log_file: Path, meta_line: str) -> str:
    from aerodock.flightlog import load_flightlogs
    from aerodock.ingest.csv_generic import write_csv

    path = log_file.parent / "flight.csv"
    write_csv(load_flightlogs(log_file)[0], path)
    lines = path.read_text().splitlines()
    return "\n".join([meta_line, *lines[1:]]) + "\n"


def test_a_deeply_nested_csv_meta_line_exits_2(log_file, tmp_path):
    path = tmp_path / "deep.csv"
    path.write_text(_csv_text(log_file, "# meta: " + "[" * 5000 + "]" * 5000))
    refused(cli(["ingest", "--format", "csv", path, "--out", tmp_path / "o.npz"], "csv-meta"),
            "nested too deeply")


def test_a_csv_label_basis_outside_its_choices_is_refused(log_file, tmp_path):
    path = tmp_path / "banana.csv"
    path.write_text(_csv_text(log_file, '# meta: {"label_basis": "banana", '
                                        '"follower_mass_kg": 0.7}'))
    refused(cli(["ingest", "--format", "csv", path, "--out", tmp_path / "o.npz"], "csv-meta"),
            "label_basis must be one of command|thrust")
    assert not (tmp_path / "o.npz").exists()


def test_view_of_a_flight_without_samples_exits_2(tmp_path):
    from aerodock.flightlog import FlightLog, save_flightlogs

    empty = FlightLog(t_s=np.zeros(0), leader_pos_m=np.zeros((0, 3)),
                      leader_vel_mps=np.zeros((0, 3)), leader_quat=np.zeros((0, 4)),
                      follower_pos_m=np.zeros((0, 3)), follower_vel_mps=np.zeros((0, 3)),
                      follower_quat=np.zeros((0, 4)), follower_cmd_accel_mps2=np.zeros((0, 3)),
                      follower_thrust_n=np.zeros(0), follower_obs_accel_mps2=np.zeros((0, 3)),
                      meta={"name": "empty"})
    path = save_flightlogs(tmp_path / "empty.npz", [empty])
    refused(cli(["view", path, "--out", tmp_path / "v.gif"], "empty-flight"), "0 samples")


def test_ingest_out_dev_null_or_a_fifo_is_refused(log_file, fifo, tmp_path):
    from aerodock.flightlog import load_flightlogs
    from aerodock.ingest.csv_generic import write_csv

    csv = write_csv(load_flightlogs(log_file)[0], tmp_path / "flight.csv")
    for target in (Path("/dev/null"), fifo):
        refused(cli(["ingest", "--format", "csv", csv, "--out", target], "fifo"),
                "not a regular file")
    assert not Path("/dev/null.npz").exists()
    assert not Path(f"{fifo}.npz").exists()


def test_export_to_a_non_utf8_name_does_not_crash(log_file, tmp_path):
    pytest.importorskip("onnx")
    from fuzz_helpers import run_cli

    model = tmp_path / "model"
    res = run_cli(["train", "--data", log_file, "--out", model, "--model", "mlp",
                   "--max-epochs", "2"], family="setup")  # the input, made in-process
    assert res.rc == 0, res.err
    name = os.fsdecode(b"\xff\xfe.onnx")
    res = cli(["export", "--model", model, "--out", name, "--json"], "odd-output-name",
              cwd=tmp_path)
    assert res.returncode in (0, 2), res.stderr
    assert "Traceback" not in res.stderr
    if res.returncode == 0:
        assert json.loads(res.stdout)["kind"] == "mlp"
        assert (tmp_path / name).is_file()


def test_a_ulog_whose_last_message_overruns_the_file_is_refused_not_looped_on(tmp_path):
    """tools/audit.py found pyulog looping for ever on a damaged ULog: a message header claiming
    20,000 bytes (corrupt: over its 10,000) where fewer remain makes it seek back further than it
    read, to the same header. aerodock bounds what pyulog may read."""
    bad = tmp_path / "loop.ulg"
    bad.write_bytes(b"ULog\x01\x12\x35\x01" + bytes(8) + b"\x20\x4e\x00" + bytes(19999))
    refused(cli(["ingest", "--format", "ulog", "--single", bad, "--out", tmp_path / "o.npz"],
                "ulog-loop"), "loop back on themselves")
