"""The position controller's step, compiled: one call per state message.

:meth:`aerodock.control.controller.PositionController.step` hands :func:`control_tick` every
per-trial array it and its estimators hold, and the numbers the batch shares (Kalman gains,
clocks, the ramp-in) that the estimators' Python side worked out for this message. Without
``commanding`` (a message between the controller's own ticks) it runs the state filter and the
bias estimator, nothing else: the last command holds. With it (a tick of the controller), the
same, then the accelerometer observer, the command
(:func:`aerodock.control.command_kernel.position_command`: the LQR, the inversion map, the
forward map, the limits), then what the estimators are told of it (Freyja's input, the bias
observer's applied acceleration, the accelerometer observer's motor model).

Each part is the one implementation in :mod:`aerodock.control.estimator_kernels` or
:mod:`aerodock.control.command_kernel`, called in the order the step always ran them, so the
numbers are the ones the separate calls gave, to the bit. A part the controller does not fly (or
does not run this message) is switched off by its flag and reads a placeholder (:data:`NO_STATE`
and its kin: arrays of the real ones' types), so every configuration and both kinds of message
run the one compiled variant.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.control.command_kernel import body_z_axis, position_command
from aerodock.control.estimator_kernels import (
    AO_CONSTS,
    BIAS_CONSTS,
    FY_CONSTS,
    SF_CONSTS,
    accel_commanded_rows,
    accel_update_rows,
    bias_observer_rows,
    freyja_measure_rows,
    state_filter_rows,
)
from aerodock.jit import njit

NO_ESTIMATOR, BIAS_OBSERVER, FREYJA = 0, 1, 2
"""The bias estimator a controller flies (``kind``)."""

# A controller's constants, one read-only block (:func:`controller_constants`): the LQR gains
# (nominal, terminal: (2, 4, 7)), the vehicle's mass and thrust limit, gravity, the tilt limit's
# tangent, the yaw-rate limit, the reference acceleration's share, then the state filter's, the
# bias estimator's and the accelerometer observer's constants (their ``*_CONSTS`` layouts).
K_GAINS = 0
K_MASS, K_THRUST_MAX, K_GRAVITY, K_TAN_TILT, K_YAW_RATE_MAX, K_REF_FF = 56, 57, 58, 59, 60, 61
K_FILTER = 62
K_ESTIMATOR = K_FILTER + SF_CONSTS
K_ACCEL = K_ESTIMATOR + max(BIAS_CONSTS, FY_CONSTS)
K_SIZE = K_ACCEL + AO_CONSTS

# Placeholders for what a controller does not have, of the types of the real arrays: per-trial
# memory writable (the kernels never touch a placeholder: its flag is off), shared gains
# read-only (as the classes hold theirs).
NO_STATE = np.zeros((0, 3, 3))
NO_ROWS3 = np.zeros((0, 3))
NO_ROWS = np.zeros(0)
NO_MASK = np.zeros(0, dtype=np.bool_)
NO_GAIN_P = np.zeros(3)  # a state filter's gain (position only)
NO_GAIN_PV = np.zeros((3, 2))  # an estimator's gain (position and velocity)
for _placeholder in (NO_GAIN_P, NO_GAIN_PV):
    _placeholder.flags.writeable = False


def controller_constants(gains: np.ndarray, mass_kg: float, thrust_max_n: float,
                         gravity_mps2: float, tan_tilt: float, yaw_rate_max_radps: float,
                         reference_ff_factor: float, filter_consts: np.ndarray | None,
                         estimator_consts: np.ndarray | None,
                         accel_consts: np.ndarray | None) -> np.ndarray:
    """A controller's constants as :func:`control_tick` reads them (the ``K_*`` layout; a part
    the controller does not fly left zero), read-only."""
    out = np.zeros(K_SIZE)
    out[K_GAINS:K_MASS] = np.asarray(gains, dtype=float).reshape(-1)
    out[K_MASS:K_FILTER] = (mass_kg, thrust_max_n, gravity_mps2, tan_tilt, yaw_rate_max_radps,
                            reference_ff_factor)
    for start, part in ((K_FILTER, filter_consts), (K_ESTIMATOR, estimator_consts),
                        (K_ACCEL, accel_consts)):
        if part is not None:
            out[start:start + part.size] = part
    out.flags.writeable = False
    return out


@njit
def _check_rows(rows: np.ndarray, n: int) -> None:
    """Raise unless ``rows`` holds ``n`` trials (the kernels read rows 0 to n - 1 unchecked)."""
    if rows.shape[0] != n:
        raise ValueError("an input of the controller's step does not hold one row per trial")


@njit
def _estimate(constants: np.ndarray, has_filter: bool, filter_propagations: int,
              filter_gain: np.ndarray, filter_state: np.ndarray, kind: int,
              est_propagations: int, est_clear: bool, est_gain: np.ndarray,
              est_state: np.ndarray, est_input: np.ndarray, has_last: bool,
              last_input: np.ndarray, p_meas: np.ndarray,
              v_meas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state filter (when ``has_filter``) and the bias estimator (``kind``) on one message;
    the position and velocity the controller flies, each (n, 3)."""
    filter_consts = constants[K_FILTER:K_ESTIMATOR]
    est_consts = constants[K_ESTIMATOR:K_ACCEL]
    n = p_meas.shape[0]
    _check_rows(v_meas, n)
    p_used, v_used = p_meas, v_meas
    if has_filter:  # what the state manager publishes
        _check_rows(filter_state, n)
        state_filter_rows(filter_state, filter_consts, filter_propagations, filter_gain, p_meas)
        p_used, v_used = np.empty((n, 3)), np.empty((n, 3))
        for i in range(n):
            for c in range(3):
                p_used[i, c] = filter_state[i, c, 0]
                v_used[i, c] = filter_state[i, c, 1]
    if kind != NO_ESTIMATOR:
        _check_rows(est_state, n)
    if kind == FREYJA:
        _check_rows(est_input, n)
        freyja_measure_rows(est_state, est_input, est_consts, est_propagations, est_clear,
                            est_gain, p_used, v_used)
    elif kind == BIAS_OBSERVER and has_last:
        _check_rows(last_input, n)
        bias_observer_rows(est_state, est_consts, est_gain, p_used, v_used, last_input)
    return p_used, v_used


