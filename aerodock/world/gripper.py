"""The follower's single-point gripper: contact arm, HX711-like strain sensor, servo-driven gate.

Geometry: the contact arm sits ``mount_height_m`` above the follower's centre of mass (body -z).
The bar is *inside the gate* when its whole section passes through the mouth (perpendicular
distance from the gripper axis to the bar line <= ``aperture_m / 2`` minus the bar's radius,
within the bar's length) and its centre lies between the arm and ``gate_height_m`` minus the bar's
radius above it (and not more than its radius below: pushed through the arm). Contact is a stiff
spring-damper between arm and bar.

Sensing and actuation: the strain gauge is read at ``sensor_rate_hz`` with noise and a resting bias
that is calibrated at start (mean of ``calibration_samples`` readings, so a small residual remains);
a passive trigger fires when the calibrated reading exceeds ``contact_threshold_n``; an active
trigger fires when software commands it. Either way the servo starts ``latency_s`` later and the
torque-limited gate takes ``close_time_s`` to close. The bar is captured only if it is still inside
the gate when the gate finishes closing; if it was inside when closing began but not at the end,
it slipped through (the paper's failure mode).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import IntEnum

import numpy as np

from aerodock.config import Config
from aerodock.frozen import freeze
from aerodock.jit import any_layout, njit
from aerodock.world.sensor_kernels import (
    CHANGED_BY_CONTACT,
    CHANGED_DONE,
    CHANGED_READING,
    CHANGED_SERVO,
    CHANGED_START,
    gripper_step_kernel,
)


def _armed_any(flag: bool | np.ndarray) -> bool:
    """Whether a trigger is armed in any trial (a plain bool costs no array call in the loop)."""
    return flag if isinstance(flag, bool) else _any(flag)


def _any(a: np.ndarray) -> bool:
    """``bool(a.any())``: whether any element is nonzero (NaN counts, as it is truthy), through
    ``np.count_nonzero``'s C loop, a fifth of the cost of ``ndarray.any``'s reduction on a
    handful of trials (the gripper's tests run at every physics step)."""
    return bool(np.count_nonzero(a))


class GateState(IntEnum):
    """Per-trial gate state."""

    OPEN = 0
    CLOSING = 1
    CAPTURED = 2
    MISSED = 3


# Plain ints for the hot loop (an enum member lookup costs more than the array operation).
_OPEN, _CLOSING, _CAPTURED, _MISSED = 0, 1, 2, 3


@dataclass(frozen=True)
class GripperParams:
    """Constants of the gripper (see ``[gripper]`` in defaults.toml)."""

    aperture_m: float
    gate_height_m: float
    mount_height_m: float
    sensor_rate_hz: float
    sensor_noise_n: float
    sensor_bias_sd_n: float
    calibration_samples: int
    contact_threshold_n: float
    contact_stiffness_npm: float
    contact_damping_nspm: float
    latency_s: float
    close_time_s: float
    passive: bool | np.ndarray  # armed triggers: for every trial, or (n,) per trial
    active: bool | np.ndarray
    bar_radius_m: float
    bar_half_length_m: float

    @classmethod
    def from_config(cls, cfg: Config) -> GripperParams:
        """Bind ``[gripper]`` (and the bar's size) of ``cfg``."""
        g = cfg.gripper
        return cls(
            aperture_m=g.aperture_m, gate_height_m=g.gate_height_m,
            mount_height_m=g.mount_height_m, sensor_rate_hz=g.sensor_rate_hz,
            sensor_noise_n=g.sensor_noise_n, sensor_bias_sd_n=g.sensor_bias_sd_n,
            calibration_samples=int(g.calibration_samples),
            contact_threshold_n=g.contact_threshold_n,
            contact_stiffness_npm=g.contact_stiffness_npm,
            contact_damping_nspm=g.contact_damping_nspm, latency_s=g.latency_s,
            close_time_s=g.close_time_s, passive=g.trigger in ("passive", "both"),
            active=g.trigger in ("active", "both"),
            bar_radius_m=cfg.platform.bar_diameter_m / 2.0,
            bar_half_length_m=cfg.platform.bar_length_m / 2.0,
        )


@dataclass(frozen=True)
class GripperState:
    """Batch of N grippers."""

    gate: np.ndarray  # (n,) GateState
    bias_true_n: np.ndarray  # (n,) resting bias of the strain gauge
    bias_est_n: np.ndarray  # (n,) calibrated estimate of it
    reading_n: np.ndarray  # (n,) last calibrated reading
    servo_start_s: np.ndarray  # (n,) when the servo starts closing (nan: not triggered)
    triggered_by_contact: np.ndarray  # (n,) bool
    inside_at_start: np.ndarray  # (n,) bool: bar inside the gate when closing began
    slipped: np.ndarray  # (n,) bool: bar slipped through the closing gate
    resolved_s: np.ndarray  # (n,) when the gate finished closing (nan: not yet)
    close_time_s: np.ndarray  # (n,) servo travel time (inf: a jammed servo never closes)
    sensor_stuck_n: np.ndarray  # (n,) a faulty strain gauge reads this (nan: healthy)

    def __post_init__(self) -> None:
        # Read-only: a changed gripper is a new state (WorldState.gripper_flags keys on it).
        freeze(*(getattr(self, name) for name in _STATE_FIELDS))

    def __setstate__(self, state: dict) -> None:  # a copy or an unpickled state: read-only too
        self.__dict__.update(state)
        self.__post_init__()

    @property
    def captured(self) -> np.ndarray:
        """(n,) bool."""
        return self.gate == GateState.CAPTURED


_STATE_FIELDS = tuple(f.name for f in fields(GripperState))


def calibrated_gripper(n: int, params: GripperParams, rng: np.random.Generator) -> GripperState:
    """Grippers after the start-of-flight calibration of the strain gauge's resting bias."""
    bias = params.sensor_bias_sd_n * rng.standard_normal(n)
    calib_noise = params.sensor_noise_n / np.sqrt(params.calibration_samples)
    est = bias + calib_noise * rng.standard_normal(n)
    nan = np.full(n, np.nan)
    false = np.zeros(n, dtype=bool)
    return GripperState(
        gate=np.zeros(n, dtype=np.int8), bias_true_n=bias, bias_est_n=est, reading_n=np.zeros(n),
        servo_start_s=nan, triggered_by_contact=false, inside_at_start=false.copy(),
        slipped=false.copy(), resolved_s=nan.copy(), close_time_s=np.full(n, params.close_time_s),
        sensor_stuck_n=nan.copy(),
    )


def bar_in_gripper(
    follower_p: np.ndarray, follower_R: np.ndarray, follower_v: np.ndarray,  # noqa: N803
    bar_p: np.ndarray, bar_v: np.ndarray, bar_yaw_rad: np.ndarray, params: GripperParams,
    cos_sin: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contact force magnitude (n,), inside-gate flag (n,) and the follower's up axis (n, 3).

    The contact force pushes the bar along ``up`` and the follower along ``-up``. ``cos_sin``:
    ``(cos(bar_yaw_rad), sin(bar_yaw_rad))`` if the caller has them already.
    """
    force, inside, up = contact_in_gripper(follower_p, follower_R, follower_v, bar_p, bar_v,
                                           bar_yaw_rad, params, cos_sin)
    return (np.zeros_like(inside, dtype=float) if force is None else force), inside, up


def contact_in_gripper(
    follower_p: np.ndarray, follower_R: np.ndarray, follower_v: np.ndarray,  # noqa: N803
    bar_p: np.ndarray, bar_v: np.ndarray, bar_yaw_rad: np.ndarray, params: GripperParams,
    cos_sin: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
    """:func:`bar_in_gripper` with None for the force when no bar touches an arm (the usual
    step: the caller then has nothing to add). Compiled: :func:`contact_kernel`."""
    n = follower_p.shape[0]
    c, s = (np.cos(bar_yaw_rad), np.sin(bar_yaw_rad)) if cos_sin is None else cos_sin
    force, inside, up = np.empty(n), np.empty(n, dtype=bool), np.empty((n, 3))
    touching = contact_kernel(follower_p, follower_R, follower_v, bar_p, bar_v, c, s,
                              params.mount_height_m, params.bar_radius_m, params.aperture_m,
                              params.bar_half_length_m, params.gate_height_m,
                              params.contact_stiffness_npm, params.contact_damping_nspm, force,
                              inside, up)
    return (force if touching else None), inside, up


@njit
def contact_kernel_body(fol_p: np.ndarray, fol_r: np.ndarray, fol_v: np.ndarray, bar_p: np.ndarray,
                        bar_v: np.ndarray, cos_yaw: np.ndarray, sin_yaw: np.ndarray,
                        mount_height: float, bar_radius: float, aperture: float,
                        bar_half_length: float, gate_height: float, stiffness: float,
                        damping: float, force: np.ndarray, inside: np.ndarray,
                        up: np.ndarray) -> bool:
    """The bar against each follower's contact arm: the force magnitude ``force`` (n,), the
    bar inside the gate ``inside`` (n,) and the follower's up axis ``up`` (n, 3); whether any
    bar touches an arm.

    The arm sits ``mount_height`` up the follower's axis; the bar (its axis horizontal,
    ``(cos yaw, sin yaw, 0)``, radius ``r``) fits through the mouth only with its whole
    section: centre within ``aperture/2 - r`` of the axis; the closed gate holds it between the
    arm (a bar pressed more than its radius into the arm's contact spring has passed below it)
    and the gate's top. Contact is a spring-damper, pushing only."""
    any_touching = False
    mouth = aperture / 2.0 - bar_radius
    for i in range(fol_p.shape[0]):
        u0, u1, u2 = -fol_r[i, 0, 2], -fol_r[i, 1, 2], -fol_r[i, 2, 2]
        up[i, 0], up[i, 1], up[i, 2] = u0, u1, u2
        r0 = bar_p[i, 0] - (u0 * mount_height + fol_p[i, 0])
        r1 = bar_p[i, 1] - (u1 * mount_height + fol_p[i, 1])
        r2 = bar_p[i, 2] - (u2 * mount_height + fol_p[i, 2])
        height = r0 * u0 + r1 * u1 + r2 * u2
        h0, h1, h2 = r0 - height * u0, r1 - height * u1, r2 - height * u2
        c, s = cos_yaw[i], sin_yaw[i]
        along = h0 * c
        along += h1 * s
        d0 = h0 - along * c
        d1 = h1 - along * s
        perp = d0 * d0
        perp += d1 * d1
        perp += h2 * h2
        perp = math.sqrt(perp)
        in_mouth = perp <= mouth and abs(along) <= bar_half_length
        inside[i] = in_mouth and height <= gate_height - bar_radius and height > -bar_radius
        penetration = bar_radius - height
        if in_mouth and penetration > 0:
            any_touching = True
            rate = -((bar_v[i, 0] - fol_v[i, 0]) * u0 + (bar_v[i, 1] - fol_v[i, 1]) * u1
                     + (bar_v[i, 2] - fol_v[i, 2]) * u2)
            f = stiffness * penetration + damping * rate
            force[i] = f if (f >= 0.0 or f != f) else 0.0
        else:
            force[i] = 0.0
    return any_touching


@any_layout("force", "inside", "up")
@njit
def contact_kernel(fol_p: np.ndarray, fol_r: np.ndarray, fol_v: np.ndarray, bar_p: np.ndarray,
                   bar_v: np.ndarray, cos_yaw: np.ndarray, sin_yaw: np.ndarray,
                   mount_height: float, bar_radius: float, aperture: float,
                   bar_half_length: float, gate_height: float, stiffness: float,
                   damping: float, force: np.ndarray, inside: np.ndarray,
                   up: np.ndarray) -> bool:
    """:func:`contact_kernel_body` for a call from Python: any array layout (sealed to one general
    signature, :func:`aerodock.jit.any_layout`); compiled callers call the body itself, which no
    seal stops from compiling for their types."""
    return contact_kernel_body(fol_p, fol_r, fol_v, bar_p, bar_v, cos_yaw, sin_yaw, mount_height,
                               bar_radius, aperture, bar_half_length, gate_height, stiffness,
                               damping, force, inside, up)


@njit
def contact_push(contact: np.ndarray, up: np.ndarray, captured: np.ndarray, any_captured: bool,
                 contact_seen: np.ndarray, fol_force: np.ndarray, bar_force: np.ndarray) -> None:
    """The contact's push (the world's ``gripper contact`` term, once some bar touches an arm):
    no push on a captured follower (``contact`` set to 0 there, in place: NumPy's
    ``np.where(captured, 0.0, contact)``), ``push = up * contact``, ``contact_seen |= contact >
    0``, the followers' rows ``fol_force -= push`` (n, 3: the followers' rows of the step's
    accumulator) and ``bar_force += push``, element by element as NumPy computes them.

    Row by row: a trial whose bar touches nothing (its contact 0) takes no push, whatever the
    other trials do, so a block of trials computes what the whole batch does for its rows (the
    compiled period's blocks, :mod:`aerodock.world.period_kernel`). NumPy's batch pushed a zero
    there, which changes a number only where the accumulator holds a -0 (the sign of a zero)."""
    for i in range(contact.shape[0]):
        if any_captured and captured[i]:
            contact[i] = 0.0
        c = contact[i]
        if c == 0.0:
            continue
        if c > 0:
            contact_seen[i] = True
        for k in range(3):
            push = up[i, k] * c
            fol_force[i, k] -= push
            bar_force[i, k] += push


def gripper_idle(state: GripperState) -> bool:
    """Every gate open and no servo waiting to start (start times NaN or never): a step in which
    no trigger fires changes nothing (see :func:`step_is_idle`)."""
    gate = state.gate
    return bool(np.count_nonzero(gate == _OPEN) == gate.size  # (gate == OPEN).all()
                and not _any(state.servo_start_s < np.inf))


def step_is_idle(idle: bool, sample_sensor: bool, close_command: np.ndarray,
                 params: GripperParams) -> bool:
    """Whether :func:`step_gripper` would return its state unchanged without drawing: an
    ``idle`` gripper (:func:`gripper_idle`) between sensor samples with no active command."""
    return idle and not sample_sensor and not (_armed_any(params.active) and _any(close_command))


def step_gripper(
    state: GripperState,
    t_s: float,
    contact_force_n: np.ndarray,
    inside: np.ndarray,
    sample_sensor: bool,
    close_command: np.ndarray,
    params: GripperParams,
    rng: np.random.Generator,
) -> GripperState:
    """Advance the sensor, triggers and gate to time ``t_s``.

    Args:
        state: current state.
        t_s: simulation time now.
        contact_force_n: (n,) true contact force on the arm.
        inside: (n,) bar inside the gate now.
        sample_sensor: the HX711 produces a sample at this step.
        close_command: (n,) bool, the software's active trigger (ignored unless active).
        params: gripper constants.
        rng: noise source.
    """
    n = state.gate.shape[0]
    # The strain gauge's noise is drawn as always: (n,) at a sample, nothing otherwise.
    noise = rng.standard_normal(contact_force_n.shape) if sample_sensor else _NO_NOISE
    passive_any, active_any = _armed_any(params.passive), _armed_any(params.active)
    reading, servo_start, resolved = np.empty(n), np.empty(n), np.empty(n)
    by_contact, inside_at_start = np.empty(n, dtype=bool), np.empty(n, dtype=bool)
    slipped, gate = np.empty(n, dtype=bool), np.empty(n, dtype=np.int8)
    changed = gripper_step_kernel(
        state.gate, state.bias_true_n, state.bias_est_n, state.reading_n, state.servo_start_s,
        state.triggered_by_contact, state.inside_at_start, state.slipped, state.resolved_s,
        state.close_time_s, state.sensor_stuck_n, float(t_s), contact_force_n, _bools(inside),
        bool(sample_sensor), noise, float(params.sensor_noise_n),
        float(params.contact_threshold_n), passive_any, _trigger_rows(params.passive),
        active_any, _trigger_rows(params.active), _bools(close_command),
        float(params.latency_s), reading, by_contact, servo_start, gate, inside_at_start,
        slipped, resolved)
    if not changed:
        return state  # nothing changed (states are never modified in place)
    return gripper_after(state, changed, reading, by_contact, servo_start, gate, inside_at_start,
                         slipped, resolved)


def gripper_after(state: GripperState, changed: int, reading: np.ndarray,
                  by_contact: np.ndarray, servo_start: np.ndarray, gate: np.ndarray,
                  inside_at_start: np.ndarray, slipped: np.ndarray,
                  resolved: np.ndarray) -> GripperState:
    """The grippers' state after :func:`gripper_step_kernel` wrote the new arrays and said which
    it ``changed`` (its ``CHANGED_*`` bits): those arrays where they changed, the state's own
    where not (passed on as they are: states are never modified in place)."""
    started, done = changed & (CHANGED_START | CHANGED_DONE), changed & CHANGED_DONE
    record = object.__new__(GripperState)
    # GripperState's __init__ sets its fields and freezes its arrays; ``state``'s are frozen
    # already (every GripperState's are), so only the new ones are frozen here: the same record
    # for half the cost (this runs in most control periods: the strain gauge's reading
    # changes at every sample)
    record.__dict__.update(
        gate=_frozen(gate) if started else state.gate,
        bias_true_n=state.bias_true_n, bias_est_n=state.bias_est_n,
        reading_n=_frozen(reading) if changed & CHANGED_READING else state.reading_n,
        servo_start_s=_frozen(servo_start) if changed & CHANGED_SERVO else state.servo_start_s,
        triggered_by_contact=_frozen(by_contact) if changed & CHANGED_BY_CONTACT
        else state.triggered_by_contact,
        inside_at_start=_frozen(inside_at_start) if changed & CHANGED_START
        else state.inside_at_start,
        slipped=_frozen(slipped) if done else state.slipped,
        resolved_s=_frozen(resolved) if done else state.resolved_s,
        close_time_s=state.close_time_s, sensor_stuck_n=state.sensor_stuck_n)
    return record


def _frozen(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only."""
    a.flags.writeable = False
    return a


_NO_NOISE = np.zeros(0)  # gripper_step_kernel's noise between samples (not read)
_ARMED, _UNARMED = np.ones(1, dtype=bool), np.zeros(1, dtype=bool)
freeze(_NO_NOISE, _ARMED, _UNARMED)


def _trigger_rows(flag: bool | np.ndarray) -> np.ndarray:
    """A trigger's arming as gripper_step_kernel reads it: (1,) for every trial, or (n,)."""
    if isinstance(flag, np.ndarray) and flag.ndim:
        return _bools(flag)
    return _ARMED if flag else _UNARMED


def _bools(a: np.ndarray) -> np.ndarray:
    """``a`` as a bool array (itself when it is one)."""
    return a if isinstance(a, np.ndarray) and a.dtype == np.bool_ else np.asarray(a, dtype=bool)
