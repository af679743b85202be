"""The one data location (aerodock.ingest.data_dir): --data-dir, then AERODOCK_DATA_DIR, then
this repository's ../shared/data; a named location that is not a folder stops the command with one
line before anything runs."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_process import aerodock

from aerodock.ingest.data_dir import (
    ENV_VAR,
    NEURAL_SWARM,
    fallback_dirs,
    find_data_dir,
    has_swap_flights,
)


def _flights(root: Path, folder: str = "swap_ss") -> Path:
    """A data location holding one (empty) Neural-Swarm flight file in ``folder``."""
    (root / NEURAL_SWARM / folder).mkdir(parents=True)
    (root / NEURAL_SWARM / folder / "cf50_00.csv").write_text("# time\n")
    return root


def test_the_option_beats_the_variable_which_beats_the_fallback(tmp_path):
    opt, env, cwd = tmp_path / "opt", tmp_path / "env", tmp_path / "work" / "clone"
    for folder in (opt, env, cwd, tmp_path / "work" / "shared" / "data"):
        folder.mkdir(parents=True)
    environ = {ENV_VAR: str(env)}
    assert find_data_dir(opt, environ, cwd) == find_data_dir(str(opt), {}, cwd)
    assert find_data_dir(opt, environ, cwd).path == opt
    assert find_data_dir(opt, environ, cwd).source == "--data-dir"
    assert find_data_dir(None, environ, cwd).path == env
    assert find_data_dir(None, environ, cwd).source == ENV_VAR
    fallback = find_data_dir(None, {}, cwd)
    assert fallback.path == tmp_path / "work" / "shared" / "data"
    assert fallback.source == "../shared/data" and not fallback.named


def test_an_empty_variable_counts_as_unset(tmp_path):
    cwd = tmp_path / "clone"
    cwd.mkdir()
    (tmp_path / "shared" / "data").mkdir(parents=True)
    assert find_data_dir(None, {ENV_VAR: "  "}, cwd).path == tmp_path / "shared" / "data"


def test_without_a_location_there_is_no_path_and_no_error(tmp_path):
    cwd = tmp_path / "clone"
    cwd.mkdir()
    located = find_data_dir(None, {}, cwd)
    if any(folder.is_dir() for folder in fallback_dirs(cwd)):
        # the repository's own ../shared/data (this project's machines) is the second fallback
        assert located.path == fallback_dirs(cwd)[1]
    else:
        assert located.path is None and located.source == "none"
    assert located.problem() is None


def test_a_named_location_that_is_not_a_folder_is_a_one_line_problem(tmp_path):
    missing = tmp_path / "nowhere"
    located = find_data_dir(missing, {}, tmp_path)
    assert located.path == missing and located.named
    assert located.problem().startswith(f"--data-dir {missing}: no such folder")
    assert "\n" not in located.problem()
    by_env = find_data_dir(None, {ENV_VAR: str(missing)}, tmp_path)
    assert by_env.problem().startswith(f"{ENV_VAR} {missing}: no such folder")
    (tmp_path / "a_file").write_text("x")
    assert find_data_dir(tmp_path / "a_file", {}, tmp_path).problem() is not None


def test_the_flights_are_found_only_where_the_csv_files_are(tmp_path):
    root = _flights(tmp_path / "data")
    located = find_data_dir(root, {}, tmp_path)
    assert located.neural_swarm() == root / NEURAL_SWARM
    assert has_swap_flights(located.neural_swarm())
    assert not has_swap_flights(located.neural_swarm(), ("swap_ss", "swap_sl_2020-06-19"))
    (root / NEURAL_SWARM / "swap_sl_2020-06-19").mkdir()
    assert not has_swap_flights(root / NEURAL_SWARM, ("swap_sl_2020-06-19",))  # no CSV in it
    assert not has_swap_flights(None)
    assert find_data_dir(None, {}, tmp_path / "x").neural_swarm() in (
        None, fallback_dirs(tmp_path / "x")[1] / NEURAL_SWARM)


@pytest.mark.parametrize("command", [["reproduce", "--smoke"], ["evaluate-compensation"]])
def test_commands_refuse_a_named_location_that_is_missing(tmp_path, command, monkeypatch):
    missing = tmp_path / "nowhere"
    out = ["--out", str(tmp_path / "out")] if command[0] == "reproduce" else []
    proc = aerodock(*command, *out, "--data-dir", missing, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip() == (f"error: --data-dir {missing}: no such folder (the data "
                                   f"location holding {NEURAL_SWARM}/; see docs/real-logs.md)")
    assert not (tmp_path / "out").exists()
    monkeypatch.setenv(ENV_VAR, str(missing))
    proc = aerodock(*command, *out, cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.startswith(f"error: {ENV_VAR} {missing}: ")
    assert "Traceback" not in proc.stderr and not (tmp_path / "out").exists()


def test_evaluate_compensation_takes_the_folder_or_the_location_not_both(tmp_path):
    root = _flights(tmp_path / "data")
    proc = aerodock("evaluate-compensation", "--data", root / NEURAL_SWARM, "--data-dir", root,
                    cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == ("error: give --data (the neural-swarm folder) or --data-dir "
                                   "(the folder holding it), not both")


def test_evaluate_compensation_reads_the_flights_in_the_variables_location(tmp_path, monkeypatch):
    # The location holds swap_ss but not swap_sl_2020-06-19: the study names the missing folder,
    # under the location the variable gave (not ../shared).
    root = _flights(tmp_path / "data")
    monkeypatch.setenv(ENV_VAR, str(root))
    proc = aerodock("evaluate-compensation", "--quick", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert str(root / NEURAL_SWARM) in proc.stderr and "Traceback" not in proc.stderr
