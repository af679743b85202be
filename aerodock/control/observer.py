"""Disturbance (bias-acceleration) observer: the paper's LQG baseline "without model".

Per axis, a discrete Kalman filter over ``[p, v, b]`` with the model::

    p' = v,   v' = u + b + w_a,   b' = w_b        (measurements: p and v, from motion capture)

where ``u`` is the acceleration actually applied, ``b`` an unknown, slowly varying disturbance
acceleration, ``w_a`` white unmodelled acceleration (spectral density ``accel_noise^2``) and
``w_b`` the bias random walk (spectral density ``sigma_b^2``). The three axes are independent
and share the same matrices, so one steady-state gain (from ``scipy.linalg.solve_discrete_are``)
serves every trial and axis; an update is a couple of small matrix products over ``(n, 3, 3)``.

Choosing the bias process noise: when the measurements pin down ``p`` and ``v`` much faster
than the bias moves, the bias estimate is the steady-state Kalman filter of a random walk seen
through white noise (the unexplained acceleration ``w_a``), which is a first-order low-pass with
time constant ``tau = accel_noise / sigma_b``. So ``sigma_b = accel_noise / bias_tau_s``; the
realised time constant (slowest eigenvalue of the error dynamics) is exposed as
:attr:`BiasObserver.bias_time_constant_s` and matches ``bias_tau_s`` to well under 1 % for the
default settings.
"""

from __future__ import annotations

import copy
import functools
import sys

import numpy as np

from aerodock.control.command_kernel import rows3
from aerodock.control.controller_kernel import BIAS_OBSERVER, NO_ROWS3
from aerodock.control.estimator_kernels import bias_observer_rows, packed


