"""The paper's bias estimator as its flight stack publishes it (Freyja's ``bias_estimator.cpp``).

Freyja (github.com/unl-nimbus-lab/Freyja, branch ``ros2-devel`` as of the paper's flights, e.g.
commit 762ee2b of 2023-10-05; the same structure since 2019) estimates a disturbance
acceleration with a Kalman filter over ``x = [p, v, b]`` (NED, per axis), run as two loops:

- **propagation** on its own clock (``estimator_rate``: 10 Hz in the code, 20 Hz in its flight
  launch file ``freyja_flight.launch.yaml``): ``x <- A x + B (0.95 u)``, ``P <- A P A' + Q`` with
  ``A = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]]``, ``B = [dt^2/2, dt, 0]``, the process noise
  ``Q = diag(0.1, 0.2, 0.8)`` added once per propagation (not scaled by ``dt``), ``u`` the last
  control input the controller handed over (its acceleration command after the bias and
  external-force corrections, gravity excluded, before the inversion map: 95 % of it, the
  ``input_shaping``), then the bias clipped to ``+-(2, 2, 3)`` m/s² (north, east, down);
- **measurement update** at every state message (motion capture, 100 Hz in the flight launch):
  ``G = P C' (C P C' + R)^-1``, ``x <- x + G (z - C x)``, ``P <- (I - G C) P`` with ``z = [p, v]``
  and ``R = diag(0.2, 0.3)``.

``P`` starts at ``10 I`` (``1 I`` before 2023). The published estimate ramps in over 1.5 s after
the estimator is enabled (``b_out = min(1, (t / 1.5)^3) b``). Propagation stops after three
periods without a measurement. The paper states none of this: it names the LQG baseline only.

``P`` depends only on the timing, which every trial and axis share, so one 3x3 covariance serves
the batch; the estimates are ``(n, 3 axes, 3)``. With the flight launch's rates the estimate
reaches 63 % of a disturbance step in about 0.5 s and 98 % in about 2.2 s, and settles at 95 %
of it (the input shaping).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from aerodock.config.schema import ControlSection
from aerodock.control.command_kernel import rows3
from aerodock.control.controller_kernel import FREYJA
from aerodock.control.covariance_memo import CovarianceMemo
from aerodock.control.estimator_kernels import freyja_measure_rows, packed


@dataclass(frozen=True)
class FreyjaEstimatorParams:
    """Freyja's bias estimator's constants (defaults: its source and flight launch file)."""

    propagation_rate_hz: float = 20.0  # estimator_rate (flight launch; the code's default: 10)
    process_noise: tuple[float, float, float] = (0.1, 0.2, 0.8)  # Q on p, v, b per propagation
    measurement_noise: tuple[float, float] = (0.2, 0.3)  # R on p, v
    initial_cov: float = 10.0  # P0 = initial_cov * I
    input_shaping: float = 0.95
    bias_limit_mps2: tuple[float, float, float] = (2.0, 2.0, 3.0)
    output_ramp_s: float = 1.5  # estimator_tc_: the cubic ramp-in after enable
    stale_propagations: int = 3  # no propagation after this many without a measurement

    @classmethod
    def from_control(cls, control: ControlSection) -> FreyjaEstimatorParams:
        """The constants a ``[control]`` section sets (``freyja_estimator_rate_hz``,
        ``freyja_estimator_coeffs``: Q on p, v, b, then R on p, v); the others Freyja's."""
        q_p, q_v, q_b, r_p, r_v = control.freyja_estimator_coeffs
        return cls(propagation_rate_hz=control.freyja_estimator_rate_hz,
                   process_noise=(q_p, q_v, q_b), measurement_noise=(r_p, r_v))


