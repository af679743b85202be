"""Loading and checking a configuration: the defaults, a user file's overrides, the rules.

Every constant of the simulated world, the controllers and the mission lives in
``aerodock/config/defaults.toml``. A user file overrides any subset of keys; a value must have the
type of its default and satisfy the key's rule. Errors name the key and the file in one line::

    cfg = load_config("my.toml")
    cfg.vehicle.mass_kg          # 0.7
    cfg2 = cfg.with_overrides({"platform": {"cable_length_m": 0.64}})
    cfg3 = load_config("my.toml", sets=["platform.cable_length_m=0.64"])  # --set

A config that names a plug-in field names code: it is imported only from a trusted source
(:mod:`aerodock.config.plugins`; ``trusted`` below, ``--trust-plugin`` on the command line).
"""

from __future__ import annotations

import copy
import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any

from aerodock.config.errors import ConfigError
from aerodock.config.plugins import resolve_factory
from aerodock.config.schema import (
    LEADER_FIXED_KEYS,
    RULES,
    SECTIONS,
    AutopilotSection,
    ControlSection,
    CurriculumSection,
    DownwashSection,
    GripperSection,
    ImuSection,
    MissionSection,
    MocapSection,
    PlannerSection,
    PlatformSection,
    SimSection,
    VehicleSection,
)
from aerodock.config.timing import Timing
from aerodock.config.toml_text import dumps_toml
from aerodock.fileio import read_toml

DEFAULTS_NAME = "defaults.toml"
_DEFAULT_FIELD = "aerodock.downwash.jet:RoundJetField"

__all__ = ["Config", "ConfigError", "load_config", "parse_set", "resolve_factory"]


@dataclass(frozen=True)
class Config:
    """Validated configuration: one typed, read-only section per TOML table
    (``cfg.vehicle.mass_kg``; see :mod:`aerodock.config.schema`).

    ``trusted`` holds the plug-in modules the user trusted when it was loaded
    (:func:`load_config`); :meth:`with_overrides` passes them on. Its own ``downwash.field`` was
    checked when it was read from text, so building it needs no trust again (a ``Config`` made
    in Python from a dict is the program's own choice).
    """

    data: dict[str, Any]
    source: str = "defaults"
    trusted: tuple[str, ...] = ()

    def _section(self, name: str) -> Any:
        return SECTIONS[name](**self.data[name])

    @cached_property
    def vehicle(self) -> VehicleSection:
        """``[vehicle]``."""
        return self._section("vehicle")

    @cached_property
    def leader(self) -> VehicleSection:
        """The leader's vehicle: ``[vehicle]`` with the ``[leader]`` table's values."""
        return VehicleSection(**{**self.data["vehicle"], **self.data["leader"]})

    @property
    def leader_differs(self) -> bool:
        """The ``[leader]`` or ``[leader_autopilot]`` table sets a value other than the
        follower's."""
        vehicle, autopilot = self.data["vehicle"], self.data["autopilot"]
        return (any(vehicle[k] != v for k, v in self.data["leader"].items())
                or any(autopilot[k] != v for k, v in self.data["leader_autopilot"].items()))

    @cached_property
    def leader_autopilot(self) -> AutopilotSection:
        """The leader's autopilot: ``[autopilot]`` with the ``[leader_autopilot]`` table's
        values (a flight stack's gains are a vehicle type's)."""
        return AutopilotSection(**{**self.data["autopilot"], **self.data["leader_autopilot"]})

    @cached_property
    def autopilot(self) -> AutopilotSection:
        """``[autopilot]``."""
        return self._section("autopilot")

    @cached_property
    def imu(self) -> ImuSection:
        """``[imu]``."""
        return self._section("imu")

    @cached_property
    def mocap(self) -> MocapSection:
        """``[mocap]``."""
        return self._section("mocap")

    @cached_property
    def sim(self) -> SimSection:
        """``[sim]``."""
        return self._section("sim")

    @cached_property
    def timing(self) -> Timing:
        """The simulation's clocks, bound once from ``[sim]`` and ``[control]``."""
        return Timing.from_sections(self.sim, self.control)

    @cached_property
    def downwash(self) -> DownwashSection:
        """``[downwash]``."""
        return self._section("downwash")

    @cached_property
    def platform(self) -> PlatformSection:
        """``[platform]``."""
        return self._section("platform")

    @cached_property
    def gripper(self) -> GripperSection:
        """``[gripper]``."""
        return self._section("gripper")

    @cached_property
    def control(self) -> ControlSection:
        """``[control]``."""
        return self._section("control")

    @cached_property
    def planner(self) -> PlannerSection:
        """``[planner]``."""
        return self._section("planner")

    @cached_property
    def mission(self) -> MissionSection:
        """``[mission]``."""
        return self._section("mission")

    @cached_property
    def curriculum(self) -> CurriculumSection:
        """``[curriculum]``."""
        return self._section("curriculum")

    def to_dict(self) -> dict[str, Any]:
        """A deep copy of the values, e.g. for recording in results.json."""
        return copy.deepcopy(self.data)

    def to_toml(self) -> str:
        """The values as TOML text that :func:`load_config` reads back to the same config."""
        return dumps_toml(self.data)

    def with_overrides(self, overrides: Mapping[str, Any], source: str = "overrides") -> Config:
        """A new validated config with ``overrides`` (nested tables) applied."""
        merged = copy.deepcopy(self.data)
        _merge(merged, overrides, _defaults(), source, prefix="")
        # A field other than this config's own needs the same trust as one read from a file.
        _validate(merged, source, (*self.trusted, self.data["downwash"]["field"]))
        return Config(merged, self.source, self.trusted)


