"""The configuration's keys: one typed section per TOML table, each key with its rule.

``defaults.toml`` holds every key's default value (and the comment a user reads); this module
holds, beside each key's type, the rule a value must satisfy: a range (``number``, ``integer``),
a set of choices (``choice``), a fixed-length list (``numbers``) or a bounded list
(``number_list``). A test checks that the two name exactly the same keys. Code reads a section
as a typed, frozen object (``cfg.vehicle.mass_kg``), so a misspelt key is an attribute error a
type checker sees, not a dict lookup.

The ranges keep values physical (a 1e-300 m rotor has no disk area: NaN forces), keep the
arithmetic finite, and keep a run's memory and time bounded (durations <= 10 min of flight,
rates <= 20 kHz).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

from aerodock.learning.kinds import trained_kinds

STACKS = ("generic", "arducopter", "crazyflie-pid", "crazyflie-sjc")
"""``[autopilot] stack``'s choices: the flight stacks whose attitude loops a rigid-body vehicle
flies (:mod:`aerodock.world.vehicles.stacks`)."""


@dataclass(frozen=True)
class Rule:
    """What a key's value must be (the numeric bounds are inclusive)."""

    kind: str  # number | integer | choice | numbers | number_list | flag | text | table
    low: float = 0.0
    high: float = 0.0
    choices: tuple[str, ...] = ()
    length: int = 0  # numbers: exactly this many; number_list: at most this many


def _key(rule: Rule) -> Any:
    return field(metadata={"rule": rule})


def number(low: float, high: float) -> Any:
    """A finite number in ``[low, high]``."""
    return _key(Rule("number", low, high))


def integer(low: int, high: int) -> Any:
    """An integer in ``[low, high]``."""
    return _key(Rule("integer", low, high))


def choice(*options: str) -> Any:
    """One of ``options``."""
    return _key(Rule("choice", choices=tuple(options)))


def numbers(length: int, low: float, high: float) -> Any:
    """Exactly ``length`` finite numbers, each in ``[low, high]``."""
    return _key(Rule("numbers", low, high, length=length))


def number_list(max_length: int, low: float, high: float) -> Any:
    """A list of up to ``max_length`` finite numbers, each in ``[low, high]``."""
    return _key(Rule("number_list", low, high, length=max_length))


def flag() -> Any:
    """A boolean."""
    return _key(Rule("flag"))


def text() -> Any:
    """A string."""
    return _key(Rule("text"))


def table() -> Any:
    """A table of free keys (a plug-in field's own keyword arguments)."""
    return _key(Rule("table"))


@dataclass(frozen=True)
class VehicleSection:
    """``[vehicle]``: both quadrotors (the paper's in-house vehicles)."""

    model: str = choice("point-mass", "rigid-body")
    mass_kg: float = number(0.001, 100)
    diagonal_m: float = number(0.01, 10)
    rotor_radius_m: float = number(0.001, 5)
    n_rotors: int = integer(1, 16)
    drag_coeff_kgps: float = number(0, 100)
    tau_attitude_s: float = number(1e-06, 10)
    tau_thrust_s: float = number(1e-06, 10)
    tilt_max_deg: float = number(1, 89)
    # Hover needs 1 g; 10 % more is the least that leaves any authority to manoeuvre.
    thrust_max_g: float = number(1.1, 10)
    thrust_gain_sd: float = number(0, 0.5)
    mass_sd: float = number(0, 0.3)
    inertia_sd: float = number(0, 0.3)
    torque_coeff_sd: float = number(0, 0.3)
    motor_tau_sd: float = number(0, 0.3)
    accel_noise_mps2: float = number(0, 100)
    inertia_kgm2: list[float] = numbers(3, 1e-07, 1000)
    rotor_thrust_coeff: float = number(1e-10, 0.01)
    rotor_torque_ratio_m: float = number(0, 1)
    motor_tau_s: float = number(0.0001, 10)
    rotor_drag_coeff: float = number(0, 1)
    rotor_drag_z_coeff: float = number(0, 1)
    parasitic_drag_coeff: float = number(0, 100)


