"""Configuration: typed defaults from ``defaults.toml``, overridden by a user TOML file.

Every constant of the simulated world, the controllers and the mission lives in
``aerodock/defaults.toml``. A user file overrides any subset of keys; a value must have the type of
its default and satisfy the key's range rule. Errors name the key and the file in one line::

    cfg = load_config("my.toml")
    cfg.vehicle.mass_kg          # 0.7
    cfg2 = cfg.with_overrides({"platform": {"cable_length_m": 0.64}})
"""

from __future__ import annotations

import copy
import importlib
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

DEFAULTS_NAME = "defaults.toml"

# Keys that must be strictly positive; every other numeric key must be >= 0 unless signed.
_STRICTLY_POSITIVE_SUFFIXES = ("_kg", "_hz")
_STRICTLY_POSITIVE = {
    "vehicle.diagonal_m", "vehicle.rotor_radius_m", "vehicle.n_rotors", "vehicle.tau_attitude_s",
    "vehicle.tau_thrust_s", "vehicle.tilt_max_deg", "vehicle.thrust_max_g",
    "vehicle.rotor_thrust_coeff", "vehicle.motor_tau_s",
    "sim.gravity_mps2", "sim.air_density_kgpm3",
    "platform.cable_length_m", "platform.bar_length_m", "platform.bar_diameter_m",
    "platform.cable_spacing_m",
    "gripper.aperture_m", "gripper.gate_height_m", "gripper.close_time_s",
    "gripper.calibration_samples", "gripper.contact_threshold_n",
    "gripper.contact_stiffness_npm",
    "control.observer_bias_tau_s", "control.yaw_rate_max_radps",
    "planner.horizon_hover_s", "planner.horizon_moving_s", "planner.replan_threshold_m",
    "mission.dock_window_s", "mission.leader_lost_s", "mission.abort_tracking_m",
    "mission.start_radius_m", "mission.leader_altitude_m",
    "curriculum.stage_step_m", "curriculum.min_depth_m", "curriculum.flights_per_stage",
    "curriculum.free_air_m",
}
_SIGNED: set[str] = set()
_CHOICES = {"gripper.trigger": {"passive", "active", "both"},
            "vehicle.model": {"rigid-body", "point-mass"},
            "curriculum.model": {"so2", "so2-ext", "mlp"}}
_LENGTHS = {
    "control.q_diag": 7, "control.r_diag": 4,
    "control.terminal_q_diag": 7, "control.terminal_r_diag": 4, "curriculum.stage0_depth_m": 2,
    "vehicle.inertia_kgm2": 3, "autopilot.attitude_p": 3, "autopilot.rate_p": 3,
    "autopilot.rate_i": 3, "autopilot.rate_max_dps": 3,
}
_DEFAULT_FIELD = "aerodock.downwash.jet:RoundJetField"


class ConfigError(ValueError):
    """A configuration value is invalid; the message names the key and the file."""


class Section(Mapping[str, Any]):
    """Read-only attribute view of one TOML table."""

    def __init__(self, name: str, values: dict[str, Any]):
        self._name = name
        self._values = values

    def __getattr__(self, key: str) -> Any:
        try:
            value = self._values[key]
        except KeyError:
            raise AttributeError(f"config section [{self._name}] has no key {key!r}") from None
        return Section(f"{self._name}.{key}", value) if isinstance(value, dict) else value

    def __getitem__(self, key: str) -> Any:
        return self._values[key]

    def __iter__(self):
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"Section({self._name}, {self._values!r})"


@dataclass(frozen=True)
class Config:
    """Validated configuration; sections are attributes (``cfg.vehicle.mass_kg``)."""

    data: dict[str, Any]
    source: str = "defaults"

    def __getattr__(self, key: str) -> Section:
        data = object.__getattribute__(self, "data")
        if key in data:
            return Section(key, data[key])
        raise AttributeError(f"config has no section [{key}]")

    def to_dict(self) -> dict[str, Any]:
        """A deep copy of the values, e.g. for recording in results.json."""
        return copy.deepcopy(self.data)

    def with_overrides(self, overrides: Mapping[str, Any], source: str = "overrides") -> Config:
        """A new validated config with ``overrides`` (nested tables) applied."""
        merged = copy.deepcopy(self.data)
        _merge(merged, overrides, _defaults(), source, prefix="")
        _validate(merged, source)
        return Config(merged, self.source)


def _defaults() -> dict[str, Any]:
    text = resources.files("aerodock").joinpath(DEFAULTS_NAME).read_text()
    return tomllib.loads(text)


def _type_name(value: Any) -> str:
    return {bool: "a boolean", int: "a number", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(value), type(value).__name__)


