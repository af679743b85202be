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
        ("[vehicle]\nmass_kg = -0.7\n", "'vehicle.mass_kg' must be >= 0.001 and <= 100"),
        ("[sim]\ncontrol_rate_hz = 0\n", "'sim.control_rate_hz' must be >= 1"),
        ("[vehicle]\nmas_kg = 1.0\n", "unknown key 'vehicle.mas_kg'"),
        ("[nonsense]\nx = 1\n", "unknown key 'nonsense'"),
        # keys nothing read: the file is told where the parameter lives, not silently ignored
        ("[mission]\noffset_m = 0.87\n", "'mission.offset_m' is no longer a key (nothing read "
                                          "it): the cable length d_p is 'platform.cable_length_m'"),
        ("[mission]\nleader_speed_mps = 0.5\n", "dock --leader-speed"),
        ("[vehicle]\nmass_kg = \"heavy\"\n", "'vehicle.mass_kg' must be a number"),
        ("[gripper]\ntrigger = \"psychic\"\n", "'gripper.trigger' must be one of"),
        ("[control]\nq_diag = [1, 2]\n", "'control.q_diag' must be 7"),
        ("[downwash]\nfield = \"no_such_pkg.mod:Field\"\n", "names code outside aerodock"),
        ("[downwash]\nfield = \"aerodock.no_such:Field\"\n", "cannot be imported"),
        ("[downwash]\nfield = \"aerodock.downwash.jet:Nope\"\n", "has no attribute 'Nope'"),
        ("[downwash]\nfield = \"nocolon\"\n", "package.module:factory"),
        ("[sim]\nphysics_rate_hz = 330\n", "multiple of"),
        ("not toml at all", "invalid TOML"),
        # issue 12: finiteness, ranges, integers, booleans, tables, plug-in paths
        ("[gripper]\nlatency_s = nan\n", "'gripper.latency_s' must be a finite number"),
        ("[mission]\nclearance_m = inf\n", "'mission.clearance_m' must be a finite number"),
        ("[vehicle]\nmass_kg = 1e308\n", "'vehicle.mass_kg' must be >= 0.001 and <= 100"),
        ("[vehicle]\nrotor_radius_m = 1e-300\n", "'vehicle.rotor_radius_m' must be >= 0.001"),
        ("[vehicle]\nn_rotors = 4.5\n", "'vehicle.n_rotors' must be an integer"),
        ("[control]\nq_diag = [true, 1, 8, 0.01, 0.01, 0.1, 1]\n", "'control.q_diag' must be 7"),
        ("[control]\nq_diag = [1, 1, nan, 0.01, 0.01, 0.1, 1]\n", "'control.q_diag[2]'"),
        ("[curriculum]\nstage0_depth_m = [1.8, 1.5]\n", "low < high"),
        ("[control]\nr_diag = [0.8, 0.8, 0, 1]\n", "'control.r_diag[2]' must be >= 1e-06"),
        ("[control]\nq_diag = [1, 1, 1e308, 0.01, 0.01, 0.1, 1]\n", "'control.q_diag[2]'"),
        ("[downwash.params]\nspread_rate = -0.15\n", "'downwash.params.spread_rate' must be >= 0"),
        ("[downwash.params]\nturb_vertical = nan\n", "'downwash.params.turb_vertical'"),
        ("[downwash]\nparams = 3\n", "'downwash.params' must be a table"),
        ("[downwash]\nfield = \".jet:X\"\n", "package.module:factory"),
        ("[mission]\ndock_window_s = 1e6\n", "'mission.dock_window_s' must be >= 0.01 and <= 600"),
        ("[sim]\nphysics_rate_hz = 1e9\n", "'sim.physics_rate_hz' must be >= 1 and <= 20000"),
        ("downwash = 3\n", "'downwash' must be a table"),
        # physically impossible set-ups
        ("[gripper]\naperture_m = 0.008\n", "must be wider than 'platform.bar_diameter_m'"),
        ("[vehicle]\nthrust_max_g = 0.5\n", "'vehicle.thrust_max_g' must be >= 1.1"),
        ("[vehicle]\nthrust_max_g = 1.0\n", "'vehicle.thrust_max_g' must be >= 1.1"),
        ("[mission]\nleader_altitude_m = 0.4\n", "docking point is"),
        ("[platform]\ncable_length_m = 2.6\n", "at or below the ground"),
        ("[mission]\nstart_below_m = 2.0\n", "the follower would start"),
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


