"""Fault injection: what goes wrong on real flights, drawn per trial and flown by the mission.

A fault file (TOML) lists faults as ``[[fault]]`` tables::

    [[fault]]
    name = "follower mocap dropout"
    kind = "follower_mocap_dropout"   # one of KINDS
    probability = 1.0                 # fraction of trials that suffer it
    start_s = [2.0, 3.8]              # when it starts: uniform in this range (mission time)
    duration_s = 0.3                  # how long, s (leave it out: to the end of the trial)
    magnitude = 0.0                   # kind-specific (see KINDS)

Kinds (``magnitude`` in brackets):

- ``follower_mocap_dropout`` / ``leader_mocap_dropout``: that vehicle's motion capture freezes
  at its last value (the vehicle's own controller and the follower's view of it);
- ``latency_spike``: the follower's motion capture arrives [magnitude s, 0-10] late;
- ``leader_state_lost``: the leader's state stops reaching the follower (network);
- ``contact_sensor_dead`` / ``contact_sensor_stuck``: the strain gauge reads 0 /
  [magnitude N, 0-10 000];
- ``servo_slow`` / ``servo_jammed``: the gate closes [magnitude, 1-100] times slower / never;
- ``rotor_thrust_loss``: one of the follower's rotors (drawn per trial) loses [magnitude, a
  fraction 0-1] of its thrust (rigid-body world).

Kinds without a magnitude take none (0 if given). ``probability`` is in [0, 1], ``start_s``
and ``duration_s`` are finite, at most :data:`MAX_FAULT_TIME_S` (the longest mission time a
config allows), and ``duration_s`` is positive. :func:`check_fault` applies these rules to
faults built in code too (the mission checks every fault it is given).

Every draw comes from the campaign's per-trial random streams: same file and seed, same faults.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import read_toml

KINDS = ("follower_mocap_dropout", "leader_mocap_dropout", "latency_spike", "leader_state_lost",
         "contact_sensor_dead", "contact_sensor_stuck", "servo_slow", "servo_jammed",
         "rotor_thrust_loss")
_DEFAULT_MAGNITUDE = {"latency_spike": 0.1, "contact_sensor_stuck": 1.0, "servo_slow": 3.0,
                      "rotor_thrust_loss": 0.3}
MAX_FAULTS = 64
MAGNITUDE_RANGES: dict[str, tuple[float, float]] = {
    "latency_spike": (0.0, 10.0),  # s, as mocap.latency_s
    "contact_sensor_stuck": (0.0, 10_000.0),  # N, as gripper.contact_threshold_n
    "servo_slow": (1.0, 100.0),  # x the closing time: slower, never faster
    "rotor_thrust_loss": (0.0, 1.0),  # a fraction of the rotor's thrust
}
"""Each kind's physical range of ``magnitude`` (inclusive); kinds not listed have none (0)."""
MAX_FAULT_TIME_S = 600.0
"""Latest start and longest duration of a fault, s (durations in the config go up to 600 s)."""


@dataclass(frozen=True)
class Fault:
    """One fault as the file states it."""

    name: str
    kind: str
    probability: float = 1.0
    start_s: tuple[float, float] = (0.0, 0.0)
    duration_s: float = math.inf
    magnitude: float = 0.0


@dataclass(frozen=True)
class FaultDraw:
    """One fault drawn for N trials: who has it, when, and (for a rotor fault) which rotor."""

    fault: Fault
    hit: np.ndarray  # (n,) bool
    start_s: np.ndarray  # (n,)
    end_s: np.ndarray  # (n,)
    rotor: np.ndarray  # (n,) int

    def active(self, t_s: float) -> np.ndarray:
        """(n,) bool: the fault is on at mission time ``t_s``."""
        return self.hit & (self.start_s <= t_s) & (t_s < self.end_s)


class FaultFileError(ValueError):
    """A fault file is unreadable or invalid; the message names the file and the entry."""


def _number(entry: dict[str, Any], key: str, default: float, where: str) -> float:
    value = entry.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise FaultFileError(f"{where}: '{key}' must be a number, got {value!r}")
    value = float(value)
    if key in entry and (not math.isfinite(value) or value < 0):
        raise FaultFileError(f"{where}: '{key}' must be finite and >= 0, got {value!r}")
    return value


