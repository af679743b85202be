"""Sweep axes over any config key and over the controller: parsed, checked by the config's own
rules before anything runs, and flown as the configuration ``dock`` would fly."""

from __future__ import annotations

import tomllib

import pytest
from short_mission import short_mission_toml

from aerodock.config import load_config
from aerodock.control.profiles import controller_config
from aerodock.sweep import SweepSpecError, cell_config, load_spec, parse_spec, run_sweep
from aerodock.sweep.spec import check_against_config

FAST_WORLD = {"vehicle": {"model": "point-mass"}, "sim": {"physics_rate_hz": 100.0}}


@pytest.fixture(scope="module")
def fast_cfg():
    """The short mission in the cheapest world (what is tested is which config flies)."""
    base = tomllib.loads(short_mission_toml())
    return load_config().with_overrides({**base, **FAST_WORLD})


def test_dotted_and_quoted_config_keys_are_axes():
    doc = tomllib.loads('[axes]\ndownwash.params.turb_vertical = [0, 0.3]\n'
                        '"mission.terminal_s" = [1.0]\ncontroller = ["paper", "ours"]\n')
    spec = parse_spec(doc)
    assert len(spec.cells) == 2 * 1 * 2
    assert {c.controller for c in spec.cells} == {"paper", "ours"}
    settings = {c.settings for c in spec.cells}
    assert settings == {(("downwash.params.turb_vertical", 0.0), ("mission.terminal_s", 1.0)),
                        (("downwash.params.turb_vertical", 0.3), ("mission.terminal_s", 1.0))}
    assert isinstance(spec.cells[0].settings[0][1], float)  # 0 in a float key is 0.0
    row = spec.cells[0].row()
    assert list(row)[-4:] == ["controller", "downwash.params.turb_vertical",
                              "mission.terminal_s", "seed"]


def test_random_ranges_of_config_keys_draw_the_key_type():
    doc = {"sweep": {"kind": "random", "samples": 12, "sampling_seed": 1},
           "axes": {"mission": {"terminal_s": {"min": 0.5, "max": 1.5}},
                    "gripper": {"calibration_samples": {"min": 20, "max": 60}}}}
    spec = parse_spec(doc)
    values = [dict(c.settings) for c in spec.cells]
    assert all(0.5 <= v["mission.terminal_s"] <= 1.5 for v in values)
    assert all(type(v["gripper.calibration_samples"]) is int
               and 20 <= v["gripper.calibration_samples"] <= 60 for v in values)
    assert len({v["mission.terminal_s"] for v in values}) == 12


@pytest.mark.parametrize("axes, message", [
    ({"downwash": {"turb_vertical": [0.1]}}, "did you mean downwash.params.turb_vertical"),
    ({"downwash": {"field": ["os:system"]}}, "names code"),
    ({"downwash": {"params": [1]}}, "a table, not a value"),
    ({"mission": {"nope": [1]}}, "unknown axis 'axes.mission.nope'"),
    ({"platform": {"cable_length_m": [0.5]}}, "is the cable_length_m axis"),
    ({"controller": ["best"]}, "not one of paper|tuned|ours"),
    ({"mission": {"terminal_s": {"min": 0.5, "max": 1.0}}}, "needs a random study"),
    ({"vehicle": {"model": {"min": 0, "max": 1}}}, "needs a random study"),
])
def test_bad_axes_are_refused_on_parsing(axes, message):
    with pytest.raises(SweepSpecError, match=message):
        parse_spec({"axes": axes}, "s.toml")


@pytest.mark.parametrize("axes, message", [
    ({"downwash": {"params": {"turb_vertical": [0.2, 20.0]}}},
     r"axes: 'downwash.params.turb_vertical' must be >= 0 and <= 10, got 20.0"),
    ({"vehicle": {"model": ["rigid"]}}, "'vehicle.model' must be one of point-mass|rigid-body"),
    ({"control": {"q_diag": [3.0]}}, "'control.q_diag' must be a list"),
    ({"leader": {"model": ["point-mass"]}}, "'leader.model' cannot differ"),
    # a rule between keys, on the configuration the sweep flies (physics at 100 Hz here)
    ({"sim": {"control_rate_hz": [100.0, 200.0]}}, "'sim.physics_rate_hz' must be >="),
    ({"mission": {"leader_altitude_m": [0.5]}}, "at or below the ground"),
])
def test_config_values_are_checked_by_the_config_rules_before_anything_runs(
        axes, message, fast_cfg):
    spec = parse_spec({"axes": axes}, "s.toml")
    with pytest.raises(SweepSpecError, match=message) as err:
        check_against_config(spec, fast_cfg)
    assert str(err.value).startswith("s.toml: ") and "\n" not in str(err.value)