def test_plugin_that_is_not_a_field_factory_is_refused_uncalled(tmp_path, monkeypatch):
    """A trusted module's plain function is not a factory: refused as the config loads."""
    monkeypatch.setenv("AERODOCK_TRUST_PLUGINS", "numpy")
    path = _write(tmp_path, '[downwash]\nfield = "numpy:zeros"\n[downwash.params]\nshape = 3\n')
    with pytest.raises(ConfigError, match="numpy:zeros is not a field factory"):
        load_config(path)


def test_factory_that_builds_no_field(tmp_path, monkeypatch):
    """A marked factory whose result lacks the protocol is refused when it is built."""
    (tmp_path / "plug_nofield.py").write_text(
        "from aerodock.downwash import field_factory\n\n"
        "@field_factory\ndef F(**kw):\n    return object()\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    path = _write(tmp_path, '[downwash]\nfield = "plug_nofield:F"\n')
    cfg = load_config(path, trusted=["plug_nofield"])
    with pytest.raises(ConfigError, match="does not build a field"):
        build_field(cfg)


def test_with_overrides_validates(cfg):
    with pytest.raises(ConfigError, match="cable_length_m"):
        cfg.with_overrides({"platform": {"cable_length_m": 0.0}})
    assert np.isclose(cfg.with_overrides({"platform": {"cable_length_m": 1.0}})
                      .platform.cable_length_m, 1.0)


def test_every_key_has_exactly_one_rule_and_its_default_satisfies_it():
    """defaults.toml (the values) and the schema (types and rules) name exactly the same keys,
    and every default satisfies its key's rule."""
    from aerodock.config.loader import _defaults
    from aerodock.config.schema import RULES

    flat = {}
    for section, values in _defaults().items():
        for key, value in values.items():
            if section == "downwash" and key == "params":
                flat.update({f"downwash.params.{k}": v for k, v in value.items()})
            flat[f"{section}.{key}"] = value
    assert set(flat) == set(RULES)
    for key, value in flat.items():
        rule = RULES[key]
        if rule.kind == "choice":
            assert value in rule.choices, key
        elif rule.kind in ("number", "integer", "numbers", "number_list"):
            items = value if isinstance(value, list) else [value]
            assert all(rule.low <= v <= rule.high for v in items), key
            assert rule.kind != "integer" or isinstance(value, int), key
            assert rule.kind != "numbers" or len(value) == rule.length, key


def test_sections_are_typed_and_misspelt_keys_fail(cfg):
    """A section is a frozen dataclass of its keys: a misspelt key is an AttributeError."""
    from aerodock.config.schema import VehicleSection

    assert isinstance(cfg.vehicle, VehicleSection)
    assert cfg.vehicle.mass_kg == 0.7
    with pytest.raises(AttributeError):
        cfg.vehicle.mass_kilograms  # noqa: B018


def test_plugin_without_params_gets_none_of_the_jets(tmp_path):
    """Switching the field to a plug-in without a params table must not pass the jet's."""
    text = '[downwash]\nfield = "aerodock.downwash.template:UniformColumnField"\n'
    cfg = load_config(_write(tmp_path, text))
    assert cfg.data["downwash"]["params"] == {}
    assert type(build_field(cfg)).__name__ == "UniformColumnField"
    back = cfg.with_overrides({"downwash": {"field": "aerodock.downwash.jet:RoundJetField"}})
    assert back.data["downwash"]["params"] == load_config().data["downwash"]["params"]


_MARK = "from aerodock.downwash import field_factory\n@field_factory\n"


@pytest.mark.parametrize(("body", "needle"), [
    ("raise RuntimeError('boom')\n", "failed on import (RuntimeError: boom)"),
    ("import sys\nsys.exit(3)\n", "failed on import (SystemExit: 3)"),
    (_MARK + "def F(**kw):\n    raise KeyError('k')\n", "failed to build (KeyError"),
    (_MARK + "def F(**kw):\n    import sys\n    sys.exit(4)\n", "failed to build (SystemExit: 4)"),
])
def test_plugin_failures_are_config_errors(tmp_path, monkeypatch, body, needle):
    name = f"plug_{abs(hash(body))}"
    (tmp_path / f"{name}.py").write_text(body)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("AERODOCK_TRUST_PLUGINS", name)
    path = _write(tmp_path, f'[downwash]\nfield = "{name}:F"\n')
    with pytest.raises(ConfigError) as err:
        build_field(load_config(path))
    assert needle in str(err.value) and str(path) in str(err.value)


def test_integral_float_is_refused_for_an_integer_key(tmp_path):
    """An integer key takes an integer (the documented rule; the audit of issue 25 found 6.0
    accepted): a float is refused even when it is whole."""
    with pytest.raises(ConfigError, match="'vehicle.n_rotors' must be an integer, got 6.0"):
        load_config(_write(tmp_path, "[vehicle]\nn_rotors = 6.0\n"))
    cfg = load_config(_write(tmp_path, "[vehicle]\nn_rotors = 6\n"))
    assert cfg.vehicle.n_rotors == 6 and isinstance(cfg.vehicle.n_rotors, int)


def test_an_installed_packages_declared_field_needs_no_trust(tmp_path, monkeypatch):
    """A field declared in the ``aerodock.fields`` entry-point group loads as a built-in does;
    another attribute of the same module is not declared, so it is refused unimported."""
    from importlib.metadata import EntryPoint

    from aerodock.config import plugins

    monkeypatch.delenv("AERODOCK_TRUST_PLUGINS", raising=False)
    (tmp_path / "declared_fields.py").write_text(
        "from aerodock.downwash.template import UniformColumnField as Column\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    points = [EntryPoint("column", "declared_fields:Column", plugins.ENTRY_POINT_GROUP)]
    monkeypatch.setattr(plugins.metadata, "entry_points",
                        lambda group: points if group == plugins.ENTRY_POINT_GROUP else [])
    cfg = load_config(_write(tmp_path, '[downwash]\nfield = "declared_fields:Column"\n'))
    assert type(build_field(cfg)).__name__ == "UniformColumnField"
    with pytest.raises(ConfigError, match="names code outside aerodock"):
        load_config(_write(tmp_path, '[downwash]\nfield = "declared_fields:Other"\n'))


def test_set_applies_after_the_file_and_before_the_checks(tmp_path):
    """--set wins over the file; the rules between keys see the result (a file that alone
    breaks one is rescued by a --set, and the other way round)."""
    path = _write(tmp_path, "[platform]\ncable_length_m = 0.64\n[vehicle]\nmass_kg = 0.8\n")
    cfg = load_config(path, sets=["platform.cable_length_m=0.5", "vehicle.n_rotors=6"])
    assert (cfg.platform.cable_length_m, cfg.vehicle.mass_kg, cfg.vehicle.n_rotors) == (0.5, 0.8, 6)
    assert isinstance(cfg.platform.cable_length_m, float)  # 0.5 typed as the key's default
    bad = _write(tmp_path, "[gripper]\naperture_m = 0.008\n")
    assert load_config(bad, sets=["platform.bar_diameter_m=0.005"]).gripper.aperture_m == 0.008
    with pytest.raises(ConfigError, match=r"\+ --set: 'gripper.aperture_m'"):
        load_config(sets=["gripper.aperture_m=0.008"])


def test_plugin_params_by_set_merge_into_the_files(tmp_path):
    text = ('[downwash]\nfield = "aerodock.downwash.template:UniformColumnField"\n'
            '[downwash.params]\naccel_mps2 = 2.0\nradius_m = 0.2\n')
    cfg = load_config(_write(tmp_path, text), sets=["downwash.params.radius_m=0.3"])
    assert cfg.data["downwash"]["params"] == {"accel_mps2": 2.0, "radius_m": 0.3}
