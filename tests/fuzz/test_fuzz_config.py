"""Config TOML fuzzing: every file loads into a valid, finite config or gives a ConfigError."""

from __future__ import annotations

import json
import math
import random
import sys
from importlib import resources
from pathlib import Path

import pytest
from fuzz_helpers import (
    NASTY_VALUES,
    assert_clean,
    count,
    mutate_bytes,
    n_cases,
    run_cli,
    toml_value,
)

from aerodock.config import Config, ConfigError, load_config
from aerodock.config.loader import _defaults
from aerodock.downwash import build_field

FAULTS = Path(__file__).resolve().parents[2] / "examples" / "faults.toml"
DEFAULTS_TEXT = resources.files("aerodock.config").joinpath("defaults.toml").read_text()
PLUGINS = ["aerodock.downwash.template:UniformColumnField", "aerodock.downwash.jet:RoundJetField",
           ".jet:X", "numpy:zeros", "os:system", "aerodock.downwash.jet", "a b:c", "json:loads"]


def _keys() -> list[tuple[str, str]]:
    out = []
    for section, table in _defaults().items():
        for key, value in table.items():
            if isinstance(value, dict):
                out.extend((f"{section}.{key}", sub) for sub in value)
            else:
                out.append((section, key))
    return out


KEYS = _keys()


def _random_toml(rng: random.Random) -> str:
    """One to four keys set to nasty or slightly-off values, sometimes a plug-in field."""
    tables: dict[str, dict[str, object]] = {}
    for _ in range(rng.randint(1, 4)):
        section, key = rng.choice(KEYS)
        default = _defaults()
        for part in section.split("."):
            default = default[part]
        default = default[key]
        if rng.random() < 0.5 or isinstance(default, str | bool):
            value = rng.choice(NASTY_VALUES)
        elif isinstance(default, list):
            value = [v * rng.choice([-1, 0, 0.5, 2, 1e6]) for v in default][::rng.choice([1, -1])]
        else:
            value = default * rng.choice([-1, 0, 1e-9, 0.5, 2, 10, 1e3, 1e9])
            value = int(value) if isinstance(default, int) else float(value)
        tables.setdefault(section, {})[key] = value
    if rng.random() < 0.15:
        tables.setdefault("downwash", {})["field"] = rng.choice(PLUGINS)
    if rng.random() < 0.05:
        tables.setdefault("downwash", {})["params"] = rng.choice([3, "x", [1]])
    lines = []
    for section, values in tables.items():
        if section == "downwash" and "params" in values and not isinstance(values["params"], dict):
            lines.append("[downwash]")
            lines.append(f"params = {toml_value(values.pop('params'))}")
            lines.extend(f"{k} = {toml_value(v)}" for k, v in values.items())
            continue
        lines.append(f"[{section}]")
        lines.extend(f"{k} = {toml_value(v)}" for k, v in values.items())
    return "\n".join(lines) + "\n"


def _all_finite(obj) -> bool:
    if isinstance(obj, float):
        return math.isfinite(obj)
    if isinstance(obj, dict):
        return all(_all_finite(v) for v in obj.values())
    if isinstance(obj, list):
        return all(_all_finite(v) for v in obj)
    return True


def _check(path) -> Config | None:
    try:
        cfg = load_config(path)
        build_field(cfg)
    except ConfigError as err:
        assert "\n" not in str(err).strip() or "TOML" in str(err)
        assert str(path) in str(err)
        return None
    assert _all_finite(cfg.data)
    return cfg


def test_random_config_values(tmp_path):
    rng = random.Random(12)
    loaded = 0
    path = tmp_path / "user.toml"
    for _ in range(n_cases(600)):
        path.write_text(_random_toml(rng))
        loaded += _check(path) is not None
        count("config-values")
    assert 0 < loaded < n_cases(600)


def test_damaged_defaults_file(tmp_path):
    rng = random.Random(5)
    path = tmp_path / "damaged.toml"
    for _ in range(n_cases(250)):
        path.write_bytes(mutate_bytes(DEFAULTS_TEXT.encode(), rng))
        _check(path)
        count("config-bytes")


def test_random_configs_through_the_cli(tmp_path):
    """``field probe`` (and a few ``dock`` runs) under random configs: 0 or 2, strict JSON."""
    rng = random.Random(99)
    results = []
    for i in range(n_cases(60)):
        path = tmp_path / f"c{i}.toml"
        path.write_text(_random_toml(rng))
        if i % 12 == 0:
            args = ["dock", "--trials", "1", "--config", path, "--json"]
        else:
            args = ["field", "probe", "--separation", rng.choice(["0.36", "0.64", "1.35", "0"]),
                    "--radial", rng.choice(["0", "0.1", "-0.3"]), "--samples", "20",
                    "--config", path, "--json"]
        results.append(run_cli(args, family="cli-config"))
    assert_clean(results)