@njit
def control_tick(
        # a tick of the controller's own (else a message in between: the estimators only)
        commanding: bool,
        # the controller's constants (the K_* layout), NumPy's loops (aerodock.jit)
        constants: np.ndarray, loops: np.ndarray,
        # the state filter: on, this message's propagations and gain, its state
        has_filter: bool, filter_propagations: int, filter_gain: np.ndarray,
        filter_state: np.ndarray,
        # the bias estimator: its kind, as the filter's, Freyja's input and ramp-in
        kind: int, est_propagations: int, est_clear: bool, est_gain: np.ndarray,
        est_state: np.ndarray, est_input: np.ndarray, ramp: float,
        # the acceleration applied over the last period (the bias observer's input), the
        # measurements
        has_last: bool, last_input: np.ndarray, p_meas: np.ndarray, v_meas: np.ndarray,
        # Freyja is told the feed-forward as part of the command
        input_adds_ff: bool,
        # the accelerometer observer: whether live, its memory, the reading
        has_accel: bool, accel_live: bool, accel_has_start: bool, residual_mps2: np.ndarray,
        thrust_state_n: np.ndarray, thrust_mean_n: np.ndarray, accel_ff_mps2: np.ndarray,
        accel_mps2: np.ndarray, hold: np.ndarray, has_hold: bool,
        # the attitude measured, the reference, the gains' schedule, the feed-forward
        rpy_meas: np.ndarray, ref_pos: np.ndarray, ref_vel: np.ndarray, ref_accel: np.ndarray,
        ref_yaw: np.ndarray, ref_yaw_rate: np.ndarray, terminal: np.ndarray,
        has_terminal: bool, ff: np.ndarray, has_ff: bool,
        # out: the command, the acceleration it applies, whether a limit cut it, the bias
        # subtracted
        roll: np.ndarray, pitch: np.ndarray, thrust: np.ndarray, yaw_rate: np.ndarray,
        applied: np.ndarray, saturated: np.ndarray, bias_out: np.ndarray) -> None:
    """One state message (see the module docstring): with ``commanding``, every trial's
    numbers written into ``roll`` to ``bias_out`` and the estimators' memory; without, the state
    filter and the bias estimator only (everything after ``v_meas`` is then unread)."""
    n = p_meas.shape[0]
    if commanding:
        _check_rows(rpy_meas, n)
        _check_rows(ref_pos, n)
        _check_rows(ref_vel, n)
        _check_rows(ref_accel, n)
        _check_rows(ref_yaw, n)
        _check_rows(ref_yaw_rate, n)
        _check_rows(last_input, n)
        for out1 in (roll, pitch, thrust, yaw_rate):
            _check_rows(out1, n)
        _check_rows(applied, n)
        _check_rows(saturated, n)
        _check_rows(bias_out, n)
        if has_terminal:
            _check_rows(terminal, n)
        if has_ff:
            _check_rows(ff, n)
        if has_accel:
            _check_rows(residual_mps2, n)
            _check_rows(accel_ff_mps2, n)
            _check_rows(accel_mps2, n)
            _check_rows(thrust_state_n, n)
            _check_rows(thrust_mean_n, n)
            if has_hold:
                _check_rows(hold, n)
    p_used, v_used = _estimate(constants, has_filter, filter_propagations, filter_gain,
                               filter_state, kind, est_propagations, est_clear, est_gain,
                               est_state, est_input, has_last, last_input, p_meas, v_meas)
    if not commanding:  # between the controller's ticks: the last command holds
        return
    accel_consts = constants[K_ACCEL:K_SIZE]
    if has_accel:
        if accel_live:  # the period just flown ran under a known command
            body_z = np.empty((n, 3))
            for i in range(n):
                r, p, y = rpy_meas[i, 0], rpy_meas[i, 1], rpy_meas[i, 2]
                body_z[i, 0], body_z[i, 1], body_z[i, 2] = body_z_axis(
                    math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y))
            accel_update_rows(residual_mps2, accel_consts, thrust_mean_n, accel_ff_mps2,
                              accel_mps2, body_z, hold, has_hold)
    # What the command subtracts: the bias estimate as published, plus the accelerometer's.
    for i in range(n):
        for c in range(3):
            b = 0.0
            if kind == FREYJA:
                b = ramp * est_state[i, c, 2]
            elif kind == BIAS_OBSERVER:
                b = est_state[i, c, 2]
            if has_accel:
                b = b + residual_mps2[i, c]
            bias_out[i, c] = b
    ref_ff_factor = constants[K_REF_FF]
    accel_ref = ref_accel
    if ref_ff_factor != 1.0:
        accel_ref = np.empty((n, 3))
        for i in range(n):
            for c in range(3):
                accel_ref[i, c] = ref_ff_factor * ref_accel[i, c]
    which = np.zeros(n, dtype=np.int64)
    yaw = np.empty(n)
    for i in range(n):
        if has_terminal and terminal[i]:
            which[i] = 1
        yaw[i] = rpy_meas[i, 2]
    desired = np.empty((n, 3))
    gains = constants[K_GAINS:K_MASS].reshape((2, 4, 7))
    position_command(loops, gains, which, p_used, v_used, yaw, ref_pos, ref_vel, accel_ref,
                     ref_yaw, ref_yaw_rate, bias_out, ff, has_ff, constants[K_MASS:K_THRUST_MAX],
                     constants[K_GRAVITY], constants[K_TAN_TILT],
                     constants[K_THRUST_MAX:K_GRAVITY], constants[K_YAW_RATE_MAX], desired,
                     roll, pitch, thrust, applied, yaw_rate, saturated)
    # What the estimators are told: Freyja the command (the feed-forward added back when it
    # counts as known), the bias observer the acceleration applied with the feed-forward (and
    # the accelerometer's estimate: it then takes out what the accelerometer cannot see).
    for i in range(n):
        for c in range(3):
            f = ff[i, c] if has_ff else 0.0
            if kind == FREYJA:
                est_input[i, c] = desired[i, c] + f if input_adds_ff else desired[i, c]
            u = applied[i, c] + f
            if has_accel:
                u = u + residual_mps2[i, c]
            last_input[i, c] = u
    if has_accel:
        accel_commanded_rows(thrust_state_n, thrust_mean_n, accel_ff_mps2, accel_consts,
                             accel_has_start, thrust, ff, has_ff)