@dataclass(frozen=True)
class AutopilotSection:
    """``[autopilot]``: the rigid-body vehicles' autopilot, a flight stack's attitude loops
    (:mod:`aerodock.world.vehicles.stacks`) -> mixer."""

    stack: str = choice(*STACKS)
    attitude_p: list[float] = numbers(3, 0, 1000)
    rate_p: list[float] = numbers(3, 0, 10000)
    rate_i: list[float] = numbers(3, 0, 100000)
    rate_integral_max_radps2: float = number(0, 10000)
    rate_max_dps: list[float] = numbers(3, 1, 3600)
    ac_ang_p: list[float] = numbers(3, 0, 1000)
    ac_accel_max_cdss: list[float] = numbers(3, 0, 1e7)
    ac_input_tc_s: float = number(0, 10)
    ac_rat_p: list[float] = numbers(3, 0, 100)
    ac_rat_i: list[float] = numbers(3, 0, 100)
    ac_rat_d: list[float] = numbers(3, 0, 10)
    ac_rat_imax: list[float] = numbers(3, 0, 10)
    ac_rat_fltt_hz: list[float] = numbers(3, 0, 10000)
    ac_rat_flte_hz: list[float] = numbers(3, 0, 10000)
    ac_rat_fltd_hz: list[float] = numbers(3, 0, 10000)
    cf_att_kp: list[float] = numbers(3, 0, 1000)
    cf_att_ki: list[float] = numbers(3, 0, 1000)
    cf_att_ilimit_deg: list[float] = numbers(3, 0, 1e5)
    cf_rate_kp: list[float] = numbers(3, 0, 1e6)
    cf_rate_ki: list[float] = numbers(3, 0, 1e6)
    cf_rate_kd: list[float] = numbers(3, 0, 1e5)
    cf_rate_ilimit_deg: list[float] = numbers(3, 0, 1e5)
    cf_thrust_max_n: float = number(1e-6, 1e4)
    sjc_lambda: list[float] = numbers(3, 0, 1000)
    sjc_k_nms: list[float] = numbers(3, 0, 100)
    sjc_ki_nm: list[float] = numbers(3, 0, 100)
    sjc_ilimit_rad: list[float] = numbers(3, 0, 1000)
    sjc_kdw_nms2: list[float] = numbers(3, 0, 10)
    sjc_jtune_kgm2: list[float] = numbers(3, 0, 10)


@dataclass(frozen=True)
class ImuSection:
    """``[imu]``: what the flight computer's IMU measures (rigid-body vehicles)."""

    gyro_noise_radps: float = number(0, 10)
    accel_vibration_mps2: float = number(0, 1000)
    accel_bias_sd_mps2: float = number(0, 100)
    attitude_noise_rad: float = number(0, 1)
    chain: str = choice("filtered", "ideal")
    gyro_cutoff_hz: float = number(0, 10000)
    accel_cutoff_hz: float = number(0, 10000)
    latency_s: float = number(0, 1)
    gyro_range_dps: float = number(10, 1e5)
    accel_range_g: float = number(1, 1000)
    accel_gain_radps: float = number(0, 100)
    heading_gain_radps: float = number(0, 100)


@dataclass(frozen=True)
class MocapSection:
    """``[mocap]``: motion capture's noise and latency."""

    pos_noise_m: float = number(0, 10)
    vel_noise_mps: float = number(0, 100)
    latency_s: float = number(0, 10)


@dataclass(frozen=True)
class SimSection:
    """``[sim]``: rates and constants of the simulation."""

    physics_rate_hz: float = number(1, 20000)
    control_rate_hz: float = number(1, 20000)
    gravity_mps2: float = number(0.1, 100)
    air_density_kgpm3: float = number(0.01, 100)


