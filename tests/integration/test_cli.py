"""The command line as a user runs it: numbers, JSON, and one-line errors."""

from __future__ import annotations

import json
from functools import partial

import pytest
from cli_process import aerodock as run_cli
from short_mission import short_mission_toml

aerodock = partial(run_cli, check=True, timeout_s=300)


@pytest.mark.parametrize("sep", [0.36, 0.64, 1.35])
def test_field_probe_json_gives_the_fields_mean_and_spread(sep):
    """What `field probe` prints is the default jet's own mean and turbulence (the jet itself is
    checked in tests/unit/test_downwash.py)."""
    import numpy as np

    from aerodock.config import load_config
    from aerodock.downwash import build_field
    from aerodock.downwash.probe import probe_bodies

    out = json.loads(aerodock("field", "probe", "--separation", str(sep), "--radial", "0",
                              "--samples", "20000", "--json").stdout)
    field = build_field(load_config())
    leader, follower = probe_bodies(sep, 0.0, 0.0, 0.7, 9.81)
    sd = float(np.sqrt(field.turbulence(leader, follower)["axial_var_mps4"][0]))
    assert out["frame"] == "NED"
    assert out["field_mean_mps2"][2] == pytest.approx(
        field.mean_acceleration(leader, follower)[0, 2], rel=1e-9)
    assert abs(out["mean_mps2"][2] - out["field_mean_mps2"][2]) < 0.3 * sd
    assert out["sd_mps2"][2] == pytest.approx(sd, rel=0.15)


def test_field_plot_writes_png(tmp_path):
    path = tmp_path / "f.png"
    aerodock("field", "plot", "--out", str(path))
    assert path.read_bytes()[:4] == b"\x89PNG"


def test_bad_config_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[vehicle]\nmass_kg = -1\n")
    proc = aerodock("field", "probe", "--separation", "0.36", "--radial", "0", "--config",
                    str(bad), check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:")
    assert "vehicle.mass_kg" in lines[0] and str(bad) in lines[0]
    assert "Traceback" not in proc.stderr


@pytest.fixture(scope="module")
def short_toml(tmp_path_factory):
    """A config with the mission's waiting times cut (tests/short_mission.py): what these tests
    check of ``dock`` holds whatever the timing."""
    path = tmp_path_factory.mktemp("short") / "short.toml"
    path.write_text(short_mission_toml())
    return str(path)


@pytest.fixture(scope="module")
def docked(tmp_path_factory, short_toml):
    """``aerodock dock --json --save-logs`` in its own process: what it printed, parsed."""
    logs = tmp_path_factory.mktemp("logs")
    return json.loads(aerodock("dock", "--trials", "4", "--compensation", "oracle", "--json",
                               "--save-logs", str(logs), "--config", short_toml).stdout)


def test_dock_json_and_bad_trials(docked):
    out = docked
    assert out["trials"] == 4 and 0 <= out["success_rate"] <= 1
    assert len(out["success_wilson95"]) == 2
    proc = aerodock("dock", "--trials", "0", check=False)
    assert proc.returncode == 2 and "trials" in proc.stderr
    proc = aerodock("dock", "--trials", "2", "--compensation", "model", check=False)
    assert proc.returncode == 2 and "--model" in proc.stderr


def test_dock_saves_flightlogs(docked):
    from aerodock.flightlog import load_flightlogs

    logs = load_flightlogs(docked["logs"])
    assert len(logs) == 4
    assert "true_field_mean_mps2" in logs[0].extra


def run_inprocess(*args):
    """``aerodock ARGS`` in-process: (exit code, stdout, stderr)."""
    import io
    from contextlib import redirect_stderr, redirect_stdout

    from aerodock.cli import run

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = run([str(a) for a in args])
    return rc, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("args", [
    ["dock", "--bogus"], ["dock", "--trials", "abc"], ["field", "probe", "--radial", "0"],
    ["nosuchcommand"], ["dock", "--compensation", "psychic"],
])
def test_usage_errors_are_one_line(args):
    rc, out, err = run_inprocess(*args)
    assert rc == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), err
    assert "--help" in lines[0]


@pytest.mark.parametrize(("args", "needle"), [
    (["dock", "--trials", "1", "--leader-speed", "nan", "--json"], "--leader-speed"),
    (["dock", "--trials", "1", "--offset", "inf", "--json"], "--offset"),
    (["dock", "--trials", "1", "--offset", "5", "--json"], "ground"),
    (["dock", "--trials", "10000000"], "limit of 10000"),
    (["dock", "--trials", "2000", "--save-logs", "x"], "over the limit of"),
    (["field", "probe", "--separation", "nan", "--radial", "0", "--json"], "--separation"),
    (["field", "probe", "--separation", "0.3", "--radial", "0", "--samples", "100000000"],
     "between 2 and 200000"),
])
def test_bad_numbers_and_sizes_are_refused(args, needle):
    rc, out, err = run_inprocess(*args)
    assert rc == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and needle in err, err


def test_print_json_refuses_nan(capsys):
    import typer

    from aerodock.cli.common import print_json

    with pytest.raises(typer.Exit) as exc:
        print_json({"a": {"b": [1.0, float("nan")]}})
    assert exc.value.exit_code == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "a.b.1" in captured.err