class FreyjaBiasEstimator:
    """A batch of Freyja's bias estimators (see the module docstring).

    Call :meth:`measure` at every state message (the control loop's rate) with the measured
    position and velocity, and :meth:`set_input` whenever the controller computes a command; the
    estimator propagates on its own clock inside :meth:`measure`.

    Args:
        n: trials.
        measure_dt_s: period of the state messages, s.
        params: the estimator's constants.
    """

    def __init__(self, n: int, measure_dt_s: float,
                 params: FreyjaEstimatorParams | None = None) -> None:
        self.n = int(n)
        self.params = params or FreyjaEstimatorParams()
        self.measure_dt_s = float(measure_dt_s)
        self.prop_dt_s = 1.0 / self.params.propagation_rate_hz
        dt = self.prop_dt_s
        self._a = np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        self._b = np.array([0.5 * dt * dt, dt, 0.0])
        self._q = np.diag(self.params.process_noise)
        self._r = np.diag(self.params.measurement_noise)
        self._limit = np.asarray(self.params.bias_limit_mps2, dtype=float)
        self._covs = CovarianceMemo("freyja-estimator", self._a, self._q, self._r)
        # What the kernel reads (FY_* layout): A's entries off the diagonal, B, the shaping,
        # the limits.
        self._consts = packed(self._a[0, 1], self._a[0, 2], self._a[1, 2], self._b[:2],
                              self.params.input_shaping, self._limit)
        self.reset(np.zeros((self.n, 3)), np.zeros((self.n, 3)))

    def reset(self, p: np.ndarray, v: np.ndarray) -> None:
        """Enable the estimator at the measured state: zero bias, ``P = initial_cov I``."""
        self.state = np.zeros((self.n, 3, 3))
        self.state[:, :, 0] = p
        self.state[:, :, 1] = v
        self.cov = self.params.initial_cov * np.eye(3)
        self.input_mps2 = np.zeros((self.n, 3))
        self.t_since_enable_s = 0.0
        self._t_to_propagation_s = self.prop_dt_s  # the thread's first wake-up
        self._propagations_since_measure = 0

    def take_rows(self, rows: np.ndarray) -> FreyjaBiasEstimator:
        """The estimators of the trials at ``rows`` (their estimates and inputs copied; the
        shared covariance and clock as they stand)."""
        out = copy.copy(self)
        out.n = len(rows)
        out.state = self.state[rows]
        out.input_mps2 = self.input_mps2[rows]
        return out

    def set_input(self, accel_cmd_mps2: np.ndarray) -> None:
        """The controller's latest command (n, 3): net acceleration, gravity excluded."""
        self.input_mps2 = rows3(np.array(accel_cmd_mps2, dtype=float, copy=True), self.n)

    def measure(self, p_meas: np.ndarray, v_meas: np.ndarray) -> None:
        """One state message: the propagations due since the last one, then the update (the
        estimates and a stale input changed in place)."""
        propagations, clear, gain = self._clock()
        n = self.n
        freyja_measure_rows(self.state, self.input_mps2, self._consts, propagations, clear, gain,
                            rows3(p_meas, n), rows3(v_meas, n))

    def _tick_args(self, updating: bool = True) -> tuple:
        """The compiled step's arguments for this estimator on a state message (``kind`` to
        ``ramp`` of :func:`aerodock.control.controller_kernel.control_tick`): the clocks and
        covariance advanced (:meth:`_clock`), its estimates, input and ramp-in (it takes every
        message; ``updating`` is the bias observer's; its constants are in the controller's)."""
        propagations, clear, gain = self._clock()
        return FREYJA, propagations, clear, gain, self.state, self.input_mps2, self.ramp()

    def _clock(self) -> tuple[int, bool, np.ndarray]:
        """One state message's share of the batch: the clocks and the covariance advanced; the
        propagations due (with the input), whether the input went stale, and the update's gain
        (3, 2). The estimates are left to :func:`~aerodock.control.estimator_kernels.
        freyja_measure_rows`."""
        self.t_since_enable_s += self.measure_dt_s
        self._t_to_propagation_s -= self.measure_dt_s
        propagations, clear = 0, False
        while self._t_to_propagation_s <= 1e-9:
            self._propagations_since_measure += 1
            if self._propagations_since_measure > self.params.stale_propagations:
                clear = True  # stale input cleared, no propagation
            else:
                propagations += 1
                (self.cov,) = self._covs.step("propagate", self.cov, self._propagated_cov)
            self._t_to_propagation_s += self.prop_dt_s
        self._propagations_since_measure = 0
        gain, self.cov = self._covs.step("update", self.cov, self._updated_cov)  # gain (3, 2)
        return propagations, clear, gain

    def _propagated_cov(self, cov: np.ndarray) -> tuple[np.ndarray]:
        """(P after one propagation,) (shared by the batch; see :class:`CovarianceMemo`)."""
        a = self._a
        return (a @ cov @ a.T + self._q,)

    def _updated_cov(self, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the update's gain (3, 2), P after it) on position and velocity."""
        c = np.eye(2, 3)
        gain = cov @ c.T @ np.linalg.inv(c @ cov @ c.T + self._r)
        return gain, (np.eye(3) - gain @ c) @ cov

    def ramp(self) -> float:
        """The published estimate's share of the bias now: ``min(1, (t / ramp) ** 3)``."""
        return min(1.0, (self.t_since_enable_s / self.params.output_ramp_s) ** 3)

    @property
    def bias_mps2(self) -> np.ndarray:
        """(n, 3) the published estimate: the bias times the ramp-in factor."""
        return self.ramp() * self.state[:, :, 2]
