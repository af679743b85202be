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
import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from aerodock.fileio import read_toml

DEFAULTS_NAME = "defaults.toml"

# Every numeric key's range, (low, high), both inclusive. Values must be finite; the bounds keep
# them physical (a 1e-300 m rotor has no disk area: NaN forces), keep the arithmetic finite, and
# keep a run's memory and time bounded (durations <= 10 min of flight, rates <= 20 kHz). Keys of
# the default downwash field are listed under "downwash.params.".
_RANGES: dict[str, tuple[float, float]] = {
    "vehicle.mass_kg": (0.001, 100),
    "vehicle.diagonal_m": (0.01, 10),
    "vehicle.rotor_radius_m": (0.001, 5),
    "vehicle.n_rotors": (1, 16),
    "vehicle.drag_coeff_kgps": (0, 100),
    "vehicle.tau_attitude_s": (1e-06, 10),
    "vehicle.tau_thrust_s": (1e-06, 10),
    "vehicle.tilt_max_deg": (1, 89),
    # Hover needs 1 g; 10 % more is the least that leaves any authority to manoeuvre.
    "vehicle.thrust_max_g": (1.1, 10),
    "vehicle.thrust_gain_sd": (0, 0.5),
    "vehicle.accel_noise_mps2": (0, 100),
    "vehicle.inertia_kgm2": (1e-07, 1000),
    "vehicle.rotor_thrust_coeff": (1e-10, 0.01),
    "vehicle.rotor_torque_ratio_m": (0, 1),
    "vehicle.motor_tau_s": (0.0001, 10),
    "vehicle.rotor_drag_coeff": (0, 1),
    "vehicle.rotor_drag_z_coeff": (0, 1),
    "vehicle.parasitic_drag_coeff": (0, 100),
    "autopilot.attitude_p": (0, 1000),
    "autopilot.rate_p": (0, 10000),
    "autopilot.rate_i": (0, 100000),
    "autopilot.rate_integral_max_radps2": (0, 10000),
    "autopilot.rate_max_dps": (1, 3600),
    "imu.gyro_noise_radps": (0, 10),
    "imu.accel_vibration_mps2": (0, 1000),
    "imu.accel_bias_sd_mps2": (0, 100),
    "imu.attitude_noise_rad": (0, 1),
    "mocap.pos_noise_m": (0, 10),
    "mocap.vel_noise_mps": (0, 100),
    "mocap.latency_s": (0, 10),
    "sim.physics_rate_hz": (1, 20000),
    "sim.control_rate_hz": (1, 20000),
    "sim.gravity_mps2": (0.1, 100),
    "sim.air_density_kgpm3": (0.01, 100),
    "downwash.params.core_length_m": (0.001, 100),
    "downwash.params.half_width0_m": (0.001, 100),
    "downwash.params.spread_rate": (0, 10),
    "downwash.params.ingest_coeff": (0, 10),
    "downwash.params.planar_ratio": (0, 10),
    "downwash.params.turb_vertical": (0, 10),
    "downwash.params.turb_lateral": (0, 10),
    "downwash.params.turb_corr_time_s": (0.001, 100),
    "downwash.params.bar_drag_coeff": (0, 100),
    "platform.cable_length_m": (0.01, 100),
    "platform.cable_spacing_m": (0.01, 10),
    "platform.bar_length_m": (0.01, 10),
    "platform.bar_diameter_m": (0.0005, 1),
    "platform.bar_mass_kg": (0.001, 100),
    "platform.anchor_below_leader_m": (0, 10),
    "platform.yaw_damping": (0, 1000),
    "platform.swing_damping": (0, 1000),
    "gripper.aperture_m": (0.001, 10),
    "gripper.gate_height_m": (0.001, 10),
    "gripper.mount_height_m": (0, 10),
    "gripper.sensor_rate_hz": (1, 20000),
    "gripper.sensor_noise_n": (0, 1000),
    "gripper.sensor_bias_sd_n": (0, 1000),
    "gripper.calibration_samples": (1, 100000),
    "gripper.contact_threshold_n": (0.0001, 10000),
    "gripper.contact_stiffness_npm": (1, 1e7),
    "gripper.contact_damping_nspm": (0, 1e5),
    "gripper.latency_s": (0, 10),
    "gripper.close_time_s": (0.001, 10),
    "control.q_diag": (0, 1e6),
    "control.terminal_q_diag": (0, 1e6),
    "control.r_diag": (1e-06, 1e6),
    "control.terminal_r_diag": (1e-06, 1e6),
    "control.observer_bias_tau_s": (0.01, 1e4),
    "control.observer_pos_noise_m": (0, 10),
    "control.observer_vel_noise_mps": (0, 100),
    "control.accel_observer_tau_s": (0.001, 100),
    "control.yaw_rate_max_radps": (0.01, 100),
    "planner.horizon_hover_s": (0.1, 600),
    "planner.horizon_moving_s": (0.1, 600),
    "planner.hold_s": (0, 600),
    "planner.replan_threshold_m": (0.0001, 100),
    "planner.rise_m": (0, 10),
    "planner.rise_s": (0.05, 60),
    "mission.offset_m": (0.01, 100),
    "mission.start_radius_m": (0.01, 100),
    "mission.start_below_m": (0, 100),
    "mission.start_jitter_m": (0, 10),
    "mission.dock_window_s": (0.01, 600),
    "mission.leader_lost_s": (0.01, 600),
    "mission.abort_tracking_m": (0.001, 100),
    "mission.clearance_m": (0, 10),
    "mission.post_dock_thrust_fraction": (0, 1),
    "mission.leader_speed_mps": (0, 100),
    "mission.leader_altitude_m": (0.1, 1e4),
    "mission.insertion_m": (0, 1),
    "mission.terminal_s": (0, 600),
    "mission.active_trigger_delay_s": (0, 600),
    "mission.post_dock_s": (0, 600),
    "mission.backoff_s": (0.1, 600),
    "mission.backoff_distance_m": (0, 100),
    "mission.settle_s": (0, 600),
    "mission.leader_ramp_s": (0, 600),
    "mission.status_delay_s": (0, 10),
    "curriculum.stage0_depth_m": (0.05, 100),
    "curriculum.stage_step_m": (0.01, 100),
    "curriculum.min_depth_m": (0.05, 100),
    "curriculum.deep_depths_m": (0.05, 100),
    "curriculum.flights_per_stage": (1, 1000),
    "curriculum.deep_flights_per_stage": (1, 1000),
    "curriculum.free_air_m": (0.01, 100),
    "curriculum.leader_drift_max_mps": (0, 100),
    "curriculum.drift_fraction": (0, 1),
}
# A numeric key without an entry above (e.g. one added to defaults.toml later): non-negative, as
# every key used to be, and bounded so that products and squares stay finite.
_DEFAULT_RANGE = (0.0, 1e6)
_CHOICES = {"gripper.trigger": {"passive", "active", "both"},
            "vehicle.model": {"rigid-body", "point-mass"},
            "control.rejection": {"bias-observer", "accelerometer"},
            "control.accel_observer_axes": {"down", "all"},
            "curriculum.model": {"so2", "so2-ext", "so2-wrench", "mlp"},
            "curriculum.label_basis": {"command", "thrust"}}