def _merge(target: dict, user: Mapping, reference: dict, source: str, prefix: str) -> None:
    for key, value in user.items():
        dotted = f"{prefix}{key}"
        if prefix == "downwash." and key == "params":
            # Plug-in parameters are the factory's own keyword arguments: checked on load.
            if user.get("field", target.get("field")) != _DEFAULT_FIELD:
                target["params"] = dict(value)
            else:
                _merge(target["params"], value, reference["params"], source, f"{dotted}.")
            continue
        if key not in reference:
            raise ConfigError(f"{source}: unknown key '{dotted}'")
        default = reference[key]
        if isinstance(default, dict):
            if not isinstance(value, Mapping):
                raise ConfigError(f"{source}: '{dotted}' must be a table")
            _merge(target[key], value, default, source, f"{dotted}.")
            continue
        numeric = isinstance(default, int | float) and not isinstance(default, bool)
        if numeric and (isinstance(value, bool) or not isinstance(value, int | float)):
            raise ConfigError(f"{source}: '{dotted}' must be a number, got {value!r}")
        if not numeric and type(value) is not type(default):
            raise ConfigError(f"{source}: '{dotted}' must be {_type_name(default)}, got {value!r}")
        target[key] = float(value) if isinstance(default, float) else value


def _validate(data: dict[str, Any], source: str) -> None:
    for section, table in data.items():
        for key, value in table.items():
            dotted = f"{section}.{key}"
            if dotted in _CHOICES and value not in _CHOICES[dotted]:
                choices = "|".join(sorted(_CHOICES[dotted]))
                raise ConfigError(f"{source}: '{dotted}' must be one of {choices}, got {value!r}")
            if dotted in _LENGTHS:
                if len(value) != _LENGTHS[dotted] or not all(
                    isinstance(v, int | float) and v >= 0 for v in value
                ):
                    raise ConfigError(
                        f"{source}: '{dotted}' must be {_LENGTHS[dotted]} non-negative numbers"
                    )
                if "r_diag" in key and min(value) <= 0:
                    raise ConfigError(f"{source}: '{dotted}' must be strictly positive")
            if isinstance(value, bool) or not isinstance(value, int | float):
                continue
            if dotted in _SIGNED:
                continue
            strict = dotted in _STRICTLY_POSITIVE or key.endswith(_STRICTLY_POSITIVE_SUFFIXES)
            if strict and not value > 0:
                raise ConfigError(f"{source}: '{dotted}' must be > 0, got {value!r}")
            if not strict and value < 0 and section != "downwash":
                raise ConfigError(f"{source}: '{dotted}' must be >= 0, got {value!r}")
    sim = data["sim"]
    if sim["physics_rate_hz"] < sim["control_rate_hz"]:
        raise ConfigError(f"{source}: 'sim.physics_rate_hz' must be >= 'sim.control_rate_hz'")
    ratio = sim["physics_rate_hz"] / sim["control_rate_hz"]
    if abs(ratio - round(ratio)) > 1e-9:
        raise ConfigError(
            f"{source}: 'sim.physics_rate_hz' must be a multiple of 'sim.control_rate_hz'"
        )
    # Fail now, not mid-run, on an unknown or broken plug-in.
    resolve_factory(data["downwash"]["field"], source)


def resolve_factory(path: str, source: str = "config") -> Any:
    """Import ``"package.module:attr"`` and return the attribute (a field factory)."""
    module_name, _, attr = path.partition(":")
    if not module_name or not attr:
        raise ConfigError(
            f"{source}: 'downwash.field' must look like 'package.module:factory', got {path!r}"
        )
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise ConfigError(
            f"{source}: 'downwash.field' plug-in module {module_name!r} cannot be imported ({err})"
        ) from None
    try:
        return getattr(module, attr)
    except AttributeError:
        raise ConfigError(
            f"{source}: 'downwash.field' plug-in {module_name!r} has no attribute {attr!r}"
        ) from None


def load_config(path: str | Path | None = None) -> Config:
    """Load the defaults and apply the user TOML file at ``path`` (if any).

    Raises:
        ConfigError: unreadable file, TOML syntax error, unknown key, wrong type or range.
    """
    data = _defaults()
    source = "defaults"
    if path is not None:
        source = str(path)
        try:
            user = tomllib.loads(Path(path).read_text())
        except FileNotFoundError:
            raise ConfigError(f"{source}: config file not found") from None
        except (OSError, UnicodeDecodeError) as err:
            raise ConfigError(f"{source}: cannot read config file ({err})") from None
        except tomllib.TOMLDecodeError as err:
            raise ConfigError(f"{source}: invalid TOML ({err})") from None
        _merge(data, user, _defaults(), source, prefix="")
    _validate(data, source)
    return Config(data, source)