def _defaults() -> dict[str, Any]:
    text = resources.files("aerodock.config").joinpath(DEFAULTS_NAME).read_text()
    return tomllib.loads(text)


def _type_name(value: Any) -> str:
    return {bool: "a boolean", int: "a number", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(value), type(value).__name__)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


# Keys that earlier configs carried and nothing read: a file that sets one is told where the
# parameter lives instead of having its value ignored.
RETIRED_KEYS = {
    "mission.offset_m": "the cable length d_p is 'platform.cable_length_m' (or dock --offset)",
    "mission.leader_speed_mps": "the leader's speed is dock --leader-speed (or a sweep axis)",
}


def _merge(target: dict, user: Mapping, reference: dict, source: str, prefix: str) -> None:
    if not isinstance(user, Mapping):
        raise ConfigError(f"{source}: '{prefix.rstrip('.') or 'the file'}' must be a table")
    for key, value in user.items():
        dotted = f"{prefix}{key}"
        if dotted in RETIRED_KEYS:
            raise ConfigError(f"{source}: '{dotted}' is no longer a key (nothing read it): "
                              f"{RETIRED_KEYS[dotted]}")
        if key not in reference:
            raise ConfigError(f"{source}: unknown key '{dotted}'")
        if dotted == "downwash":
            _merge_downwash(target[key], value, reference[key], source)
            continue
        if dotted == "leader":
            _merge_leader(target[key], value, reference["vehicle"], source)
            continue
        if dotted == "leader_autopilot":
            _merge_leader(target[key], value, reference["autopilot"], source, key)
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
        if isinstance(default, int) and numeric and not isinstance(value, int):
            # An integer key takes an integer: 4.0 is a float written where a count belongs.
            raise ConfigError(f"{source}: '{dotted}' must be an integer, got {value!r}")
        target[key] = float(value) if isinstance(default, float) else value


def _merge_leader(target: dict, user: Any, vehicle: dict, source: str,
                  table: str = "leader") -> None:
    """``[leader]``: ``[vehicle]`` keys where the leader differs (typed as ``[vehicle]``'s);
    ``[leader_autopilot]`` (``table``): ``[autopilot]`` keys, the same way."""
    section = "vehicle" if table == "leader" else "autopilot"
    if not isinstance(user, Mapping):
        raise ConfigError(f"{source}: '{table}' must be a table")
    for key in user:
        if table == "leader" and key in LEADER_FIXED_KEYS:
            raise ConfigError(f"{source}: 'leader.{key}' cannot differ from 'vehicle.{key}'")
    scratch = {key: vehicle[key] for key in user if key in vehicle}
    try:
        _merge(scratch, user, vehicle, source, prefix=f"{section}.")
    except ConfigError as err:
        raise ConfigError(str(err).replace(f"'{section}.", f"'{table}.")) from None
    target.update(scratch)


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
        # Plug-in parameters are the factory's own keyword arguments (checked when it is built);
        # a new field starts from none, the same field keeps those not given again.
        base = {} if changed else dict(target["params"])
        base.update(params or {})
    target["field"] = field_path
    target["params"] = base


def _range_text(low: float, high: float) -> str:
    return f">= {low:g} and <= {high:g}"


def _check_number(value: Any, dotted: str, source: str,
                  rule: tuple[float, float] | None = None) -> None:
    if not math.isfinite(value):
        raise ConfigError(f"{source}: '{dotted}' must be a finite number, got {value!r}")
    if rule is None:
        found = RULES[dotted]
        rule = (found.low, found.high)
    low, high = rule
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


def _validate(data: dict[str, Any], source: str, trusted: Iterable[str] = ()) -> None:
    for section, values in data.items():
        for key, value in values.items():
            dotted = f"{section}.{key}"
            if dotted == "downwash.params":
                if data["downwash"]["field"] == _DEFAULT_FIELD:
                    for pkey, pvalue in value.items():
                        _check_number(pvalue, f"{dotted}.{pkey}", source)
                else:
                    _check_plugin_params(value, source, f"{dotted}.")
                continue
            if section in ("leader", "leader_autopilot"):
                _validate_leader_key(key, value, source, section)
                continue
            rule = RULES[dotted]
            bounds = (rule.low, rule.high)
            if rule.kind == "choice" and value not in rule.choices:
                choices = "|".join(sorted(rule.choices))
                raise ConfigError(f"{source}: '{dotted}' must be one of {choices}, got {value!r}")
            if rule.kind == "numbers":
                if len(value) != rule.length or not all(_is_number(v) for v in value):
                    raise ConfigError(f"{source}: '{dotted}' must be {rule.length} numbers "
                                      f"{_range_text(*bounds)}, got {value!r}")
                for i, item in enumerate(value):
                    _check_number(item, f"{dotted}[{i}]", source, bounds)
            elif rule.kind == "number_list":
                if (not isinstance(value, list) or len(value) > rule.length
                        or not all(_is_number(v) for v in value)):
                    raise ConfigError(f"{source}: '{dotted}' must be a list of up to "
                                      f"{rule.length} numbers {_range_text(*bounds)}, "
                                      f"got {value!r}")
                for i, item in enumerate(value):
                    _check_number(item, f"{dotted}[{i}]", source, bounds)
            elif _is_number(value):
                _check_number(value, dotted, source, bounds)
    _check_consistency(data, source)
    # Fail now, not mid-run, on an untrusted, unknown or broken plug-in (nothing is called).
    resolve_factory(data["downwash"]["field"], source, trusted)