def check_fault(fault: Fault, where: str) -> None:
    """Refuse a fault whose values are outside their physical ranges (see the module docstring).

    Raises:
        FaultFileError: unknown kind, a probability outside [0, 1], a start or duration that is
            not finite or beyond :data:`MAX_FAULT_TIME_S` (an infinite duration is allowed only
            as the default, "to the end"), or a magnitude outside its kind's range.
    """
    if fault.kind not in KINDS:
        raise FaultFileError(f"{where}: 'kind' must be one of {'|'.join(KINDS)}, "
                             f"got {fault.kind!r}")
    if not 0.0 <= fault.probability <= 1.0:
        raise FaultFileError(f"{where}: 'probability' must be in [0, 1], got {fault.probability}")
    lo, hi = fault.start_s
    if not (0.0 <= lo <= hi <= MAX_FAULT_TIME_S):
        raise FaultFileError(f"{where}: 'start_s' must be a number or [low, high] with "
                             f"0 <= low <= high <= {MAX_FAULT_TIME_S:g}, got {[lo, hi]!r}")
    duration = fault.duration_s
    if not (duration == math.inf or 0.0 < duration <= MAX_FAULT_TIME_S):
        raise FaultFileError(f"{where}: 'duration_s' must be > 0 and <= {MAX_FAULT_TIME_S:g} s "
                             f"(leave it out for a fault that lasts to the end), got {duration!r}")
    low, high = MAGNITUDE_RANGES.get(fault.kind, (0.0, 0.0))
    if not low <= fault.magnitude <= high:
        if high == 0.0:
            raise FaultFileError(f"{where}: kind {fault.kind} has no 'magnitude' (0 if given), "
                                 f"got {fault.magnitude!r}")
        raise FaultFileError(f"{where}: 'magnitude' of {fault.kind} must be between {low:g} "
                             f"and {high:g}, got {fault.magnitude!r}")


def parse_faults(data: dict[str, Any], source: str) -> list[Fault]:
    """Faults from a parsed TOML document (``[[fault]]`` tables)."""
    entries = data.get("fault")
    unknown = set(data) - {"fault"}
    if unknown:
        raise FaultFileError(f"{source}: unknown table(s) {sorted(unknown)}; expected [[fault]]")
    if not isinstance(entries, list) or not entries:
        raise FaultFileError(f"{source}: no [[fault]] entries")
    if len(entries) > MAX_FAULTS:
        raise FaultFileError(f"{source}: {len(entries)} faults; at most {MAX_FAULTS}")
    faults = []
    allowed = {"name", "kind", "probability", "start_s", "duration_s", "magnitude"}
    for i, entry in enumerate(entries):
        where = f"{source}: fault {i + 1}"
        if not isinstance(entry, dict):
            raise FaultFileError(f"{where}: must be a table")
        extra = set(entry) - allowed
        if extra:
            raise FaultFileError(f"{where}: unknown key(s) {sorted(extra)}")
        kind = entry.get("kind")
        if kind not in KINDS:
            raise FaultFileError(f"{where}: 'kind' must be one of {'|'.join(KINDS)}, got {kind!r}")
        name = entry.get("name", kind)
        if not isinstance(name, str) or not name:
            raise FaultFileError(f"{where}: 'name' must be a non-empty string")
        prob = _number(entry, "probability", 1.0, where)
        if prob > 1:
            raise FaultFileError(f"{where}: 'probability' must be in [0, 1], got {prob}")
        start = entry.get("start_s", [0.0, 0.0])
        if isinstance(start, int | float) and not isinstance(start, bool):
            start = [start, start]
        if (not isinstance(start, list) or len(start) != 2
                or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in start)
                or not all(math.isfinite(x) and x >= 0 for x in start) or start[0] > start[1]):
            raise FaultFileError(f"{where}: 'start_s' must be a number or [low, high] with "
                                 f"0 <= low <= high, got {start!r}")
        fault = Fault(
            name=name, kind=kind, probability=prob, start_s=(float(start[0]), float(start[1])),
            duration_s=_number(entry, "duration_s", math.inf, where),
            magnitude=_number(entry, "magnitude", _DEFAULT_MAGNITUDE.get(kind, 0.0), where),
        )
        check_fault(fault, where)
        faults.append(fault)
    return faults


def load_faults(path: str | Path) -> list[Fault]:
    """Read a fault file (see the module docstring).

    Raises:
        FaultFileError: unreadable file, bad TOML, unknown kind or key, out-of-range value.
    """
    return parse_faults(read_toml(path, "fault file", FaultFileError), str(path))


def draw_faults(faults: tuple[Fault, ...], n: int, rng: Any) -> list[FaultDraw]:
    """Per-trial draws of every fault (``rng``: the campaign's per-trial streams)."""
    draws = []
    for f in faults:
        u = rng.random((n, 3))
        hit = u[:, 0] < f.probability
        start = f.start_s[0] + (f.start_s[1] - f.start_s[0]) * u[:, 1]
        rotor = np.minimum((u[:, 2] * 4).astype(int), 3)
        draws.append(FaultDraw(f, hit, start, start + f.duration_s, rotor))
    return draws


