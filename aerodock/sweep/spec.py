"""A sweep's specification (TOML) and the cells it expands to.

```toml
[sweep]
kind = "grid"            # "grid": every combination; "random": `samples` random points
trials = 8               # docking trials per cell (one campaign per cell)
seeds = [0, 1]           # every point is flown with each campaign seed
samples = 20             # random only: number of points
sampling_seed = 0        # random only: seed of the draw of the points
model = "models/final"   # needed if compensation includes "model"
config = "my.toml"       # optional aerodock config (relative to this file)

[axes]                   # each axis: a list of values, or (random only) {min = a, max = b}
cable_length_m = [0.36, 0.64, 1.35]      # d_p, m
leader_speed_mps = [0.0, 0.25]           # leader speed towards north, m/s
mocap_noise_scale = [1.0, 5.0]           # x the config's motion-capture noise (pos and vel)
leader_dropout_s = ["none", [3.0, 1.0]]  # fault: leader state lost from 3 s for 1 s
compensation = ["observer", "oracle"]    # none | observer | model | oracle
controller = ["paper", "tuned", "ours"]  # the profile, as dock --controller
downwash.params.turb_vertical = [0.15, 0.25]  # any config key, by its dotted name
mission.terminal_s = {min = 0.5, max = 1.5}   # (random only: a range of a numeric key)
```

Axes left out keep the config's value (compensation: ``observer``; controller: ``tuned``; no
fault). A grid's points are the Cartesian product in the order of :data:`AXES`, then the config
keys in the file's order; a random study draws each axis independently (uniform on
``{min, max}``, integers for an integer key; uniform choice from a list).

**Config keys.** An axis named ``section.key`` (TOML's dotted keys, or one quoted name such as
``"downwash.params.turb_vertical"``) sets that key of the configuration, as a ``--config``
file would: same type, same rule, same checks between keys (:mod:`aerodock.config.loader`),
checked against the configuration the sweep flies for every point before any cell runs.
``leader.KEY`` sets a ``[vehicle]`` key for the leader alone. ``downwash.field`` (it names code)
and whole tables are not axes; ``platform.cable_length_m`` is the ``cable_length_m`` axis.
In a cell, the config keys apply first, then the controller profile (as ``dock --controller``
applies it over ``--config``), then the noise scale.

Every value is checked by the rule ``aerodock dock`` applies to it (:mod:`aerodock.mission.checks`:
a cable length in (0, 100] m with the docking point above the ground, a leader speed within
+-100 m/s, a dropout as the fault it becomes), and the size is limited
(:mod:`aerodock.mission.limits`: at most 10 000 trials per campaign, 10 000 campaigns and 200 000
trials in all, counted before the cells are expanded).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.config.schema import RULES
from aerodock.control.compensation import Compensation
from aerodock.control.profiles import PROFILES, controller_config
from aerodock.fileio import read_toml
from aerodock.mission.checks import (
    MissionSpecError,
    check_dropout,
    check_leader_speed,
    check_mission,
    check_number,
    check_offset,
)
from aerodock.mission.limits import MAX_TRIALS, LimitError, check_sweep_size

AXES = ("cable_length_m", "leader_speed_mps", "mocap_noise_scale", "leader_dropout_s",
        "compensation", "controller")
"""The named axes; any other axis is a config key (``section.key``)."""
_NUMERIC = ("cable_length_m", "leader_speed_mps", "mocap_noise_scale")
MAX_NOISE_SCALE = 1e6
"""Largest motion-capture noise scale (the scaled noise must also fit the config's ranges)."""
_SWEEP_KEYS = {"kind", "trials", "seeds", "samples", "sampling_seed", "model", "config", "name"}


class SweepSpecError(ValueError):
    """The sweep specification is invalid; the message names the file and the key."""


@dataclass(frozen=True)
class Cell:
    """One campaign of the sweep: a point of the axes and a campaign seed."""

    index: int
    cable_length_m: float | None
    leader_speed_mps: float
    mocap_noise_scale: float
    leader_dropout_s: tuple[float, float] | None
    compensation: str
    seed: int
    controller: str = "tuned"
    settings: tuple[tuple[str, Any], ...] = ()
    """The config keys' values of this cell, ``(("section.key", value), ...)``."""

    def row(self) -> dict[str, Any]:
        """The cell's columns of the tidy table (a column per config key after ``controller``)."""
        drop = self.leader_dropout_s
        return {"cell": self.index, "cable_length_m": self.cable_length_m,
                "leader_speed_mps": self.leader_speed_mps,
                "mocap_noise_scale": self.mocap_noise_scale,
                "fault": "none" if drop is None else "leader_dropout",
                "dropout_start_s": None if drop is None else drop[0],
                "dropout_duration_s": None if drop is None else drop[1],
                "compensation": self.compensation, "controller": self.controller,
                **dict(self.settings), "seed": self.seed}

    def overrides(self) -> dict[str, Any]:
        """The config keys as nested tables (``Config.with_overrides``)."""
        return nested_overrides(self.settings)


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep specification (see the module docstring)."""

    kind: str
    trials: int
    seeds: tuple[int, ...]
    axes: dict[str, Any]
    samples: int = 0
    sampling_seed: int = 0
    model: Path | None = None
    config: Path | None = None
    name: str = "sweep"
    source: str = "spec"
    cells: tuple[Cell, ...] = field(default=())


def _fail(source: str, msg: str) -> SweepSpecError:
    return SweepSpecError(f"{source}: {msg}")


def _check_value(source: str, axis: str, value: Any) -> Any:
    """One axis value, validated and normalised: by the rule ``dock`` applies to the same value
    (:mod:`aerodock.mission.checks`), named as the axis."""
    if axis in _NUMERIC:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise _fail(source, f"axes.{axis}: values must be numbers, got {value!r}")
        try:
            if axis == "cable_length_m":
                check_offset(value, f"axes.{axis}")
            elif axis == "leader_speed_mps":
                check_leader_speed(value, f"axes.{axis}")
            else:
                check_number(f"axes.{axis}", value, 0.0, MAX_NOISE_SCALE)
        except MissionSpecError as err:
            raise _fail(source, str(err)) from None
        return float(value)
    if axis == "compensation":
        try:
            return Compensation(value).value
        except ValueError:
            raise _fail(source, f"axes.compensation: {value!r} is not one of "
                        "none|observer|model|oracle") from None
    if axis == "controller":
        if value not in PROFILES:
            raise _fail(source, f"axes.controller: {value!r} is not one of {'|'.join(PROFILES)}")
        return value
    if axis == "leader_dropout_s":
        if value == "none":
            return None
        ok = (isinstance(value, list) and len(value) == 2
              and all(isinstance(v, int | float) and not isinstance(v, bool) and v >= 0
                      for v in value) and value[1] > 0)
        if not ok:
            raise _fail(source, f"axes.leader_dropout_s: {value!r} must be \"none\" or "
                        "[start_s, duration_s] with duration > 0")
        try:
            return check_dropout(value, "axes.leader_dropout_s")
        except MissionSpecError as err:
            raise _fail(source, str(err)) from None
    raise AssertionError(axis)  # pragma: no cover - every named axis is handled above


def nested_overrides(settings: tuple[tuple[str, Any], ...] | list[tuple[str, Any]]
                     ) -> dict[str, Any]:
    """``(("a.b.c", v), ...)`` as nested tables ``{"a": {"b": {"c": v}}}``."""
    out: dict[str, Any] = {}
    for dotted, value in settings:
        *path, last = dotted.split(".")
        table = out
        for part in path:
            table = table.setdefault(part, {})
        table[last] = value
    return out


def config_axis_kind(source: str, axis: str) -> str:
    """The rule kind (:class:`aerodock.config.schema.Rule`) of a config-key axis, after checking
    that the key can be an axis: a known key of the configuration (or any key of a plug-in
    field's ``downwash.params``), not a table, not the field's import path (that names code).

    Raises:
        SweepSpecError: not a key an axis can set; the message lists the named axes.
    """
    known = f"(named axes: {', '.join(AXES)}; or a config key such as mission.terminal_s)"
    if axis == "downwash.field":
        raise _fail(source, "axes.downwash.field: the field names code; it is not a sweep axis "
                    "(set it in the sweep's config file)")
    if axis == "platform.cable_length_m":
        raise _fail(source, "axes.platform.cable_length_m: the cable length is the "
                    "cable_length_m axis")
    section, _, key = axis.partition(".")
    if section == "leader":  # a [vehicle] key for the leader (the loader refuses the fixed)
        rule = RULES.get(f"vehicle.{key}")
    else:
        rule = RULES.get(axis)
    if rule is None and axis.startswith("downwash.params.") and axis.count(".") == 2:
        return "plugin"  # a plug-in field's own keyword argument (the default's are in RULES)
    if rule is None:
        hint = ""
        if section == "downwash" and f"downwash.params.{key}" in RULES:
            hint = f" (did you mean downwash.params.{key}?)"
        raise _fail(source, f"unknown axis 'axes.{axis}'{hint} {known}")
    if rule.kind == "table":
        raise _fail(source, f"axes.{axis}: a table, not a value; name one of its keys")
    return rule.kind


def _flatten_axes(source: str, raw: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``[axes]`` with TOML's dotted keys (nested tables) as ``"section.key"`` names; a table
    with exactly the keys ``min`` and ``max`` is a range, not a nesting."""
    out: dict[str, Any] = {}
    for key, value in raw.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and value and set(value) != {"min", "max"}:
            if name in AXES:
                raise _fail(source, f"axes.{name}: a {{min, max}} range needs exactly the keys "
                            "min and max")
            out.update(_flatten_axes(source, value, f"{name}."))
        else:
            out[name] = value
    return out


def parse_spec(data: dict[str, Any], source: str = "spec", base_dir: Path | None = None
               ) -> SweepSpec:
    """Validate a specification (a parsed TOML document) and expand its cells."""
    unknown = set(data) - {"sweep", "axes"}
    if unknown:
        raise _fail(source, f"unknown table(s) {sorted(unknown)} (expected [sweep] and [axes])")
    sw = data.get("sweep", {})
    bad = set(sw) - _SWEEP_KEYS
    if bad:
        raise _fail(source, f"unknown key(s) {sorted('sweep.' + k for k in bad)}")
    kind = sw.get("kind", "grid")
    if kind not in ("grid", "random"):
        raise _fail(source, f"sweep.kind must be \"grid\" or \"random\", got {kind!r}")
    trials = sw.get("trials", 8)
    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
        raise _fail(source, f"sweep.trials must be an integer >= 1, got {trials!r}")
    if trials > MAX_TRIALS:
        raise _fail(source, f"sweep.trials {trials} exceeds the limit of {MAX_TRIALS} per "
                    "campaign")
    seeds = sw.get("seeds", [0])
    if (not isinstance(seeds, list) or not seeds
            or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds)):
        raise _fail(source, f"sweep.seeds must be a non-empty list of integers, got {seeds!r}")
    samples = sw.get("samples", 0)
    if kind == "random" and (isinstance(samples, bool) or not isinstance(samples, int)
                             or samples < 1):
        raise _fail(source, f"sweep.samples must be an integer >= 1 for a random study, "
                    f"got {samples!r}")
    sampling_seed = sw.get("sampling_seed", 0)
    if isinstance(sampling_seed, bool) or not isinstance(sampling_seed, int) or sampling_seed < 0:
        raise _fail(source, f"sweep.sampling_seed must be an integer >= 0, got {sampling_seed!r}")
    for key in ("model", "config", "name"):
        if key in sw and not isinstance(sw[key], str):
            raise _fail(source, f"sweep.{key} must be a string, got {sw[key]!r}")
    base = base_dir or Path.cwd()
    model = Path(base, sw["model"]) if "model" in sw else None
    config = Path(base, sw["config"]) if "config" in sw else None
    raw_axes = data.get("axes", {})
    if not isinstance(raw_axes, dict):
        raise _fail(source, "[axes] must be a table")
    raw_axes = _flatten_axes(source, raw_axes)
    # The size before anything is expanded: a 3000 x 3000 grid is refused, not built.
    points = samples if kind == "random" else math.prod(
        len(v) if isinstance(v, list) else 1 for v in raw_axes.values())
    try:
        check_sweep_size(points * len(seeds), trials)
    except LimitError as err:
        raise _fail(source, str(err)) from None
    axes: dict[str, Any] = {}
    for axis, values in raw_axes.items():
        config_kind = None if axis in AXES else config_axis_kind(source, axis)
        if isinstance(values, dict):
            numeric = axis in _NUMERIC or config_kind in ("number", "integer")
            if kind != "random" or not numeric or set(values) != {"min", "max"}:
                raise _fail(source, f"axes.{axis}: a {{min, max}} range needs a random study "
                            "and a numeric axis")
            if config_kind is not None:
                lo, hi = (_range_end(source, axis, config_kind, values[k])
                          for k in ("min", "max"))
            else:
                lo, hi = (_check_value(source, axis, values[k]) for k in ("min", "max"))
            if not hi >= lo:
                raise _fail(source, f"axes.{axis}: max must be >= min")
            axes[axis] = {"min": lo, "max": hi}
        elif isinstance(values, list) and values:
            if config_kind is not None:
                axes[axis] = [float(v) if config_kind == "number" and type(v) is int else v
                              for v in values]
            else:
                axes[axis] = [_check_value(source, axis, v) for v in values]
        else:
            raise _fail(source, f"axes.{axis} must be a non-empty list of values")
    comps = axes.get("compensation", ["observer"])
    if "model" in comps and model is None:
        raise _fail(source, "compensation \"model\" needs sweep.model = \"MODEL_DIR\"")
    spec = SweepSpec(kind=kind, trials=trials, seeds=tuple(seeds), axes=axes, samples=samples,
                     sampling_seed=sampling_seed, model=model, config=config,
                     name=str(sw.get("name", "sweep")), source=source)
    return _with_cells(spec)


def _range_end(source: str, axis: str, config_kind: str, value: Any) -> float | int:
    """One end of a config key's ``{min, max}`` range: a finite number (an integer for an
    integer key); the key's own range is the loader's to check, point by point."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _fail(source, f"axes.{axis}: min and max must be finite numbers, got {value!r}")
    if config_kind == "integer":
        if not isinstance(value, int):
            raise _fail(source, f"axes.{axis}: an integer key's range takes integers, "
                        f"got {value!r}")
        return value
    return float(value)


SWEEP_NAMES = {"trials": "sweep.trials", "offset_m": "axes.cable_length_m",
               "leader_speed_mps": "axes.leader_speed_mps",
               "leader_dropout_s": "axes.leader_dropout_s", "compensation": "axes.compensation"}
"""How :func:`aerodock.mission.checks.check_mission` names a cell's values in a sweep."""


def cell_config(cfg: Config, cell: Cell) -> Config:
    """The configuration ``cell`` flies: ``cfg`` with the cell's config keys, then its
    controller profile (:func:`aerodock.control.profiles.controller_config`), then its
    motion-capture noise scale.

    Raises:
        ConfigError: a value the configuration refuses.
    """
    if cell.settings:
        cfg = cfg.with_overrides(cell.overrides(), source=f"{cfg.source} + sweep cell")
    cfg = controller_config(cfg, cell.controller)
    if cell.mocap_noise_scale != 1.0:
        scale = cell.mocap_noise_scale
        cfg = cfg.with_overrides({"mocap": {"pos_noise_m": cfg.mocap.pos_noise_m * scale,
                                            "vel_noise_mps": cfg.mocap.vel_noise_mps * scale}},
                                 source=f"axes.mocap_noise_scale {scale:g}")
    return cfg


def check_against_config(spec: SweepSpec, cfg: Config) -> None:
    """Check the sweep's cells against the configuration they fly, before any cell runs.

    Every named axis's value was checked on parsing by the rule ``dock`` applies to it; what
    depends on the configuration is checked here. Every distinct point of the config-key and
    controller axes is built as a configuration by the loader (the keys' types and rules, and
    the rules between keys); on each, the same :func:`~aerodock.mission.checks.check_mission`
    ``dock`` calls checks the run's size (per campaign) and the cable lengths, and the noise
    scales are checked as config values. Those last rules are monotonic in the value (a range,
    the docking point above the ground), so the smallest and largest value of each of those axes
    stand for all of them.

    Raises:
        SweepSpecError: a cell ``dock`` would refuse (the message names the axis or the key).
    """
    from aerodock.config import ConfigError
    from aerodock.mission.spec import MissionSpec

    def extremes(axis: str) -> list[float | None]:
        values = spec.axes.get(axis)
        if values is None:
            return [None]
        if isinstance(values, dict):
            return [values["min"], values["max"]]
        return [min(values), max(values)]

    seen: set[str] = set()
    try:
        for cell in spec.cells or (Cell(0, None, 0.0, 1.0, None, "observer", 0),):
            point = repr((cell.settings, cell.controller))
            if point in seen:
                continue
            seen.add(point)
            point_cfg = cfg
            if cell.settings:
                point_cfg = cfg.with_overrides(cell.overrides(), source=f"{spec.source}: axes")
            point_cfg = controller_config(point_cfg, cell.controller)
            for offset in extremes("cable_length_m"):
                check_mission(point_cfg, MissionSpec(trials=spec.trials, offset_m=offset),
                              SWEEP_NAMES, size=True)
            for scale in extremes("mocap_noise_scale"):
                if scale is not None:
                    point_cfg.with_overrides(
                        {"mocap": {"pos_noise_m": point_cfg.mocap.pos_noise_m * scale,
                                   "vel_noise_mps": point_cfg.mocap.vel_noise_mps * scale}},
                        source=f"axes.mocap_noise_scale {scale:g}")
    except (ConfigError, LimitError, MissionSpecError) as err:
        raise _fail(spec.source, str(err).removeprefix(f"{spec.source}: ")) from None


def load_spec(path: str | Path) -> SweepSpec:
    """Read and validate a sweep specification file."""
    path = Path(path)
    data = read_toml(path, "sweep specification", SweepSpecError)
    return parse_spec(data, str(path), path.parent)


def _axis_names(spec: SweepSpec) -> list[str]:
    """The axes in the order of a grid's product: :data:`AXES`, then the config keys."""
    return [a for a in AXES if a in spec.axes] + [a for a in spec.axes if a not in AXES]


def _points(spec: SweepSpec) -> list[dict[str, Any]]:
    names = _axis_names(spec)
    if spec.kind == "grid":
        return [dict(zip(names, combo, strict=True))
                for combo in itertools.product(*(spec.axes[a] for a in names))]
    rng = np.random.default_rng(spec.sampling_seed)
    points = []
    for _ in range(spec.samples):
        point = {}
        for a in names:
            values = spec.axes[a]
            if isinstance(values, dict) and isinstance(values["min"], int):
                point[a] = int(rng.integers(values["min"], values["max"] + 1))
            elif isinstance(values, dict):
                point[a] = float(rng.uniform(values["min"], values["max"]))
            else:
                point[a] = values[int(rng.integers(len(values)))]
        points.append(point)
    return points


def _with_cells(spec: SweepSpec) -> SweepSpec:
    keys = [a for a in spec.axes if a not in AXES]
    cells = []
    for point in _points(spec):
        for seed in spec.seeds:
            cells.append(Cell(
                index=len(cells), cable_length_m=point.get("cable_length_m"),
                leader_speed_mps=point.get("leader_speed_mps", 0.0),
                mocap_noise_scale=point.get("mocap_noise_scale", 1.0),
                leader_dropout_s=point.get("leader_dropout_s"),
                compensation=point.get("compensation", "observer"), seed=int(seed),
                controller=point.get("controller", "tuned"),
                settings=tuple((k, point[k]) for k in keys)))
    return SweepSpec(**{**spec.__dict__, "cells": tuple(cells)})