def test_several_paths_after_one_data(tmp_path):
    from aerodock.cli.app import _expand_repeatable

    assert _expand_repeatable(["train", "--data", "a.npz", "b.npz", "--out", "m"]) == [
        "train", "--data", "a.npz", "--data", "b.npz", "--out", "m"]
    assert _expand_repeatable(["evaluate", "--data=a", "b", "--json"]) == [
        "evaluate", "--data=a", "--data", "b", "--json"]
    # commands with positional arguments are left alone
    assert _expand_repeatable(["ingest", "a.csv", "b.csv", "--out", "x"]) == [
        "ingest", "a.csv", "b.csv", "--out", "x"]


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    from short_mission import short_config

    from aerodock.flightlog import save_flightlogs
    from aerodock.mission import MissionSpec, run_campaign

    # (training data for the command's plumbing: the short timing, tests/short_mission.py)
    result = run_campaign(short_config(), MissionSpec(trials=2, seed=1), record="full")
    folder = tmp_path_factory.mktemp("flights")
    return [save_flightlogs(folder / f"f{i}.npz", [log]) for i, log in enumerate(result.logs)]


def test_train_on_two_paths_and_degenerate_data_keeps_the_good_model(flights, tmp_path):
    import json as _json

    import numpy as np

    from aerodock.flightlog import load_flightlogs

    model = tmp_path / "model"
    rc, out, err = run_inprocess("train", "--data", *flights, "--out", model, "--max-epochs",
                                 "2", "--json")
    assert rc == 0, err
    assert _json.loads(out)["n_flights"] == 2
    good = (model / "model.json").read_bytes(), (model / "weights.npz").read_bytes()
    # degenerate: a dataset file with labels of 1e30 m/s² (float32 overflows to inf, the
    # loss to NaN) -> refused, the good model untouched
    from dataclasses import replace

    from aerodock.learning.datafiles import save_dataset
    from aerodock.learning.dataset import build_dataset

    ds = build_dataset(load_flightlogs(flights[0]))
    bad = save_dataset(tmp_path / "bad.npz", replace(ds, y=np.full_like(ds.y, 1e30)))
    rc, out, err = run_inprocess("train", "--data", bad, "--out", model, "--max-epochs", "2")
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "degenerate" in err, err
    assert ((model / "model.json").read_bytes(), (model / "weights.npz").read_bytes()) == good


def test_dock_flies_the_controller_it_is_given(short_toml):
    """--controller changes what flies (it was once overwritten by the config); in-process (the
    option's way to the mission, not the process, is what is checked here)."""
    runs = {}
    for c in ("paper", "tuned"):
        rc, out, err = run_inprocess("dock", "--trials", "2", "--seed", "4", "--controller", c,
                                     "--json", "--config", short_toml)
        assert rc == 0, err
        runs[c] = json.loads(out)
    assert runs["paper"]["controller"] == "paper"
    assert (runs["paper"]["terminal_err_down_median_m"]
            != runs["tuned"]["terminal_err_down_median_m"])
    rc, out, err = run_inprocess("dock", "--trials", "2", "--controller", "bogus")
    assert rc == 2 and out == ""
    assert err.strip().count("\n") == 0 and "controller" in err


def test_targets_refuses_bad_trials_in_one_line():
    bad = aerodock("targets", "--trials", "0", check=False)
    assert bad.returncode == 2
    assert bad.stderr.strip().count("\n") == 0 and "--trials" in bad.stderr


def test_an_interrupt_reported_as_a_system_error_is_an_interrupt(monkeypatch, capsys):
    """Ctrl-C landing while a compiled kernel returns reaches Python as a SystemError caused
    by the KeyboardInterrupt: the command line says 'interrupted' and exits 130, as for any
    Ctrl-C; a SystemError of its own is still a bug (exit 1, its type named)."""
    import aerodock.cli.app as app_module

    def interrupted_kernel() -> None:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as stop:
            raise SystemError("returned a result with an exception set") from stop

    def broken_kernel() -> None:
        raise SystemError("a bug")

    for kernel, want in ((interrupted_kernel, (130, "interrupted\n")),
                         (broken_kernel, (1, "error: SystemError: a bug\n"
                                             "(set AERODOCK_DEBUG=1 for a traceback)\n"))):
        monkeypatch.setattr(app_module, "_expand_repeatable", lambda args, k=kernel: k())
        monkeypatch.delenv("AERODOCK_DEBUG", raising=False)
        rc = app_module.run(["dock"])
        assert (rc, capsys.readouterr().err) == want


def test_help_does_not_load_the_compiled_world():
    """`aerodock --help` and the app's import leave numba, SciPy and PyTorch unloaded (the
    commands import what they fly): about 0.7 s against 1.2 s with numba."""
    import subprocess
    import sys

    code = ("import sys\n"
            "from aerodock.cli import app\n"
            "heavy = [m for m in ('numba', 'scipy', 'torch') if m in sys.modules]\n"
            "assert not heavy, heavy\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert run_cli("--help").returncode == 0


def test_a_bad_fault_file_is_refused_before_the_compiled_world_loads(tmp_path):
    """`dock --faults BAD` says what is wrong in one line and exits 2 without importing numba
    (the fault file is checked before the configuration, whose field loads the compiled wake;
    `aerodock.mission` loads its batch on first use): about 0.55 s against 1.3 s here."""
    import subprocess
    import sys

    bad = tmp_path / "faults.toml"
    bad.write_text('[[fault]]\nkind = "servo_slow"\nduration_s = inf\n')
    code = ("import sys\n"
            "from aerodock.cli import main\n"
            "try:\n"
            "    main()\n"
            "except SystemExit as exc:\n"
            "    print('exit', exc.code, 'numba' in sys.modules)\n")
    proc = subprocess.run([sys.executable, "-c", code, "dock", "--trials", "1", "--faults",
                           str(bad)], capture_output=True, text=True)
    assert proc.stdout.split() == ["exit", "2", "False"], (proc.stdout, proc.stderr)
    assert proc.stderr.strip().count("\n") == 0 and "'duration_s' must be finite" in proc.stderr