def _validate_leader_key(key: str, value: Any, source: str, table: str = "leader") -> None:
    """A ``[leader]`` (``[leader_autopilot]``) value against its ``[vehicle]``
    (``[autopilot]``) key's rule, named as the leader's."""
    rule = RULES[f"{'vehicle' if table == 'leader' else 'autopilot'}.{key}"]
    dotted, bounds = f"{table}.{key}", (rule.low, rule.high)
    if rule.kind == "choice" and value not in rule.choices:
        choices = "|".join(sorted(rule.choices))
        raise ConfigError(f"{source}: '{dotted}' must be one of {choices}, got {value!r}")
    if rule.kind == "numbers":
        if len(value) != rule.length or not all(_is_number(v) for v in value):
            raise ConfigError(f"{source}: '{dotted}' must be {rule.length} numbers "
                              f"{_range_text(*bounds)}, got {value!r}")
        for i, item in enumerate(value):
            _check_number(item, f"{dotted}[{i}]", source, bounds)
    elif _is_number(value):
        _check_number(value, dotted, source, bounds)


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
    control = data["control"]
    if control["command_rate_hz"] > sim["control_rate_hz"]:
        raise ConfigError(f"{source}: 'control.command_rate_hz' must be <= 'sim.control_rate_hz'")
    ticks = sim["control_rate_hz"] / control["command_rate_hz"]
    if abs(ticks - round(ticks)) > 1e-9:
        raise ConfigError(f"{source}: 'sim.control_rate_hz' must be a multiple of "
                          "'control.command_rate_hz'")
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


def _lookup_default(parts: list[str]) -> Any:
    node: Any = _defaults()
    for part in parts:
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def parse_set(text: str) -> dict[str, Any]:
    """``"section.key=value"`` (``--set``) as a nested override table.

    The value is read as a TOML value (``0.64``, ``4``, ``true``, ``[0.5, 0.8]``, ``"text"``);
    where that fails, or where the key's default is a string, it is the text as written
    (``vehicle.model=point-mass``). Types and ranges are checked by the loader as a file's are.

    Raises:
        ConfigError: not ``key=value``, or an empty part in the key.
    """
    key, eq, raw = text.partition("=")
    key, raw = key.strip(), raw.strip()
    parts = key.split(".")
    if not eq or len(parts) < 2 or not all(p.strip() for p in parts):
        raise ConfigError(f"--set {text!r}: must be section.key=value "
                          "(e.g. --set platform.cable_length_m=0.64)")
    parts = [p.strip() for p in parts]
    value: Any = raw
    quoted = raw[:1] in ("'", '"')
    if quoted or not isinstance(_lookup_default(parts), str):
        try:
            value = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            if quoted:
                raise ConfigError(f"--set {key}: {raw} is not a valid quoted string") from None
    table: dict[str, Any] = {parts[-1]: value}
    for part in reversed(parts[:-1]):
        table = {part: table}
    return table


def load_config(path: str | Path | None = None, sets: Iterable[str] = (),
                trusted: Iterable[str] = ()) -> Config:
    """Load the defaults, apply the user TOML file at ``path`` (if any), then each
    ``section.key=value`` of ``sets`` (``--set``, :func:`parse_set`), and check the result.

    ``trusted``: module prefixes (or ``module:factory`` paths) whose fields the config may name
    besides aerodock's own, installed packages' declared ones and ``AERODOCK_TRUST_PLUGINS``
    (:mod:`aerodock.config.plugins`); any other is refused before it is imported.

    Raises:
        ConfigError: unreadable file, TOML syntax error, unknown key, wrong type or range, a bad
            ``--set``, an untrusted plug-in or one that is not a field factory.
    """
    data = _defaults()
    source = "defaults"
    if path is not None:
        source = str(path)
        user = read_toml(path, "config file", ConfigError)
        _merge(data, user, _defaults(), source, prefix="")
    sets = list(sets)
    for text in sets:
        table = parse_set(text)
        _merge(data, table, _defaults(), f"--set {text.partition('=')[0].strip()}", prefix="")
    if sets:
        source = f"{source} + --set"
    trusted = tuple(trusted)
    _validate(data, source, trusted)
    return Config(data, source, trusted)
