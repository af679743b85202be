"""Configuration: defaults, overrides, and one-line errors naming key and file."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.config import ConfigError, load_config
from aerodock.downwash import build_field


def _write(tmp_path, text):
    path = tmp_path / "user.toml"
    path.write_text(text)
    return path


def test_defaults_are_the_papers_vehicles(cfg):
    assert cfg.vehicle.mass_kg == 0.7
    assert cfg.vehicle.diagonal_m == 0.27
    assert cfg.vehicle.rotor_radius_m == 0.0635
    assert cfg.platform.cable_length_m == 0.36
    assert cfg.gripper.aperture_m == 0.1
    assert list(cfg.control.q_diag) == [1, 1, 8, 0.01, 0.01, 0.1, 1]


def test_user_file_overrides_a_subset(tmp_path):
    cfg = load_config(_write(tmp_path, "[platform]\ncable_length_m = 0.64\n"))
    assert cfg.platform.cable_length_m == 0.64
    assert cfg.vehicle.mass_kg == 0.7


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("[vehicle]\nmass_kg = -0.7\n", "'vehicle.mass_kg' must be > 0"),
        ("[sim]\ncontrol_rate_hz = 0\n", "'sim.control_rate_hz' must be > 0"),
        ("[vehicle]\nmas_kg = 1.0\n", "unknown key 'vehicle.mas_kg'"),
        ("[nonsense]\nx = 1\n", "unknown key 'nonsense'"),
        ("[vehicle]\nmass_kg = \"heavy\"\n", "'vehicle.mass_kg' must be a number"),
        ("[gripper]\ntrigger = \"psychic\"\n", "'gripper.trigger' must be one of"),
        ("[control]\nq_diag = [1, 2]\n", "'control.q_diag' must be 7"),
        ("[downwash]\nfield = \"no_such_pkg.mod:Field\"\n", "cannot be imported"),
        ("[downwash]\nfield = \"aerodock.downwash.jet:Nope\"\n", "has no attribute 'Nope'"),
        ("[downwash]\nfield = \"nocolon\"\n", "package.module:factory"),
        ("[sim]\nphysics_rate_hz = 330\n", "multiple of"),
        ("not toml at all", "invalid TOML"),
    ],
)
def test_invalid_values_give_one_line_errors(tmp_path, text, needle):
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError) as err:
        load_config(path)
    msg = str(err.value)
    assert needle in msg
    assert str(path) in msg
    assert "\n" not in msg


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "absent.toml")


def test_plugin_field_loaded_by_import_path(tmp_path):
    text = ('[downwash]\nfield = "aerodock.downwash.template:UniformColumnField"\n'
            '[downwash.params]\naccel_mps2 = 2.0\nradius_m = 0.2\n')
    cfg = load_config(_write(tmp_path, text))
    field = build_field(cfg)
    assert type(field).__name__ == "UniformColumnField"
    assert field.accel_mps2 == 2.0


def test_plugin_with_bad_params_names_the_file(tmp_path):
    text = ('[downwash]\nfield = "aerodock.downwash.template:UniformColumnField"\n'
            '[downwash.params]\nwrong = 1\n')
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError, match="do not fit") as err:
        build_field(load_config(path))
    assert str(path) in str(err.value)


def test_plugin_that_is_not_a_field(tmp_path):
    path = _write(tmp_path, '[downwash]\nfield = "numpy:zeros"\n[downwash.params]\nshape = 3\n')
    with pytest.raises(ConfigError, match="does not build a field"):
        build_field(load_config(path))


def test_with_overrides_validates(cfg):
    with pytest.raises(ConfigError, match="cable_length_m"):
        cfg.with_overrides({"platform": {"cable_length_m": 0.0}})
    assert np.isclose(cfg.with_overrides({"platform": {"cable_length_m": 1.0}})
                      .platform.cable_length_m, 1.0)
