"""The position controller both vehicles fly: LQR + reference feed-forward + compensation +
inversion map, batch-first (one call computes the commands of N trials).

``u = -K (x - x_ref) + [a_ref, psi_dot_ref]``, then ``u_1:3 -= b_hat`` (bias observer, if on),
``u_1:3 -= f_ext_hat`` (feed-forward predictor, if any) and, with ``control.rejection =
"accelerometer"``, ``u_1:3 -= r_hat`` (the accelerometer observer's estimate of what the
feed-forward leaves, :mod:`aerodock.control.accel_observer`), then the inversion map to roll,
pitch and thrust with tilt and thrust saturation. Per-trial gain scheduling: ``terminal`` selects
the stiffer terminal weights for the trials that are in their terminal phase.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from aerodock.config import Config
from aerodock.config.schema import VehicleSection
from aerodock.control import controller_kernel
from aerodock.control.accel_observer import AccelObserver
from aerodock.control.command_kernel import mask_rows, per_trial, rows1, rows3, tilt_tangent
from aerodock.control.controller_kernel import (
    NO_ESTIMATOR,
    NO_GAIN_P,
    NO_GAIN_PV,
    NO_MASK,
    NO_ROWS,
    NO_ROWS3,
    NO_STATE,
    controller_constants,
)
from aerodock.control.freyja_estimator import FreyjaBiasEstimator, FreyjaEstimatorParams
from aerodock.control.freyja_state_filter import FreyjaStateFilter, FreyjaStateFilterParams
from aerodock.control.lqr import lqr_gain
from aerodock.control.observer import BiasObserver
from aerodock.downwash.base import frozen_record
from aerodock.jit import NUMPY_LOOPS
from aerodock.rows import take_rows
from aerodock.world.vehicles.point_mass import AttitudeCommand, VehicleParams

REJECTIONS = ("bias-observer", "accelerometer")


@dataclass(frozen=True)
class Reference:
    """Batch-first reference: position, velocity, acceleration (NED), yaw and yaw rate."""

    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    yaw_rad: np.ndarray
    yaw_rate_radps: np.ndarray


@dataclass(frozen=True)
class ControlOutput:
    """One control step's result."""

    command: AttitudeCommand
    applied_accel_mps2: np.ndarray  # (n, 3) u_1:3 actually sent (after saturation): the log's cmd
    feedforward_mps2: np.ndarray  # (n, 3) f_ext_hat subtracted (zeros without a predictor)
    bias_mps2: np.ndarray  # (n, 3) b_hat (+ r_hat) subtracted (zeros without an observer)
    saturated: np.ndarray  # (n,) bool: the tilt or thrust limit cut the desired acceleration


