"""The flight stacks' attitude controllers, their published parameters bound to a vehicle in SI.

``[autopilot] stack`` chooses the autopilot a rigid-body vehicle flies:

- ``generic``: attitude P -> rate PI in angular accelerations times the inertia
  (:mod:`aerodock.world.vehicles.autopilot`; gains chosen, not identified: the world of the
  results before issue 39).
- ``arducopter``: ArduCopter's attitude controller, the paper's vehicles' firmware (the paper:
  "a slightly customized ArduCopter firmware"): ``AC_AttitudeControl`` input shaping
  (``ATC_INPUT_TC``, ``ATC_ACCEL_*_MAX``), the angle loop's square-root controller
  (``ATC_ANG_*_P``), and ``AC_PID``'s rate loop (``ATC_RAT_*``: P, I with ``IMAX``, D on the
  filtered error, ``FLTT``/``FLTE``/``FLTD``). Its output, a mixer command of -1..1, is torque
  through the vehicle: ``sqrt(2) L T_max`` (roll, pitch; QUAD X's factors of 0.5 over four
  motors at ``L / sqrt(2)``) and ``2 Q_max`` (yaw), ``T_max`` the rotor's maximum thrust,
  ``Q_max`` its reaction torque there. Defaults: ArduPilot master ``90700977`` (4.7.0-dev,
  2025-05-02; identical at the Copter-4.5 and 4.6 branch points),
  ``libraries/AC_AttitudeControl/AC_AttitudeControl_Multi.h:10-39``,
  ``AC_AttitudeControl.h:16-24``, ``AC_AttitudeControl.cpp:15,153``.
- ``crazyflie-pid``: the Crazyflie firmware's stock PID controller (bitcraze
  crazyflie-firmware ``2a18fc29``, ``src/platform/interface/platform_defaults_cf2.h:96-130``;
  the same gains at tag 2019.09, ``pid.h:33-61``): attitude PI (deg -> deg/s) and rate PID
  (deg/s -> motor command units, D on the gyro), output saturated at 32767; a command unit is
  ``THRUST_MAX / 65535`` N on a motor (``motors.c:198``), the legacy mixer halves roll and pitch
  (``power_distribution_quadrotor.c:86-92``).
- ``crazyflie-sjc``: the SJC controller the Neural-Swarm flights flew (``controller: 3`` in
  aerorobotics/neural-swarm ``hardware/neural-swarm-ros-pkg/launch/neural-swarm.launch:59``;
  the law in W. Hönig's firmware, whoenig/crazyflie-firmware ``GLAS-iros2020`` ``83efb361``,
  ``src/modules/src/controller_sjc.c:297-322``): ``w_r = lambda e`` (plus the yaw rate),
  ``tau = J_tune dw_r/dt - K (w - w_r) - K_I int(w - w_r) - K_Dw d/dt(w - w_r)``, in SI; the
  gains of the vehicle's type in neural-swarm ``crazyflieTypes.yaml``.

What each omits (small angles throughout; see docs/world.md, "The autopilots"): ArduCopter's
mixer saturation flags that freeze its integrator (here the integral is clipped at ``IMAX``
only), its tilt/heading error split (here the geometric error), its 400 Hz loop (here the
physics rate); the Crazyflie PID's yaw-angle D; the SJC law's gyroscopic term ``(J w) x w_r``.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.config.schema import STACKS
from aerodock.world.vehicles import stack_kernel

_DEG = math.pi / 180.0


def stack_constants(autopilot: object, arm_m: float, rotor_thrust_max_n: float,
                    torque_ratio_m: float) -> np.ndarray | None:
    """The compiled stack's constants (:data:`stack_kernel.CONSTANTS`, flat, read-only) for
    ``autopilot`` (an ``[autopilot]`` section) on a vehicle with motors ``arm_m`` from its
    centre, each of ``rotor_thrust_max_n`` N at most with reaction torque ``torque_ratio_m``
    N m per N; None for the generic autopilot."""
    stack = autopilot.stack
    if stack == "generic":
        return None
    rows = {name: np.zeros(3) for name in (
        "ang_p", "ang_accel", "ang_i", "ang_ilim", "rate_p", "rate_i", "rate_d", "rate_ilim",
        "fltt", "flte", "fltd", "d_on_gyro", "ref_inertia", "torque_max", "shaper_accel")}
    tc = 0.0
    mixer = 0.0  # the world's: attitude first when a rotor saturates
    a = autopilot
    if stack == "arducopter":
        full = np.array([math.sqrt(2.0) * arm_m * rotor_thrust_max_n] * 2
                        + [2.0 * torque_ratio_m * rotor_thrust_max_n])
        accel = np.asarray(a.ac_accel_max_cdss, dtype=float) / 100.0 * _DEG
        rows["ang_p"] = np.asarray(a.ac_ang_p, dtype=float)
        # the angle loop's limit: half the axis's, clipped (AC_AttitudeControl.cpp:1287-1320)
        lo_hi = np.array([[40.0, 720.0], [40.0, 720.0], [10.0, 120.0]]) * _DEG
        rows["ang_accel"] = np.clip(accel / 2.0, lo_hi[:, 0], lo_hi[:, 1])
        rat_i = np.asarray(a.ac_rat_i, dtype=float)
        rows["rate_p"] = np.asarray(a.ac_rat_p, dtype=float) * full
        rows["rate_i"] = rat_i * full
        rows["rate_d"] = np.asarray(a.ac_rat_d, dtype=float) * full
        rows["rate_ilim"] = np.where(rat_i > 0, np.asarray(a.ac_rat_imax, dtype=float)
                                     / np.maximum(rat_i, 1e-300), np.inf)
        rows["fltt"] = np.asarray(a.ac_rat_fltt_hz, dtype=float)
        rows["flte"] = np.asarray(a.ac_rat_flte_hz, dtype=float)
        rows["fltd"] = np.asarray(a.ac_rat_fltd_hz, dtype=float)
        rows["torque_max"] = full  # the mixer's full command, +-1
        rows["shaper_accel"] = accel
        tc = float(a.ac_input_tc_s)
    elif stack == "crazyflie-pid":
        unit = a.cf_thrust_max_n / 65535.0  # N on a motor per command unit
        per_unit = np.array([2.0 * arm_m / math.sqrt(2.0) * unit] * 2
                            + [4.0 * torque_ratio_m * unit])  # N m per unit of rate output
        rows["ang_p"] = np.asarray(a.cf_att_kp, dtype=float)
        rows["ang_i"] = np.asarray(a.cf_att_ki, dtype=float)
        rows["ang_ilim"] = np.asarray(a.cf_att_ilimit_deg, dtype=float) * _DEG
        rows["rate_p"] = np.asarray(a.cf_rate_kp, dtype=float) / _DEG * per_unit
        rows["rate_i"] = np.asarray(a.cf_rate_ki, dtype=float) / _DEG * per_unit
        rows["rate_d"] = np.asarray(a.cf_rate_kd, dtype=float) / _DEG * per_unit
        rows["rate_ilim"] = np.asarray(a.cf_rate_ilimit_deg, dtype=float) * _DEG
        rows["d_on_gyro"] = np.ones(3)
        rows["torque_max"] = 32767.0 * per_unit
    elif stack == "crazyflie-sjc":
        rows["ang_p"] = np.asarray(a.sjc_lambda, dtype=float)
        rows["rate_p"] = np.asarray(a.sjc_k_nms, dtype=float)
        rows["rate_i"] = np.asarray(a.sjc_ki_nm, dtype=float)
        rows["rate_ilim"] = np.asarray(a.sjc_ilimit_rad, dtype=float)
        rows["rate_d"] = np.asarray(a.sjc_kdw_nms2, dtype=float)
        rows["ref_inertia"] = np.asarray(a.sjc_jtune_kgm2, dtype=float)
        rows["torque_max"] = np.full(3, np.inf)
        mixer = 1.0  # powerDistributionForceTorque: each motor's force clipped on its own
        # (whoenig/crazyflie-firmware 83efb361, power_distribution_stock.c:126-263)
    else:
        raise ValueError(f"unknown autopilot stack {stack!r} (one of {', '.join(STACKS)})")
    flat = np.concatenate([rows[k] for k in (
        "ang_p", "ang_accel", "ang_i", "ang_ilim", "rate_p", "rate_i", "rate_d", "rate_ilim",
        "fltt", "flte", "fltd", "d_on_gyro", "ref_inertia", "torque_max", "shaper_accel")]
        + [np.array([tc, mixer])])
    assert flat.shape == (stack_kernel.CONSTANTS,)
    flat.flags.writeable = False
    return flat


def state_columns(autopilot: object) -> int:
    """Numbers of autopilot state per vehicle: the generic autopilot's rate integral (3) or the
    stack's (:data:`stack_kernel.STATE_COLUMNS`)."""
    return 3 if autopilot.stack == "generic" else stack_kernel.STATE_COLUMNS