# -- a config names code only when the user says so (issue 41) ---------------------------------

# Objects that run code when called with a config's params, none of them a field factory.
CODE_CALLS = [
    ("os:system", {"command": "touch {sentinel}"}),
    ("os:popen", {"cmd": "touch {sentinel}"}),
    ("subprocess:run", {"args": ["touch", "{sentinel}"]}),
    ("subprocess:Popen", {"args": ["touch", "{sentinel}"]}),
    ("subprocess:getoutput", {"cmd": "touch {sentinel}"}),
    ("builtins:exec", {"source": "open('{sentinel}', 'w')"}),
    ("builtins:eval", {"source": "open('{sentinel}', 'w')"}),
    ("builtins:open", {"file": "{sentinel}", "mode": "w"}),
    ("pathlib:Path", {"args": "{sentinel}"}),
    ("runpy:run_path", {"path_name": "{script}"}),
    ("shutil:rmtree", {"path": "{victim}"}),
    ("importlib:import_module", {"name": "{evil}"}),
]

# A module whose import alone writes the sentinel, and an unmarked function that does when called.
EVIL_MODULE = """
from pathlib import Path
Path({sentinel!r}).write_text("imported")

def F(**kw):
    Path({sentinel!r}).write_text("called")
    return None

class NotAField:
    def reset(self, n, rng):
        pass
"""

GOOD_MODULE = """
import numpy as np

class ColumnField:
    def __init__(self, accel_mps2=2.0):
        self.accel_mps2 = accel_mps2

    def reset(self, n, rng):
        pass

    def acceleration(self, leader, follower, dt):
        out = np.zeros_like(follower.p)
        out[:, 2] = self.accel_mps2
        return out
"""


def _toml_config(field: str, params: dict) -> str:
    lines = ["[downwash]", f"field = {toml_value(field)}", "[downwash.params]"]
    lines += [f"{k} = {toml_value(v)}" for k, v in params.items()]
    return "\n".join(lines) + "\n"


def _plant(tmp_path, monkeypatch, tag: str) -> dict[str, object]:
    """A sentinel path (must never exist), a folder that must survive, a script and an evil
    module (on sys.path, never imported)."""
    sentinel = tmp_path / f"sentinel_{tag}"
    victim = tmp_path / f"victim_{tag}"
    victim.mkdir()
    (victim / "keep").write_text("x")
    script = tmp_path / f"script_{tag}.py"
    script.write_text(f"open({str(sentinel)!r}, 'w')\n")
    evil = f"aerodock_fuzz_evil_{tag}"
    (tmp_path / f"{evil}.py").write_text(EVIL_MODULE.format(sentinel=str(sentinel)))
    monkeypatch.syspath_prepend(str(tmp_path))
    return {"sentinel": sentinel, "victim": victim, "script": script, "evil": evil}


def _fill(value, names):
    if isinstance(value, str):
        return value.format(**{k: str(v) for k, v in names.items()})
    if isinstance(value, list):
        return [_fill(v, names) for v in value]
    return value


def _nothing_ran(names) -> None:
    assert not names["sentinel"].exists(), "a config ran code"
    assert (names["victim"] / "keep").exists(), "a config removed a folder"
    assert names["evil"] not in sys.modules, "an untrusted module was imported"


def _commands(rng: random.Random, path) -> list[str]:
    return rng.choice([
        ["dock", "--trials", "1", "--config", path, "--json"],
        ["field", "probe", "--separation", "0.5", "--radial", "0", "--samples", "4",
         "--config", path, "--json"],
        ["faults", str(FAULTS), "--trials", "1", "--config", path],
        ["collect", "--out", "collected", "--config", path],
        ["field", "plot", "--out", "f.png", "--config", path],
        ["targets", "--trials", "1", "--config", path],
    ])


def test_code_naming_configs_run_nothing(tmp_path, monkeypatch):
    """The audit's case and its relatives: a config naming a function of the standard library
    or an untrusted module is refused in one line, and nothing it names runs or is imported,
    whichever command reads it, by file or by --set."""
    monkeypatch.delenv("AERODOCK_TRUST_PLUGINS", raising=False)
    names = _plant(tmp_path, monkeypatch, "a")
    rng = random.Random(41)
    results = []
    cases = [*CODE_CALLS, (f"{names['evil']}:F", {}), (f"{names['evil']}:NotAField", {})]
    for i in range(n_cases(20)):
        field, params = cases[i % len(cases)]
        params = _fill(params, names)
        path = tmp_path / f"evil{i}.toml"
        path.write_text(_toml_config(field, params))
        args = _commands(rng, path)
        if i % 7 == 3:  # a sweep specification's config
            spec = tmp_path / f"spec{i}.toml"
            spec.write_text(f'[sweep]\ntrials = 1\nconfig = "{path.name}"\n'
                            "[axes]\ncable_length_m = [0.36, 0.64]\n")
            args = ["sweep", spec, "--out", tmp_path / "swept", "--jobs", "1"]
        elif i % 3 == 2:  # the same field by --set, on top of a harmless file
            path.write_text("[platform]\ncable_length_m = 0.5\n")
            args += ["--set", f"downwash.field={field}"]
            args += [f"--set=downwash.params.{k}={toml_value(v)}" for k, v in params.items()]
        res = run_cli(args, family="config-code")
        results.append(res)
        assert res.rc == 2, (args, res.err)
        assert "names code outside aerodock" in res.err or "not a field factory" in res.err, res.err
        _nothing_ran(names)
        assert not (tmp_path / "swept").exists()
    assert_clean(results)