def _freeze(obs: Any, held: Any, mask: np.ndarray) -> Any:
    """``obs`` with the rows in ``mask`` replaced by ``held`` (same Observation type)."""
    if held is None or not np.count_nonzero(mask):
        return obs
    m = mask[:, None]
    return type(obs)(np.where(m, held.p, obs.p), np.where(m, held.v, obs.v),
                     np.where(m, held.rpy, obs.rpy))


class FaultRuntime:
    """Applies drawn faults to one campaign, tick by tick (mission time ``t``).

    Observation faults return what the controllers see; gripper and rotor faults are written
    into the world's state. The leader's state over the network is handled here too (the
    mission's ``leader_dropout_s`` window is a ``leader_state_lost`` fault on every trial).
    """

    def __init__(self, draws: list[FaultDraw], n: int, dt_control_s: float) -> None:
        self.draws = draws
        self.n = n
        self.kinds = {d.fault.kind for d in draws}
        self._drawn = {kind: [d for d in draws if d.fault.kind == kind] for kind in self.kinds}
        spikes = [d.fault.magnitude for d in draws if d.fault.kind == "latency_spike"]
        self._delay_ticks = int(round(max(spikes, default=0.0) / dt_control_s))
        self._dt = dt_control_s
        self._past_f: list[Any] = []
        self._held: dict[str, Any] = {"follower": None, "leader": None, "network": None}
        self.last_fresh_leader_t = np.zeros(n)

    def _on(self, kind: str, t: float) -> np.ndarray | None:
        """(n,) bool: a fault of ``kind`` is on at ``t`` (None: no fault of that kind)."""
        drawn = self._drawn.get(kind)
        if not drawn:
            return None
        on = np.zeros(self.n, dtype=bool)
        for d in drawn:
            on |= d.active(t)
        return on

    def observations(self, t: float, obs_l: Any, obs_f: Any) -> tuple[Any, Any, Any]:
        """(leader's own view, follower's own view, follower's view of the leader)."""
        if self._delay_ticks:
            self._past_f = (self._past_f + [obs_f])[-(self._delay_ticks + 1):]
            for d in self.draws:
                if d.fault.kind == "latency_spike":
                    lag = min(int(round(d.fault.magnitude / self._dt)), len(self._past_f) - 1)
                    obs_f = _freeze(obs_f, self._past_f[-1 - lag], d.active(t))
        for who in ("follower", "leader"):
            down = self._on(f"{who}_mocap_dropout", t)
            if down is None:
                continue  # this capture never freezes: nothing to hold
            obs = obs_f if who == "follower" else obs_l
            obs = _freeze(obs, self._held[who], down)
            self._held[who] = obs
            if who == "follower":
                obs_f = obs
            else:
                obs_l = obs
        lost = self._on("leader_state_lost", t)
        if lost is None:  # the leader's state always arrives, fresh
            self.last_fresh_leader_t = np.full(self.n, t)
            return obs_l, obs_f, obs_l
        obs_l_f = _freeze(obs_l, self._held["network"], lost)
        self._held["network"] = obs_l_f
        self.last_fresh_leader_t = np.where(lost, self.last_fresh_leader_t, t)
        return obs_l, obs_f, obs_l_f

    def apply_to_world(self, t: float, world: Any) -> None:
        """Write this tick's gripper and rotor faults into ``world``."""
        g = world.gripper
        if self.kinds & {"contact_sensor_dead", "contact_sensor_stuck"}:
            stuck = np.full(self.n, np.nan)
            for d in self.draws:
                if d.fault.kind in ("contact_sensor_dead", "contact_sensor_stuck"):
                    value = 0.0 if d.fault.kind == "contact_sensor_dead" else d.fault.magnitude
                    stuck = np.where(d.active(t), value, stuck)
            g = replace(g, sensor_stuck_n=stuck)
        if self.kinds & {"servo_slow", "servo_jammed"}:
            close = np.full(self.n, world.gripper_params.close_time_s)
            for d in self.draws:
                if d.fault.kind == "servo_slow":
                    close = np.where(d.active(t), close * d.fault.magnitude, close)
                elif d.fault.kind == "servo_jammed":
                    close = np.where(d.active(t), np.inf, close)
            g = replace(g, close_time_s=close)
        world.gripper = g
        if "rotor_thrust_loss" in self.kinds:
            loss = np.zeros((self.n, 4))
            rows = np.arange(self.n)
            for d in self.draws:
                if d.fault.kind == "rotor_thrust_loss":
                    on = d.active(t)
                    loss[rows[on], d.rotor[on]] = np.maximum(loss[rows[on], d.rotor[on]],
                                                             min(d.fault.magnitude, 1.0))
            world.set_rotor_loss(loss)