@dataclass(frozen=True)
class DownwashSection:
    """``[downwash]``: the field's import path and its keyword arguments."""

    field: str = text()
    params: dict[str, Any] = table()


@dataclass(frozen=True)
class JetParams:
    """``[downwash.params]`` of the default field (:class:`aerodock.downwash.jet.RoundJetField`);
    a plug-in field's parameters are its own (checked when it is built)."""

    width0_ratio: float = number(0.01, 100)
    spread_rate: float = number(0, 10)
    ingest_coeff: float = number(0, 10)
    ingest_exponent: float = number(0.1, 5)
    planar_ratio: float = number(-10, 10)
    body_area_ratio: float = number(0, 100)
    body_drag_coeff: float = number(0, 100)
    disk_torque_gain: float = number(0, 100)
    turb_vertical: float = number(0, 10)
    turb_lateral: float = number(0, 10)
    turb_length_ratio: float = number(0.001, 1000)
    turb_time_ratio: float = number(0.001, 10000)
    bar_drag_coeff: float = number(0, 100)
    bar_turb_vertical: float = number(0, 1e6)
    bar_turb_lateral: float = number(0, 1e6)


@dataclass(frozen=True)
class PlatformSection:
    """``[platform]``: the two-cable bar under the leader."""

    cable_length_m: float = number(0.01, 100)
    cable_spacing_m: float = number(0.01, 10)
    bar_length_m: float = number(0.01, 10)
    bar_diameter_m: float = number(0.0005, 1)
    bar_mass_kg: float = number(0.001, 100)
    anchor_below_leader_m: float = number(0, 10)
    yaw_damping: float = number(0, 1000)
    swing_damping: float = number(0, 1000)


@dataclass(frozen=True)
class GripperSection:
    """``[gripper]``: contact arm, strain gauge, servo gate."""

    aperture_m: float = number(0.001, 10)
    gate_height_m: float = number(0.001, 10)
    mount_height_m: float = number(0, 10)
    sensor_rate_hz: float = number(1, 20000)
    sensor_noise_n: float = number(0, 1000)
    sensor_bias_sd_n: float = number(0, 1000)
    calibration_samples: int = integer(1, 100000)
    contact_threshold_n: float = number(0.0001, 10000)
    contact_stiffness_npm: float = number(1, 1e7)
    contact_damping_nspm: float = number(0, 1e5)
    latency_s: float = number(0, 10)
    close_time_s: float = number(0.001, 10)
    trigger: str = choice("active", "both", "passive")
    servo_feedback: bool = flag()


@dataclass(frozen=True)
class ControlSection:
    """``[control]``: LQR weights, observers and compensation."""

    q_diag: list[float] = numbers(7, 0, 1e6)
    r_diag: list[float] = numbers(4, 1e-06, 1e6)
    terminal_q_diag: list[float] = numbers(7, 0, 1e6)
    terminal_r_diag: list[float] = numbers(4, 1e-06, 1e6)
    bias_estimator: str = choice("freyja", "time-constant")
    observer_bias_tau_s: float = number(0.01, 1e4)
    observer_pos_noise_m: float = number(0, 10)
    observer_vel_noise_mps: float = number(0, 100)
    observer_accel_noise_mps2: float = number(1e-6, 1e4)
    freyja_estimator_rate_hz: float = number(0.5, 1000)
    freyja_estimator_coeffs: list[float] = numbers(5, 1e-6, 1e4)
    freyja_estimator_input: str = choice("command", "command-without-feedforward")
    state_filter: str = choice("freyja", "none")
    freyja_state_filter_rate_hz: float = number(1, 10000)
    freyja_state_filter_params: list[float] = numbers(4, 1e-9, 1e4)
    command_rate_hz: float = number(1, 20000)
    reference_ff_factor: float = number(0, 1)
    rejection: str = choice("accelerometer", "bias-observer")
    accel_observer_tau_s: float = number(0.001, 100)
    accel_observer_axes: str = choice("all", "down")
    torque_feedforward: bool = flag()
    yaw_rate_max_radps: float = number(0.01, 100)