def test_untrusted_module_is_not_imported(tmp_path, monkeypatch):
    """Refused before import: the module is on sys.path, yet not in sys.modules after, and its
    top-level code (which writes the sentinel) never ran; trusting another module, or a
    prefix that only looks like it, does not help."""
    names = _plant(tmp_path, monkeypatch, "b")
    evil = names["evil"]
    path = tmp_path / "evil.toml"
    path.write_text(_toml_config(f"{evil}:F", {}))
    for env, flags in [(None, []), ("numpy", []), (evil[:-1], []), (None, ["aerodock"]),
                       (f"{evil}.sub", []), (None, [f"{evil}:G"]), ("", [evil + "x"])]:
        if env is None:
            monkeypatch.delenv("AERODOCK_TRUST_PLUGINS", raising=False)
        else:
            monkeypatch.setenv("AERODOCK_TRUST_PLUGINS", env)
        with pytest.raises(ConfigError, match="names code outside aerodock") as err:
            load_config(path, trusted=flags)
        assert str(path) in str(err.value) and "\n" not in str(err.value)
        _nothing_ran(names)
        res = run_cli(["field", "probe", "--separation", "0.5", "--radial", "0", "--config", path,
                       *[f"--trust-plugin={f}" for f in flags]], family="config-code")
        assert res.rc == 2 and not res.problems, res
        _nothing_ran(names)
    # Naming the module through a change of field (a sweep axis, a profile) is refused too.
    with pytest.raises(ConfigError, match="names code outside aerodock"):
        load_config().with_overrides({"downwash": {"field": f"{evil}:F"}})
    _nothing_ran(names)


def test_non_field_objects_are_refused_uncalled_even_when_trusted(tmp_path, monkeypatch):
    """With every module trusted (``*``), what is named must still be a field factory: a
    function or class without reset and acceleration is refused and never called."""
    monkeypatch.setenv("AERODOCK_TRUST_PLUGINS", "*")
    names = _plant(tmp_path, monkeypatch, "c")
    sys.modules.pop(names["evil"], None)
    rng = random.Random(7)
    for field, params in [*CODE_CALLS, (f"{names['evil']}:F", {}),
                          (f"{names['evil']}:NotAField", {})]:
        path = tmp_path / "trusted.toml"
        path.write_text(_toml_config(field, _fill(params, names)))
        with pytest.raises(ConfigError, match="is not a field factory") as err:
            load_config(path)
        assert "\n" not in str(err.value) and str(path) in str(err.value)
        res = run_cli(_commands(rng, path), family="config-code")
        assert res.rc == 2 and not res.problems, (res.args, res.err)
        assert not names["sentinel"].exists() or names["sentinel"].read_text() == "imported"
        assert (names["victim"] / "keep").exists()
    # The trusted evil module was imported (the user said so), its function never called.
    assert names["sentinel"].read_text() == "imported"