class BiasObserver:
    """Batch of steady-state Kalman filters estimating a constant-ish disturbance acceleration.

    Usage at the control rate: ``reset(p, v)`` once, then every step
    ``update(p_meas, v_meas, u_applied)`` with the acceleration that was applied over the step
    that just ended, then read :attr:`bias_mps2` and subtract it from the next command.

    Attributes:
        n: Number of trials.
        dt_s: Update period.
        gain: Steady-state Kalman gain, ``(3, 2)`` mapping ``[p, v]`` innovations to ``[p, v, b]``.
        state: Estimates ``(n, 3 axes, 3)`` as ``[p, v, b]`` per axis.
    """

    def __init__(
        self,
        n: int,
        dt_s: float,
        bias_tau_s: float,
        pos_noise_m: float,
        vel_noise_mps: float,
        accel_noise_mps2: float,
    ) -> None:
        """Build the filter and its steady-state gain.

        Args:
            n: Number of independent trials.
            dt_s: Update period (e.g. 0.01 at 100 Hz).
            bias_tau_s: Desired time constant of the bias estimate (slow by design, ~4 s).
            pos_noise_m: Position measurement noise standard deviation.
            vel_noise_mps: Velocity measurement noise standard deviation.
            accel_noise_mps2: Unmodelled white acceleration (spectral density sqrt, m/s^2
                per sqrt(Hz)); sets how much ``v`` trusts the measurement over the model. The
                bias random walk is then ``accel_noise_mps2 / bias_tau_s``.

        Raises:
            ValueError: on non-positive arguments.
        """
        for name, value in (
            ("n", n),
            ("dt_s", dt_s),
            ("bias_tau_s", bias_tau_s),
            ("pos_noise_m", pos_noise_m),
            ("vel_noise_mps", vel_noise_mps),
            ("accel_noise_mps2", accel_noise_mps2),
        ):
            if not value > 0:
                raise ValueError(f"{name} must be positive, got {value}")
        self.n = int(n)
        self.dt_s = float(dt_s)
        dt = self.dt_s
        self._f = np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        self._g = np.array([0.5 * dt * dt, dt, 0.0])
        h = np.eye(2, 3)
        bias_walk = accel_noise_mps2 / bias_tau_s
        q = np.zeros((3, 3))
        q[:2, :2] = accel_noise_mps2**2 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
        q[2, 2] = bias_walk**2 * dt
        r = np.diag([pos_noise_m**2, vel_noise_mps**2])
        p_prior = _steady_prior(self._f, h, q, r)
        self.gain = _frozen(p_prior @ h.T @ np.linalg.inv(h @ p_prior @ h.T + r))
        self._error_dyn = (np.eye(3) - self.gain @ h) @ self._f
        self._consts = packed(self._f, self._g)  # what the kernel reads (BIAS_* layout)
        self._q, self._r, self._h = q, r, h
        # The time-varying gains from a reset prior until they settle (None: the steady
        # state), and how many of them this filter has used.
        self._schedule: _GainSchedule | None = None
        self._step = 0
        self.state = np.zeros((self.n, 3, 3))

    @property
    def bias_time_constant_s(self) -> float:
        """Realised time constant of the slowest mode of the estimation error, in seconds."""
        rho = float(np.max(np.abs(np.linalg.eigvals(self._error_dyn))))
        return -self.dt_s / np.log(rho)

    def reset(self, p: np.ndarray, v: np.ndarray, bias_mps2: np.ndarray | None = None,
              bias_sd_mps2: float | None = None) -> None:
        """Restart the estimates at the given position and velocity.

        Args:
            p: Position, ``(n, 3)``.
            v: Velocity, ``(n, 3)``.
            bias_mps2: Initial bias estimate, ``(n, 3)``; zero when omitted.
            bias_sd_mps2: Uncertainty of that initial bias. Given, the filter starts from this
                prior and runs the time-varying Kalman gain (fast at first, as a real filter
                started on the ground is) until it meets the steady-state gain; omitted, the
                steady-state gain from the first update.
        """
        self._schedule, self._step = None, 0
        if bias_sd_mps2 is not None:
            prior = np.diag([self._r[0, 0], self._r[1, 1], float(bias_sd_mps2) ** 2])
            self._schedule = _GainSchedule.of(self._f, self._h, self._q, self._r, prior,
                                              self.gain)
        self.state = np.zeros((self.n, 3, 3))
        self.state[:, :, 0] = p
        self.state[:, :, 1] = v
        if bias_mps2 is not None:
            self.state[:, :, 2] = bias_mps2

    def take_rows(self, rows: np.ndarray) -> BiasObserver:
        """The filters of the trials at ``rows`` (their estimates copied; the gain and the
        shared covariance as they stand)."""
        out = copy.copy(self)
        out.n = len(rows)
        out.state = self.state[rows]
        return out

    def update(self, p_meas: np.ndarray, v_meas: np.ndarray, u_applied_mps2: np.ndarray) -> None:
        """Predict over one period with the applied acceleration, then correct with measurements.

        Args:
            p_meas: Measured position at the end of the period, ``(n, 3)``.
            v_meas: Measured velocity at the end of the period, ``(n, 3)``.
            u_applied_mps2: Net acceleration applied over the period (gravity excluded),
                ``(n, 3)``. Pass what the vehicle was actually commanded to do *after*
                saturation (e.g. the forward map of the saturated attitude and thrust), or
                the saturation will be learnt as a disturbance.

        The estimates are updated in place (:func:`~aerodock.control.estimator_kernels.
        bias_observer_rows`: explicit sums per trial, so each trial's numbers do not depend on
        the batch).
        """
        n = self.n
        bias_observer_rows(self.state, self._consts, self._next_gain(), rows3(p_meas, n),
                           rows3(v_meas, n), rows3(u_applied_mps2, n))

    def _tick_args(self, updating: bool) -> tuple:
        """The compiled step's arguments for this observer (``kind`` to ``ramp`` of
        :func:`aerodock.control.controller_kernel.control_tick`; its constants are in the
        controller's): this update's gain (the schedule advanced when ``updating``), its
        estimates."""
        gain = self._next_gain() if updating else self.gain
        return BIAS_OBSERVER, 0, False, gain, self.state, NO_ROWS3, 1.0

    def _next_gain(self) -> np.ndarray:
        """This update's Kalman gain (3, 2), read-only: time-varying from the reset prior, then
        steady-state (the schedule advances: call it once per update)."""
        if self._schedule is None:
            return self.gain
        gain = self._schedule.gain(self._step)
        self._step += 1
        if self._step >= self._schedule.settled_after:
            self._schedule = None  # settled: the steady-state gain from now on
        return gain

    @property
    def settled(self) -> bool:
        """Whether the filter runs the steady-state gain."""
        return self._schedule is None

    @property
    def bias_mps2(self) -> np.ndarray:
        """Estimated disturbance acceleration ``b``, NED, ``(n, 3)`` (subtract it from ``u``)."""
        return self.state[:, :, 2].copy()