_LENGTHS = {
    "control.q_diag": 7, "control.r_diag": 4,
    "control.terminal_q_diag": 7, "control.terminal_r_diag": 4, "curriculum.stage0_depth_m": 2,
    "vehicle.inertia_kgm2": 3, "autopilot.attitude_p": 3, "autopilot.rate_p": 3,
    "autopilot.rate_i": 3, "autopilot.rate_max_dps": 3,
}
_LISTS = {"curriculum.deep_depths_m": 10}  # lists of any length up to this
_DEFAULT_FIELD = "aerodock.downwash.jet:RoundJetField"
_FIELD_PATH = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*")


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


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _merge(target: dict, user: Mapping, reference: dict, source: str, prefix: str) -> None:
    if not isinstance(user, Mapping):
        raise ConfigError(f"{source}: '{prefix.rstrip('.') or 'the file'}' must be a table")
    for key, value in user.items():
        dotted = f"{prefix}{key}"
        if key not in reference:
            raise ConfigError(f"{source}: unknown key '{dotted}'")
        if dotted == "downwash":
            _merge_downwash(target[key], value, reference[key], source)
            continue
        default = reference[key]
        if isinstance(default, dict):
            if not isinstance(value, Mapping):
                raise ConfigError(f"{source}: '{dotted}' must be a table")
            _merge(target[key], value, default, source, f"{dotted}.")
            continue
        numeric = _is_number(default)
        if numeric and not _is_number(value):
            raise ConfigError(f"{source}: '{dotted}' must be a number, got {value!r}")
        if not numeric and type(value) is not type(default):
            raise ConfigError(f"{source}: '{dotted}' must be {_type_name(default)}, got {value!r}")
        if isinstance(default, int) and numeric:
            if not (isinstance(value, int) or (math.isfinite(value) and value.is_integer())):
                raise ConfigError(f"{source}: '{dotted}' must be an integer, got {value!r}")
            value = int(value)
        target[key] = float(value) if isinstance(default, float) else value