@pytest.mark.parametrize("how", ["env", "env-prefix", "env-star", "flag", "flag-path"])
def test_trusted_module_flies(tmp_path, monkeypatch, how):
    """A user's field from a module they trust, by the environment or by --trust-plugin, runs
    through the command line like a built-in one."""
    monkeypatch.delenv("AERODOCK_TRUST_PLUGINS", raising=False)
    package = tmp_path / f"userfields_{how.replace('-', '_')}"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "column.py").write_text(GOOD_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    module = f"{package.name}.column"
    path = tmp_path / "user.toml"
    path.write_text(_toml_config(f"{module}:ColumnField", {"accel_mps2": 2.5}))
    flags: list[str] = []
    if how.startswith("env"):
        value = {"env": module, "env-prefix": package.name, "env-star": "*"}[how]
        monkeypatch.setenv("AERODOCK_TRUST_PLUGINS", f"other, {value}")
    else:
        flags = ["--trust-plugin", module if how == "flag" else f"{module}:ColumnField"]
    res = run_cli(["field", "probe", "--separation", "0.5", "--radial", "0", "--samples", "4",
                   "--config", path, *flags, "--json"], family="config-trusted")
    assert res.rc == 0, res.err
    doc = json.loads(res.out)
    assert doc["mean_mps2"] == pytest.approx([0.0, 0.0, 2.5])
    assert doc["source"] == f"{module}:ColumnField"
    # Without the trust the same file is refused.
    monkeypatch.delenv("AERODOCK_TRUST_PLUGINS", raising=False)
    res = run_cli(["field", "probe", "--separation", "0.5", "--radial", "0", "--config", path],
                  family="config-trusted")
    assert res.rc == 2 and "--trust-plugin" in res.err


# -- --set section.key=value --------------------------------------------------------------------

SET_KEYS = [f"{section}.{key}" for section, key in KEYS]
BAD_SET_KEYS = ["nope.x", "vehicle.nope", "vehicle", "vehicle.", ".mass_kg", "vehicle..mass_kg",
                "vehicle.mass_kg.x", "downwash.params.nope", "mission.offset_m", "=", "",
                "leader.model", "leader.nope", "sim.physics_rate_hz.x.y"]
SET_VALUES = ["nan", "inf", "-1", "0", "1e308", "abc", "", "true", "[1, 2]", "\"x\"", "'x'",
              "\"unterminated", "[1, 2", "{a = 1}", "1979-05-27", "0x10", "1_000", "4.5",
              "[0.5, 0.8]", "point-mass", "=", "1 2"]


def test_set_fuzz_through_the_cli():
    """Random --set pairs (known and unknown keys, nasty values, missing '='): exit 0 or 2,
    one error line naming --set and the key, never a traceback."""
    rng = random.Random(4141)
    results = []
    for _ in range(n_cases(150)):
        sets = []
        for _ in range(rng.randint(1, 3)):
            key = rng.choice(SET_KEYS + BAD_SET_KEYS)
            sets.append(key if rng.random() < 0.05 else f"{key}={rng.choice(SET_VALUES)}")
        args = ["field", "probe", "--separation", "0.5", "--radial", "0", "--samples", "4",
                "--json"]
        for text in sets:
            args += ["--set", text] if rng.random() < 0.5 else [f"--set={text}"]
        res = run_cli(args, family="config-set")
        results.append(res)
        if res.rc == 2:
            assert "--set" in res.err or "must be" in res.err, res.err
    assert_clean(results)
    assert any(r.rc == 0 for r in results) and any(r.rc == 2 for r in results)


@pytest.mark.parametrize("key", BAD_SET_KEYS)
def test_set_unknown_keys_are_one_line_errors(key):
    with pytest.raises(ConfigError) as err:
        load_config(sets=[f"{key}=1"])
    msg = str(err.value)
    assert msg.startswith("--set ") and "\n" not in msg


def test_set_values_are_typed_by_the_schema():
    """Every key set to its own default as written on a command line loads the defaults back;
    a value of the wrong type is refused naming the key."""
    defaults = load_config()
    rng = random.Random(3)
    for section, key in KEYS:
        node = defaults.data
        for part in f"{section}.{key}".split("."):
            node = node[part]
        text = node if isinstance(node, str) else toml_value(node)
        assert load_config(sets=[f"{section}.{key}={text}"]).data == defaults.data, key
        if isinstance(node, str):
            continue  # a string key takes any text (its rule then checks the choice)
        wrong = "1" if isinstance(node, bool) else "abc" if isinstance(node, list) else rng.choice(
            ["abc", "[1]", "true"])
        with pytest.raises(ConfigError, match=f"--set {section}.{key}: '{section}.{key}'"):
            load_config(sets=[f"{section}.{key}={wrong}"])


def test_resolved_config_written_as_toml_loads_back(tmp_path):
    """What bench's children and a re-run read (``Config.to_toml``): random valid configs, and a
    plug-in's parameters holding any text, load back to the same values."""
    rng = random.Random(2041)
    path, again = tmp_path / "user.toml", tmp_path / "again.toml"
    loaded = 0
    for i in range(n_cases(150)):
        path.write_text(_random_toml(rng))
        try:
            cfg = load_config(path)
        except ConfigError:
            continue
        if i % 2:
            text = "".join(chr(rng.choice([rng.randrange(0, 128), rng.randrange(0xe000, 0x10ffff)]))
                           for _ in range(rng.randrange(0, 12)))
            cfg = cfg.with_overrides({"downwash": {
                "field": "aerodock.downwash.template:UniformColumnField",
                "params": {"label": text, text or "k": [1, 2.5], "nested": {"t": text}}}})
        again.write_text(cfg.to_toml(), encoding="utf-8")
        assert load_config(again).data == cfg.data
        loaded += 1
        count("config-toml")
    assert loaded > 0