class _GainSchedule:
    """The time-varying Kalman gains from one prior, computed once and shared: they depend on the
    filter's model and the prior only, not on the measurements, so every filter reset to the
    same prior (every trial, every campaign of a process) runs the same sequence, and it is
    computed once (the same operations in the same order: the same numbers).

    ``gain(k)`` is the k-th update's gain; ``settled_after`` the number of updates after which
    the gain has met the steady state (within 1e-4 of its largest entry), unknown (a large
    number) until then.
    """

    _cache: dict[bytes, _GainSchedule] = {}
    _MAX_CACHED = 64

    def __init__(self, f: np.ndarray, h: np.ndarray, q: np.ndarray, r: np.ndarray,
                 prior: np.ndarray, steady: np.ndarray) -> None:
        self._f, self._h, self._q, self._r, self._steady = f, h, q, r, steady
        self._cov = prior
        self._gains: list[np.ndarray] = []
        self.settled_after = sys.maxsize

    @classmethod
    def of(cls, f: np.ndarray, h: np.ndarray, q: np.ndarray, r: np.ndarray, prior: np.ndarray,
           steady: np.ndarray) -> _GainSchedule:
        """The schedule of this model and prior (shared when one was made before)."""
        key = b"".join(np.ascontiguousarray(a).tobytes() for a in (f, h, q, r, prior, steady))
        hit = cls._cache.get(key)
        if hit is None:
            if len(cls._cache) >= cls._MAX_CACHED:
                cls._cache.clear()
            hit = cls._cache[key] = cls(f, h, q, r, prior, steady)
        return hit

    def gain(self, k: int) -> np.ndarray:
        """The k-th update's gain (computed now if it is the next one)."""
        while len(self._gains) <= k:
            f, h = self._f, self._h
            prior = f @ self._cov @ f.T + self._q
            gain = _frozen(prior @ h.T @ np.linalg.inv(h @ prior @ h.T + self._r))
            self._cov = (np.eye(3) - gain @ h) @ prior
            self._gains.append(gain)
            if np.max(np.abs(gain - self._steady)) < 1e-4 * np.max(np.abs(self._steady)):
                self.settled_after = len(self._gains)
                break
        return self._gains[k]


def _steady_prior(f: np.ndarray, h: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The steady-state prior covariance ``solve_discrete_are(f.T, h.T, q, r)`` (3 x 3),
    read-only, solved once per process for the same model (a solve costs about 20 ms, and every
    controller's observer asks: the same inputs give the same numbers), as
    :func:`aerodock.control.lqr.lqr_gain` keeps its gains."""
    return _dare_prior(*(np.ascontiguousarray(a, dtype=float).tobytes() for a in (f, h, q, r)))


@functools.lru_cache(maxsize=64)
def _dare_prior(f_bytes: bytes, h_bytes: bytes, q_bytes: bytes, r_bytes: bytes) -> np.ndarray:
    """:func:`_steady_prior` keyed by its inputs' float64 bytes (shapes 3 x 3, 2 x 3, 3 x 3,
    2 x 2)."""
    import scipy.linalg  # here, not at the top: the CLI starts 0.2 s sooner

    f, h = np.frombuffer(f_bytes).reshape(3, 3), np.frombuffer(h_bytes).reshape(2, 3)
    q, r = np.frombuffer(q_bytes).reshape(3, 3), np.frombuffer(r_bytes).reshape(2, 2)
    prior = scipy.linalg.solve_discrete_are(f.T, h.T, q, r)
    prior.flags.writeable = False
    return prior


def _frozen(gain: np.ndarray) -> np.ndarray:
    """A gain as the kernels read it: contiguous and read-only (shared: nobody writes it)."""
    out = np.ascontiguousarray(gain)
    out.flags.writeable = False
    return out