class PositionController:
    """LQR position controller with optional bias observer, for N trials.

    Args:
        cfg: configuration (``[control]`` weights, ``[vehicle]`` limits).
        n: number of trials.
        use_observer: run and subtract the bias observer, and with ``control.rejection =
            "accelerometer"`` the accelerometer observer too (:meth:`step` then needs the
            accelerometer's reading).
        has_accelerometer: the caller passes this vehicle's accelerometer to :meth:`step` (the
            follower: the simulated world models its IMU); without it the rejection is the bias
            observer's alone.
        vehicle: the vehicle it flies (default ``[vehicle]``; ``cfg.leader`` for the leader):
            its nominal mass, limits and motor lag are all the controller knows of it.
    """

    def __init__(self, cfg: Config, n: int, use_observer: bool, has_accelerometer: bool = False,
                 vehicle: VehicleSection | None = None):
        c = cfg.control
        vehicle = cfg.vehicle if vehicle is None else vehicle
        self.params = VehicleParams.from_config(cfg, vehicle)
        self.n = n
        self.gain = lqr_gain(c.q_diag, c.r_diag)
        self.gain_terminal = lqr_gain(c.terminal_q_diag, c.terminal_r_diag)
        self.yaw_rate_max = float(c.yaw_rate_max_radps)
        self.dt_s = cfg.timing.control_dt_s
        self.observer: BiasObserver | FreyjaBiasEstimator | None = None
        if use_observer and c.bias_estimator == "freyja":
            self.observer = FreyjaBiasEstimator(n, self.dt_s,
                                                FreyjaEstimatorParams.from_control(c))
        elif use_observer:
            self.observer = BiasObserver(n, self.dt_s, c.observer_bias_tau_s,
                                         c.observer_pos_noise_m, c.observer_vel_noise_mps,
                                         c.observer_accel_noise_mps2)
        # Freyja hands its estimator the command: by default the learnt feed-forward counted as
        # known (the estimator sees what the model left); with freyja_estimator_input =
        # "command", the whole command (see docs/control.md).
        self.estimator_input_without_ff = (
            c.freyja_estimator_input == "command-without-feedforward")
        # Freyja's state manager filters motion capture's position into position and velocity.
        self.state_filter = None
        if c.state_filter == "freyja":
            self.state_filter = FreyjaStateFilter(n, self.dt_s,
                                                  FreyjaStateFilterParams.from_control(c))
        # The controller's own rate: a new command every hold_ticks state messages (held in
        # between, as Freyja's timer does); the reference acceleration's share fed forward.
        self.hold_ticks = cfg.timing.command_ticks
        self.reference_ff_factor = float(c.reference_ff_factor)
        self._tick = 0
        self._held: ControlOutput | None = None
        self.accel_observer = None
        if use_observer and has_accelerometer and c.rejection == "accelerometer":
            v = vehicle
            motor_tau = v.motor_tau_s if v.model == "rigid-body" else v.tau_thrust_s
            self.accel_observer = AccelObserver(n, self.dt_s, c.accel_observer_tau_s, motor_tau,
                                                self.params.mass_kg, self.params.gravity_mps2,
                                                c.accel_observer_axes)
        self._last_input = None  # what the observer should see as the applied acceleration
        # What the compiled step reads: the gains (nominal, terminal), the limits, the
        # estimators' constants (the vehicle's mass and thrust limit: one for every trial).
        p = self.params
        self._constants = controller_constants(
            np.stack([self.gain, self.gain_terminal]), per_trial(p.mass_kg, 1)[0],
            per_trial(p.thrust_max_n, 1)[0], p.gravity_mps2, tilt_tangent(p.tilt_max_rad),
            self.yaw_rate_max, self.reference_ff_factor,
            *(None if part is None else part._consts
              for part in (self.state_filter, self.observer, self.accel_observer)))

    def take_rows(self, rows: np.ndarray) -> PositionController:
        """The controllers of the trials at ``rows``, each where it stands (its estimators, its
        last input and held command copied; the gains shared)."""
        out = copy.copy(self)
        out.n = len(rows)
        for name in ("observer", "state_filter", "accel_observer", "_last_input", "_held"):
            setattr(out, name, take_rows(getattr(self, name), rows))
        return out

    @property
    def uses_accelerometer(self) -> bool:
        """Whether :meth:`step` needs ``accel_mps2`` (the accelerometer observer is on)."""
        return self.accel_observer is not None

    def reset(self, p: np.ndarray, v: np.ndarray, bias_mps2: np.ndarray | None = None,
              bias_sd_mps2: float | None = None) -> None:
        """Start from measured states (n, 3), optionally with a bias guess and its uncertainty
        (see :meth:`aerodock.control.observer.BiasObserver.reset`)."""
        if self.state_filter is not None:
            self.state_filter.reset(p, v)
        if isinstance(self.observer, FreyjaBiasEstimator):
            self.observer.reset(p, v)  # Freyja's own prior (it takes no bias guess)
        elif self.observer is not None:
            self.observer.reset(p, v, bias_mps2, bias_sd_mps2)
        if self.accel_observer is not None:
            self.accel_observer.reset(self.params.hover_thrust_n)
        self._last_input = None
        self._tick = 0
        self._held = None

    def step(self, p_meas: np.ndarray, v_meas: np.ndarray, rpy_meas: np.ndarray,
             ref: Reference, terminal: np.ndarray | None = None,
             feedforward_mps2: np.ndarray | None = None,
             accel_mps2: np.ndarray | None = None,
             hold_accel_observer: np.ndarray | None = None) -> ControlOutput:
        """Commands for N trials from measured state and reference.

        One compiled call (:mod:`aerodock.control.controller_kernel`) runs the state filter, the
        bias estimator and, at the controller's own ticks, the accelerometer observer and the
        command; what the batch shares (gains, covariances, clocks) the estimators work out here.

        Args:
            p_meas, v_meas: (n, 3) measured position and velocity.
            rpy_meas: (n, 3) measured attitude (yaw used).
            ref: the reference.
            terminal: (n,) bool, trials using the terminal gains.
            feedforward_mps2: (n, 3) predicted external acceleration to cancel.
            accel_mps2: (n, 3) the accelerometer's mean reading over the period just flown
                (world NED, :meth:`aerodock.world.world.World.observed_accel`); needed when
                :attr:`uses_accelerometer`.
            hold_accel_observer: (n,) bool, trials whose accelerometer estimate is held (in
                contact with the bar).
        """
        n = self.n
        p_meas, v_meas = rows3(p_meas, n), rows3(v_meas, n)
        sf, est = self.state_filter, self.observer
        filter_args = _NO_FILTER if sf is None else sf._tick_args()
        last = self._last_input
        has_last = last is not None
        est_args = _NO_ESTIMATOR if est is None else est._tick_args(has_last)
        self._tick += 1
        if self._held is not None and (self._tick - 1) % self.hold_ticks:
            # between the controller's own ticks: the estimators only, the last command holds
            controller_kernel.control_tick(False, self._constants, NUMPY_LOOPS, *filter_args,
                                           *est_args, has_last, last if has_last else NO_ROWS3,
                                           p_meas, v_meas, *_HOLDING)
            return self._held
        acc = self.accel_observer
        if acc is None:
            accel_args = _NO_ACCEL
        elif accel_mps2 is None:
            raise ValueError("control.rejection = 'accelerometer' needs the accelerometer")
        else:
            accel_args = acc._tick_args(accel_mps2, hold_accel_observer)
        if not has_last:
            last = self._last_input = np.empty((n, 3))
        has_ff = feedforward_mps2 is not None
        has_terminal = terminal is not None
        roll, pitch, thrust, yaw_rate = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        applied, bias = np.empty((n, 3)), np.empty((n, 3))
        saturated = np.empty(n, dtype=np.bool_)
        controller_kernel.control_tick(
            True, self._constants, NUMPY_LOOPS, *filter_args, *est_args, has_last, last, p_meas,
            v_meas, self.estimator_input_without_ff, *accel_args, rows3(rpy_meas, n),
            rows3(ref.p, n), rows3(ref.v, n), rows3(ref.a, n), rows1(ref.yaw_rad, n),
            rows1(ref.yaw_rate_radps, n), mask_rows(terminal, n) if has_terminal else NO_MASK,
            has_terminal, rows3(feedforward_mps2, n) if has_ff else NO_ROWS3, has_ff, roll,
            pitch, thrust, yaw_rate, applied, saturated, bias)
        out = frozen_record(
            ControlOutput,
            command=frozen_record(AttitudeCommand, roll_rad=roll, pitch_rad=pitch,
                                  yaw_rate_radps=yaw_rate, thrust_n=thrust, torque_ff_nm=None),
            applied_accel_mps2=applied,
            feedforward_mps2=feedforward_mps2 if has_ff else np.zeros((n, 3)),
            bias_mps2=bias, saturated=saturated)
        if self.hold_ticks > 1:
            self._held = out
        return out


# What the compiled step reads for a part a controller does not fly (its flag off).
_NO_FILTER = (False, 0, NO_GAIN_P, NO_STATE)
_NO_ESTIMATOR = (NO_ESTIMATOR, 0, False, NO_GAIN_PV, NO_STATE, NO_ROWS3, 1.0)
_NO_ACCEL = (False, False, False, NO_ROWS3, NO_ROWS, NO_ROWS, NO_ROWS3, NO_ROWS3, NO_MASK, False)
# ... and everything after the measurements on a message between the controller's ticks.
_HOLDING = (False, *_NO_ACCEL, NO_ROWS3, NO_ROWS3, NO_ROWS3, NO_ROWS3, NO_ROWS, NO_ROWS, NO_MASK,
            False, NO_ROWS3, False, NO_ROWS, NO_ROWS, NO_ROWS, NO_ROWS, NO_ROWS3, NO_MASK, NO_ROWS3)
