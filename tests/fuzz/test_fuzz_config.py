"""Config TOML fuzzing: every file loads into a valid, finite config or gives a ConfigError."""

from __future__ import annotations

import math
import random
from importlib import resources

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
    for _ in range(n_cases(1200)):
        path.write_text(_random_toml(rng))
        loaded += _check(path) is not None
        count("config-values")
    assert 0 < loaded < n_cases(1200)


def test_damaged_defaults_file(tmp_path):
    rng = random.Random(5)
    path = tmp_path / "damaged.toml"
    for _ in range(n_cases(500)):
        path.write_bytes(mutate_bytes(DEFAULTS_TEXT.encode(), rng))
        _check(path)
        count("config-bytes")


def test_random_configs_through_the_cli(tmp_path):
    """``field probe`` (and a few ``dock`` runs) under random configs: 0 or 2, strict JSON."""
    rng = random.Random(99)
    results = []
    for i in range(n_cases(120)):
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