@dataclass(frozen=True)
class PlannerSection:
    """``[planner]``: the approach trajectory."""

    horizon_hover_s: float = number(0.1, 600)
    horizon_moving_s: float = number(0.1, 600)
    hold_s: float = number(0, 600)
    replan_threshold_m: float = number(0.0001, 100)
    rise_m: float = number(0, 10)
    rise_s: float = number(0.05, 60)


@dataclass(frozen=True)
class MissionSection:
    """``[mission]``: the docking mission's geometry, timing and safety limits."""

    start_radius_m: float = number(0.01, 100)
    start_below_m: float = number(0, 100)
    start_jitter_m: float = number(0, 10)
    dock_window_s: float = number(0.01, 600)
    leader_lost_s: float = number(0.01, 600)
    abort_tracking_m: float = number(0.001, 100)
    clearance_m: float = number(0, 10)
    post_dock_thrust_fraction: float = number(0, 1)
    leader_altitude_m: float = number(0.1, 1e4)
    insertion_m: float = number(0, 1)
    terminal_s: float = number(0, 600)
    active_trigger_delay_s: float = number(0, 600)
    post_dock_s: float = number(0, 600)
    gate_state_from: str = choice("sensors", "truth")
    dock_confirm_s: float = number(0.01, 10)
    dock_drop_m: float = number(0.001, 1)
    backoff_s: float = number(0.1, 600)
    backoff_distance_m: float = number(0, 100)
    settle_s: float = number(0, 600)
    leader_ramp_s: float = number(0, 600)
    status_delay_s: float = number(0, 10)


@dataclass(frozen=True)
class CurriculumSection:
    """``[curriculum]``: simulated data collection, stage by stage."""

    stage0_depth_m: list[float] = numbers(2, 0.05, 100)
    stage_step_m: float = number(0.01, 100)
    min_depth_m: float = number(0.05, 100)
    deep_depths_m: list[float] = number_list(10, 0.05, 100)
    deep_flights_per_stage: int = integer(1, 1000)
    flights_per_stage: int = integer(1, 1000)
    free_air_m: float = number(0.01, 100)
    leader_drift_max_mps: float = number(0, 100)
    drift_fraction: float = number(0, 1)
    model: str = choice(*trained_kinds())  # the registry's kinds with a network
    label_basis: str = choice("command", "thrust")


LEADER_FIXED_KEYS = frozenset({"model"})
"""``[vehicle]`` keys a ``[leader]`` table may not override (both vehicles are one model)."""

SECTIONS: dict[str, type] = {
    "vehicle": VehicleSection, "autopilot": AutopilotSection, "imu": ImuSection,
    "mocap": MocapSection, "sim": SimSection, "downwash": DownwashSection,
    "platform": PlatformSection, "gripper": GripperSection, "control": ControlSection,
    "planner": PlannerSection, "mission": MissionSection, "curriculum": CurriculumSection,
}
"""Each TOML table and the section type that holds it, in the order of defaults.toml. The
``[leader]`` table is not among them: it holds ``[vehicle]`` keys (checked by their rules) where
the leader differs from the follower, and reads as a ``VehicleSection`` (``Config.leader``)."""


def _rules() -> dict[str, Rule]:
    out: dict[str, Rule] = {}
    for name, cls in SECTIONS.items():
        for f in fields(cls):
            out[f"{name}.{f.name}"] = f.metadata["rule"]
    for f in fields(JetParams):
        out[f"downwash.params.{f.name}"] = f.metadata["rule"]
    return out


RULES: dict[str, Rule] = _rules()
"""Each key's rule by dotted name (``"vehicle.mass_kg"``, ``"downwash.params.spread_rate"``)."""
