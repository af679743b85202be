"""The paper's state filter as its flight stack publishes it (Freyja's ``state_manager``).

Freyja (unl-nimbus-lab/Freyja, branch ``ros2-devel``, e.g. commit 762ee2b of 2023-10-05; the
filter since aa8913a of 2023-06-05) does not pass motion capture's velocity on: its state manager
runs a Kalman filter over ``[p, v, a]`` per axis (``state_estimator.cpp``, ``filter_type:
kalman`` in ``freyja_flight.launch.yaml``) and publishes its position and velocity, which the
LQR controller and the bias estimator read:

- **propagation** on its own thread at 200 Hz: ``x <- A x``, ``P <- A P A' + Q`` with
  ``A = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]]`` and ``Q = diag(0.0051, 0.0147, 6.3836)`` added
  once per propagation (``kf_params`` after the measurement noise); no control input;
- **measurement update** at every motion-capture message (``tf_rate`` 100 Hz) on the position
  alone, ``R = 0.0594``; the state is published right after.

``P`` starts at ``10 I``. As the timing is every trial's and axis's, one 3x3 covariance serves the
batch. With these numbers the velocity lags a 1-2 Hz motion by about 0.1 s and overshoots a
ramp by about a quarter: part of what the paper's controller flies.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from aerodock.config.schema import ControlSection
from aerodock.control.command_kernel import rows3
from aerodock.control.covariance_memo import CovarianceMemo
from aerodock.control.estimator_kernels import packed, state_filter_rows


@dataclass(frozen=True)
class FreyjaStateFilterParams:
    """The state filter's constants (defaults: Freyja's source and flight launch file)."""

    propagation_rate_hz: float = 200.0
    measurement_noise: float = 0.0594  # R on p
    process_noise: tuple[float, float, float] = (0.0051, 0.0147, 6.3836)  # Q on p, v, a
    initial_cov: float = 10.0

    @classmethod
    def from_control(cls, control: ControlSection) -> FreyjaStateFilterParams:
        """The constants a ``[control]`` section sets (``freyja_state_filter_rate_hz``,
        ``freyja_state_filter_params``: R on p, then Q on p, v, a)."""
        r_p, q_p, q_v, q_a = control.freyja_state_filter_params
        return cls(propagation_rate_hz=control.freyja_state_filter_rate_hz, measurement_noise=r_p,
                   process_noise=(q_p, q_v, q_a))


class FreyjaStateFilter:
    """A batch of Freyja's state filters: :meth:`measure` at every motion-capture message.

    Args:
        n: trials.
        measure_dt_s: period of the motion-capture messages, s.
        params: the filter's constants.
    """

    def __init__(self, n: int, measure_dt_s: float,
                 params: FreyjaStateFilterParams | None = None) -> None:
        self.n = int(n)
        self.params = params or FreyjaStateFilterParams()
        self.measure_dt_s = float(measure_dt_s)
        self.prop_dt_s = 1.0 / self.params.propagation_rate_hz
        dt = self.prop_dt_s
        self._a = np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        self._q = np.diag(self.params.process_noise)
        self._covs = CovarianceMemo("freyja-state-filter", self._a, self._q,
                                    self.params.measurement_noise)
        self._consts = packed(self._a[0, 1], self._a[0, 2], self._a[1, 2])  # SF_* layout
        self.state = np.zeros((self.n, 3, 3))
        self.cov = self.params.initial_cov * np.eye(3)
        self._t_to_propagation_s = self.prop_dt_s

    def reset(self, p: np.ndarray, v: np.ndarray) -> None:
        """Start at a measured state (the filter has run long before the mission)."""
        self.state = np.zeros((self.n, 3, 3))
        self.state[:, :, 0] = p
        self.state[:, :, 1] = v
        self.cov = self.params.initial_cov * np.eye(3)
        self._t_to_propagation_s = self.prop_dt_s

    def take_rows(self, rows: np.ndarray) -> FreyjaStateFilter:
        """The filters of the trials at ``rows`` (their states copied; the shared covariance and
        clock as they stand)."""
        out = copy.copy(self)
        out.n = len(rows)
        out.state = self.state[rows]
        return out

    def measure(self, p_meas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One motion-capture position (n, 3): the propagations due, the update (the states
        changed in place); returns the published (position, velocity), each (n, 3)."""
        propagations, gain = self._clock()
        state_filter_rows(self.state, self._consts, propagations, gain, rows3(p_meas, self.n))
        return self.state[..., 0].copy(), self.state[..., 1].copy()

    def _tick_args(self) -> tuple:
        """The compiled step's arguments for this filter on a message (``has_filter`` to
        ``filter_state`` of :func:`aerodock.control.controller_kernel.control_tick`): the clock
        and covariance advanced (:meth:`_clock`), its states (its constants are in the
        controller's)."""
        propagations, gain = self._clock()
        return True, propagations, gain, self.state

    def _clock(self) -> tuple[int, np.ndarray]:
        """One message's share of the batch: the clock and the covariance advanced; the
        propagations due and the update's gain (3,). The states are left to
        :func:`~aerodock.control.estimator_kernels.state_filter_rows`."""
        self._t_to_propagation_s -= self.measure_dt_s
        propagations = 0
        while self._t_to_propagation_s <= 1e-9:
            (self.cov,) = self._covs.step("propagate", self.cov, self._propagated_cov)
            self._t_to_propagation_s += self.prop_dt_s
            propagations += 1
        gain, self.cov = self._covs.step("update", self.cov, self._updated_cov)  # gain (3,)
        return propagations, gain

    def _propagated_cov(self, cov: np.ndarray) -> tuple[np.ndarray]:
        """(P after one propagation,) (shared by the batch; see :class:`CovarianceMemo`)."""
        a = self._a
        return (a @ cov @ a.T + self._q,)

    def _updated_cov(self, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the update's gain (3,), P after it) on the position alone."""
        gain = cov[:, 0] / (cov[0, 0] + self.params.measurement_noise)
        return gain, cov - np.outer(gain, cov[0])