def test_a_cell_flies_its_config_keys_then_its_controller(fast_cfg):
    spec = parse_spec({"axes": {"controller": ["paper"], "control": {"q_diag": [[2.0] * 7]},
                                "mocap_noise_scale": [3.0]}})
    cfg = cell_config(fast_cfg, spec.cells[0])
    # the profile is applied over the config keys, as dock --controller over --config
    assert cfg.control.q_diag == controller_config(fast_cfg, "paper").control.q_diag
    assert cfg.control.bias_estimator == "freyja"
    assert cfg.mocap.pos_noise_m == pytest.approx(3.0 * fast_cfg.mocap.pos_noise_m)
    spec = parse_spec({"axes": {"leader": {"mass_kg": [0.9]}}})
    cfg = cell_config(fast_cfg, spec.cells[0])
    assert (cfg.leader.mass_kg, cfg.vehicle.mass_kg) == (0.9, fast_cfg.vehicle.mass_kg)


def test_sweep_over_a_config_key_and_the_controller_flies_what_dock_flies(fast_cfg):
    """Each cell's outcomes are the campaign of its configuration, flown directly."""
    from aerodock.mission import MissionSpec, run_campaign

    spec = parse_spec({"sweep": {"trials": 2, "seeds": [3]},
                       "axes": {"controller": ["paper", "ours"],
                                "downwash": {"params": {"turb_vertical": [0.0, 0.6]}}}})
    rows = run_sweep(spec, fast_cfg, jobs=1)
    assert len(rows) == 4 * 2
    seen = set()
    for cell in spec.cells:
        mine = [r for r in rows if r["cell"] == cell.index]
        turb = dict(cell.settings)["downwash.params.turb_vertical"]
        assert {(r["controller"], r["downwash.params.turb_vertical"]) for r in mine} == {
            (cell.controller, turb)}
        cfg = controller_config(
            fast_cfg.with_overrides({"downwash": {"params": {"turb_vertical": turb}}}),
            cell.controller)
        direct = run_campaign(cfg, MissionSpec(trials=2, seed=3))
        assert [r["err_down_m"] for r in mine] == [float(e) for e in direct.err_down_m]
        seen.add(tuple(r["err_down_m"] for r in mine))
    assert len(seen) == 4  # every axis changes what is flown


def test_sweep_command_over_a_config_key_writes_its_column_and_figures(tmp_path):
    from cli_process import aerodock

    (tmp_path / "fast.toml").write_text(
        '[vehicle]\nmodel = "point-mass"\n[sim]\nphysics_rate_hz = 100.0\n'
        + short_mission_toml())
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text('[sweep]\ntrials = 2\nconfig = "fast.toml"\n[axes]\n'
                         'controller = ["paper", "ours"]\n'
                         'downwash.params.turb_vertical = [0.1]\n')
    spec = load_spec(spec_path)
    assert [c.controller for c in spec.cells] == ["paper", "ours"]
    out = tmp_path / "out"
    proc = aerodock("sweep", spec_path, "--out", out, "--jobs", "2")
    assert proc.returncode == 0, proc.stderr
    header = (out / "results.csv").read_text().splitlines()[0].split(",")
    assert "controller" in header and "downwash.params.turb_vertical" in header
    assert (out / "figures" / "sweep_success.png").read_bytes()[:4] == b"\x89PNG"
    assert "ours" in proc.stdout and "paper" in proc.stdout


def test_the_example_studies_parse_and_fit_the_default_config():
    from pathlib import Path

    examples = sorted((Path(__file__).resolve().parents[2] / "examples").glob("sweep_*.toml"))
    assert len(examples) >= 2
    for path in examples:
        spec = load_spec(path)
        check_against_config(spec, load_config(spec.config))
    spec = load_spec(examples[[p.name for p in examples].index("sweep_controller_wake.toml")])
    assert len(spec.cells) == 9 and {c.controller for c in spec.cells} == {"paper", "tuned",
                                                                            "ours"}
