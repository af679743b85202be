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
from aerodock.control import command_kernel
from aerodock.control.accel_observer import AccelObserver
from aerodock.control.command_kernel import per_trial, rows1, rows3, tilt_tangent
from aerodock.control.freyja_estimator import FreyjaBiasEstimator, FreyjaEstimatorParams
from aerodock.control.freyja_state_filter import FreyjaStateFilter, FreyjaStateFilterParams
from aerodock.control.lqr import lqr_gain
from aerodock.control.observer import BiasObserver
from aerodock.geometry import rpy_to_rotmat
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
        # What the compiled command reads: the gains (nominal, terminal), the limits.
        self._gains = np.ascontiguousarray(np.stack([self.gain, self.gain_terminal]))
        self._mass = per_trial(self.params.mass_kg, 1)
        self._thrust_max = per_trial(self.params.thrust_max_n, 1)
        self._tan_tilt = tilt_tangent(self.params.tilt_max_rad)
        self.yaw_rate_max = c.yaw_rate_max_radps
        self.dt_s = cfg.timing.control_dt_s
        self.observer: BiasObserver | FreyjaBiasEstimator | None = None
        if use_observer and c.bias_estimator == "freyja":
            self.observer = FreyjaBiasEstimator(n, self.dt_s,
                                                FreyjaEstimatorParams.from_control(c))
        elif use_observer:
            self.observer = BiasObserver(n, self.dt_s, c.observer_bias_tau_s,
                                         c.observer_pos_noise_m, c.observer_vel_noise_mps,
                                         c.observer_accel_noise_mps2)
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
        if self.state_filter is not None:  # what the state manager publishes
            p_meas, v_meas = self.state_filter.measure(p_meas)
        freyja = isinstance(self.observer, FreyjaBiasEstimator)
        if freyja:
            self.observer.measure(p_meas, v_meas)  # every state message
        elif self.observer is not None and self._last_input is not None:
            self.observer.update(p_meas, v_meas, self._last_input)
        self._tick += 1
        if self._held is not None and (self._tick - 1) % self.hold_ticks:
            return self._held  # between the controller's own ticks: the last command holds
        residual = None
        if self.accel_observer is not None:
            if accel_mps2 is None:
                raise ValueError("control.rejection = 'accelerometer' needs the accelerometer")
            self.accel_observer.update(accel_mps2, rpy_to_rotmat(rpy_meas), hold_accel_observer)
            residual = self.accel_observer.residual_mps2
        ref_a = ref.a if self.reference_ff_factor == 1.0 else self.reference_ff_factor * ref.a
        bias = self.observer.bias_mps2 if self.observer is not None else np.zeros((n, 3))
        if residual is not None:
            bias = bias + residual
        ff = np.zeros((n, 3)) if feedforward_mps2 is None else feedforward_mps2
        which = (np.zeros(n, dtype=np.int64) if terminal is None
                 else np.asarray(terminal, dtype=np.int64))
        p = self.params
        desired, applied = np.empty((n, 3)), np.empty((n, 3))
        roll, pitch, thrust, yaw_rate = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        saturated = np.empty(n, dtype=np.bool_)
        command_kernel.position_command(
            NUMPY_LOOPS, self._gains, which, rows3(p_meas, n), rows3(v_meas, n),
            rows1(rpy_meas[:, 2], n), rows3(ref.p, n), rows3(ref.v, n), rows3(ref_a, n),
            rows1(ref.yaw_rad, n), rows1(ref.yaw_rate_radps, n), rows3(bias, n), rows3(ff, n),
            feedforward_mps2 is not None, self._mass, p.gravity_mps2, self._tan_tilt,
            self._thrust_max, self.yaw_rate_max, desired, roll, pitch, thrust, applied, yaw_rate,
            saturated)
        if freyja:  # Freyja hands its estimator the command: by default the learnt
            # feed-forward is counted as known (the estimator sees what the model left); with
            # freyja_estimator_input = "command", the whole command (see docs/control.md)
            self.observer.set_input(desired + ff if self.estimator_input_without_ff else desired)
        # The observer models v' = u + b with the feed-forward part known: b -> f_ext - f_ext_hat
        # (and - r_hat: the bias observer then takes out what the accelerometer cannot see).
        self._last_input = applied + ff if residual is None else applied + ff + residual
        if self.accel_observer is not None:
            self.accel_observer.commanded(thrust, ff)
        out = ControlOutput(AttitudeCommand(roll, pitch, yaw_rate, thrust), applied, ff, bias,
                            saturated)
        if self.hold_ticks > 1:
            self._held = out
        return out