def _merge_downwash(target: dict, user: Any, reference: dict, source: str) -> None:
    """``[downwash]``: a field and its own parameters; one field's never reach another."""
    if not isinstance(user, Mapping):
        raise ConfigError(f"{source}: 'downwash' must be a table")
    for key in user:
        if key not in reference:
            raise ConfigError(f"{source}: unknown key 'downwash.{key}'")
    field_path = user.get("field", target["field"])
    if not isinstance(field_path, str):
        raise ConfigError(f"{source}: 'downwash.field' must be a string, got {field_path!r}")
    params = user.get("params")
    if params is not None and not isinstance(params, Mapping):
        raise ConfigError(f"{source}: 'downwash.params' must be a table, got {params!r}")
    changed = field_path != target["field"]
    if field_path == _DEFAULT_FIELD:
        base = copy.deepcopy(reference["params"]) if changed else target["params"]
        if params is not None:
            _merge(base, params, reference["params"], source, "downwash.params.")
    else:
        # Plug-in parameters are the factory's own keyword arguments (checked when it is built).
        base = dict(params) if params is not None else ({} if changed else target["params"])
    target["field"] = field_path
    target["params"] = base


def _range_text(low: float, high: float) -> str:
    return f">= {low:g} and <= {high:g}"


def _check_number(value: Any, dotted: str, source: str,
                  rule: tuple[float, float] | None = None) -> None:
    if not math.isfinite(value):
        raise ConfigError(f"{source}: '{dotted}' must be a finite number, got {value!r}")
    low, high = rule or _RANGES.get(dotted, _DEFAULT_RANGE)
    if not low <= value <= high:
        raise ConfigError(f"{source}: '{dotted}' must be {_range_text(low, high)}, got {value!r}")


def _check_plugin_params(params: Mapping[str, Any], source: str, prefix: str) -> None:
    for key, value in params.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, Mapping):
            _check_plugin_params(value, source, f"{dotted}.")
        elif isinstance(value, list):
            for item in value:
                if isinstance(item, float) and not math.isfinite(item):
                    raise ConfigError(f"{source}: '{dotted}' must hold finite numbers")
        elif isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{source}: '{dotted}' must be a finite number, got {value!r}")


def _validate(data: dict[str, Any], source: str) -> None:
    for section, table in data.items():
        for key, value in table.items():
            dotted = f"{section}.{key}"
            if dotted == "downwash.params":
                if data["downwash"]["field"] == _DEFAULT_FIELD:
                    for pkey, pvalue in value.items():
                        _check_number(pvalue, f"{dotted}.{pkey}", source)
                else:
                    _check_plugin_params(value, source, f"{dotted}.")
                continue
            if dotted in _CHOICES and value not in _CHOICES[dotted]:
                choices = "|".join(sorted(_CHOICES[dotted]))
                raise ConfigError(f"{source}: '{dotted}' must be one of {choices}, got {value!r}")
            if dotted in _LENGTHS:
                low, high = _RANGES[dotted]
                if len(value) != _LENGTHS[dotted] or not all(_is_number(v) for v in value):
                    raise ConfigError(f"{source}: '{dotted}' must be {_LENGTHS[dotted]} numbers "
                                      f"{_range_text(low, high)}, got {value!r}")
                for i, item in enumerate(value):
                    _check_number(item, f"{dotted}[{i}]", source, (low, high))
            elif dotted in _LISTS:
                low, high = _RANGES[dotted]
                if (not isinstance(value, list) or len(value) > _LISTS[dotted]
                        or not all(_is_number(v) for v in value)):
                    raise ConfigError(f"{source}: '{dotted}' must be a list of up to "
                                      f"{_LISTS[dotted]} numbers {_range_text(low, high)}, "
                                      f"got {value!r}")
                for i, item in enumerate(value):
                    _check_number(item, f"{dotted}[{i}]", source, (low, high))
            elif _is_number(value):
                _check_number(value, dotted, source)
    _check_consistency(data, source)
    # Fail now, not mid-run, on an unknown or broken plug-in.
    resolve_factory(data["downwash"]["field"], source)


def _check_consistency(data: dict[str, Any], source: str) -> None:
    """Rules between keys: rates, depth bands, and set-ups no vehicle can fly."""
    sim, platform = data["sim"], data["platform"]
    gripper, mission = data["gripper"], data["mission"]
    if sim["physics_rate_hz"] < sim["control_rate_hz"]:
        raise ConfigError(f"{source}: 'sim.physics_rate_hz' must be >= 'sim.control_rate_hz'")
    ratio = sim["physics_rate_hz"] / sim["control_rate_hz"]
    if abs(ratio - round(ratio)) > 1e-9:
        raise ConfigError(
            f"{source}: 'sim.physics_rate_hz' must be a multiple of 'sim.control_rate_hz'"
        )
    lo, hi = data["curriculum"]["stage0_depth_m"]
    if not lo < hi:
        raise ConfigError(f"{source}: 'curriculum.stage0_depth_m' must be [low, high] with "
                          f"low < high, got {[lo, hi]}")
    if data["curriculum"]["min_depth_m"] > lo:
        raise ConfigError(f"{source}: 'curriculum.min_depth_m' must be <= the low end of "
                          f"'curriculum.stage0_depth_m' ({lo:g} m)")
    planner = data["planner"]
    horizon = min(planner["horizon_hover_s"], planner["horizon_moving_s"])
    if planner["rise_m"] > 0 and planner["rise_s"] > horizon - 0.5:
        raise ConfigError(f"{source}: 'planner.rise_s' ({planner['rise_s']:g} s) must leave at "
                          f"least 0.5 s of the approach horizon ({horizon:g} s) to align")
    if gripper["aperture_m"] <= platform["bar_diameter_m"]:
        raise ConfigError(
            f"{source}: 'gripper.aperture_m' ({gripper['aperture_m']:g} m) must be wider than "
            f"'platform.bar_diameter_m' ({platform['bar_diameter_m']:g} m): the bar cannot enter"
        )
    altitude = mission["leader_altitude_m"]
    dock_below_m = (platform["anchor_below_leader_m"] + platform["cable_length_m"]
                    + platform["bar_diameter_m"] / 2 - mission["insertion_m"]
                    + gripper["mount_height_m"])
    if dock_below_m >= altitude:
        raise ConfigError(
            f"{source}: the docking point is {dock_below_m:g} m below the leader, at or below "
            f"the ground ('mission.leader_altitude_m' = {altitude:g} m; "
            "'platform.cable_length_m' and the offsets are too long)"
        )
    start_below_m = dock_below_m + mission["start_below_m"] + 3 * mission["start_jitter_m"]
    if start_below_m >= altitude:
        raise ConfigError(
            f"{source}: the follower would start {start_below_m:g} m below the leader, at or "
            f"below the ground ('mission.leader_altitude_m' = {altitude:g} m; lower "
            "'mission.start_below_m' or raise the leader)"
        )
    if hi >= altitude:
        raise ConfigError(
            f"{source}: 'curriculum.stage0_depth_m' reaches {hi:g} m below the leader, at or "
            f"below the ground ('mission.leader_altitude_m' = {altitude:g} m)"
        )


def resolve_factory(path: str, source: str = "config") -> Any:
    """Import ``"package.module:attr"`` and return the attribute (a field factory).

    Raises:
        ConfigError: a malformed path, or a module that cannot be imported (whatever it raises,
            including ``SystemExit``), or a missing attribute.
    """
    if not isinstance(path, str) or not _FIELD_PATH.fullmatch(path):
        raise ConfigError(
            f"{source}: 'downwash.field' must look like 'package.module:factory', got {path!r}"
        )
    module_name, _, attr = path.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise ConfigError(
            f"{source}: 'downwash.field' plug-in module {module_name!r} cannot be imported ({err})"
        ) from None
    except (Exception, SystemExit) as err:  # a plug-in's own code failed while importing
        raise ConfigError(
            f"{source}: 'downwash.field' plug-in module {module_name!r} failed on import "
            f"({type(err).__name__}: {err})"
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
        user = read_toml(path, "config file", ConfigError)
        _merge(data, user, _defaults(), source, prefix="")
    _validate(data, source)
    return Config(data, source)
