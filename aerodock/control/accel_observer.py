"""Fast disturbance rejection from the accelerometer (incremental, INDI-like), batch-first.

The bias observer (:mod:`aerodock.control.observer`) sees the disturbance only through motion
capture, twice integrated: it has to be slow (4 s in the paper) or it amplifies the position
noise and lags the vehicle's own attitude transients. The accelerometer sees the disturbance
*directly*: over one control period the vehicle's acceleration is gravity, the thrust it was
commanded (along the measured body axis) and whatever else pushes it::

    f_meas = a_meas - g + R[:, 2] * T_model / m          (NED; thrust acts along -body z)

``T_model`` is the commanded collective through the motors' first-order lag (the flight computer
knows both), averaged over the period; ``R`` is the measured attitude. Everything the commands do
not explain is in ``f_meas``: the wake, rotor drag, the vehicle's thrust scale error, the bar's
pull. As in incremental nonlinear dynamic inversion this needs no model of the disturbance, only
of the actuators.

The measurement is noisy (motor vibration on the accelerometer, ``imu.accel_vibration_mps2`` per
sample at hover, growing with the thrust), so the estimate is low-passed with time constant
``tau``. A first-order filter with ``beta = dt / (tau + dt)`` passes white noise of standard
deviation ``s`` per control period as ``s * sqrt(beta / (2 - beta))``; :func:`filtered_noise_sd`
gives it and ``DEFAULT_TAU_S`` is chosen from it (see defaults.toml, ``accel_observer_tau_s``).

With a feed-forward model the observer estimates only what the model leaves: the residual
``f_meas - f_model`` is filtered and the command subtracts ``f_model(now) + residual``, so the
model answers instantly as the vehicle moves into the wake and the accelerometer corrects the
model's error within ``tau``. The slow bias observer keeps running on top (its model input
includes this estimate) and takes out what the accelerometer cannot see: its own bias.
"""

from __future__ import annotations

import copy

import numpy as np

from aerodock.control.command_kernel import mask_rows, rows1, rows3
from aerodock.control.estimator_kernels import (
    accel_commanded_rows,
    accel_update_rows,
    packed,
)


def filtered_noise_sd(sample_sd_mps2: float, dt_s: float, tau_s: float) -> float:
    """Standard deviation of white noise (``sample_sd_mps2`` per period ``dt_s``) after the
    observer's first-order low-pass of time constant ``tau_s``."""
    beta = dt_s / (tau_s + dt_s)
    return float(sample_sd_mps2 * np.sqrt(beta / (2.0 - beta)))


class AccelObserver:
    """Batch of accelerometer-based disturbance observers (see the module docstring).

    Usage, once per control period: :meth:`update` with the accelerometer's reading over the
    period just flown and the measured attitude, then read :attr:`residual_mps2`, then
    :meth:`commanded` with the thrust and feed-forward that will be applied over the next period.

    Args:
        n: trials.
        dt_s: control period, s.
        tau_s: low-pass time constant of the estimate, s.
        motor_tau_s: first-order time constant from thrust command to thrust, s.
        mass_kg: vehicle mass.
        gravity_mps2: gravity.
        axes: ``"all"``, or ``"down"`` to estimate the vertical axis only (the horizontal
            estimates stay zero).
    """

    def __init__(self, n: int, dt_s: float, tau_s: float, motor_tau_s: float, mass_kg: float,
                 gravity_mps2: float, axes: str = "all") -> None:
        for name, value in (("n", n), ("dt_s", dt_s), ("tau_s", tau_s), ("mass_kg", mass_kg)):
            if not value > 0:
                raise ValueError(f"{name} must be positive, got {value}")
        if not motor_tau_s >= 0:
            raise ValueError(f"motor_tau_s must be >= 0, got {motor_tau_s}")
        self.n, self.dt_s, self.tau_s = int(n), float(dt_s), float(tau_s)
        self.beta = self.dt_s / (self.tau_s + self.dt_s)
        if axes not in ("all", "down"):
            raise ValueError(f"axes must be 'all' or 'down', got {axes!r}")
        self.axes = np.array([0.0, 0.0, 1.0]) if axes == "down" else np.ones(3)
        # Motor lag over one period: end value and period mean, as weights of (start, command).
        if motor_tau_s > 0:
            decay = float(np.exp(-self.dt_s / motor_tau_s))
            self._mean_start = motor_tau_s / self.dt_s * (1.0 - decay)
        else:
            decay, self._mean_start = 0.0, 0.0
        self._decay = decay
        self.mass_kg = float(mass_kg)
        # What the kernels read (AO_* layout).
        self._consts = packed(self.beta, self.mass_kg, float(gravity_mps2), decay,
                              self._mean_start, self.axes)
        self.residual_mps2 = np.zeros((self.n, 3))
        self._thrust_n: np.ndarray | None = None  # modelled thrust at the start of the period
        self._thrust_mean_n = np.zeros(self.n)  # modelled mean thrust over the period flown
        self._ff = np.zeros((self.n, 3))  # feed-forward applied over the period flown
        self._live = False

    def reset(self, thrust_n: np.ndarray | float) -> None:
        """Forget the estimate; the motors start at ``thrust_n`` (e.g. hover)."""
        self.residual_mps2 = np.zeros((self.n, 3))
        self._thrust_n = np.broadcast_to(np.asarray(thrust_n, dtype=float), (self.n,)).copy()
        self._thrust_mean_n = self._thrust_n.copy()
        self._ff = np.zeros((self.n, 3))
        self._live = False

    def take_rows(self, rows: np.ndarray) -> AccelObserver:
        """The observers of the trials at ``rows`` (their estimates and motor models copied)."""
        out = copy.copy(self)
        out.n = len(rows)
        out.residual_mps2 = self.residual_mps2[rows]
        out._thrust_n = None if self._thrust_n is None else self._thrust_n[rows]
        out._thrust_mean_n = self._thrust_mean_n[rows]
        out._ff = self._ff[rows]
        return out

    def update(self, accel_mps2: np.ndarray, R: np.ndarray,  # noqa: N803
               hold: np.ndarray | None = None) -> None:
        """Fold in the accelerometer's mean reading ``(n, 3)`` (world NED, gravity excluded as a
        kinematic acceleration) over the period just flown and the measured attitude ``(n, 3, 3)``
        (the estimates changed in place).

        What the commands do not explain is ``a - g e3 + R e3 T_mean / m - ff`` (thrust along
        the body's ``-z``, through the motor model; ``ff`` the feed-forward flown), low-passed.
        ``hold`` (n,) bool keeps those trials' estimates as they are: in contact (the gripper's
        strain gauge reads a load, or the gate is closing) the push of the bar is not a
        disturbance to cancel; chasing it would drive the arm up through the bar.
        """
        if not self._live:  # no period has been flown under a known command yet
            return
        n = self.n
        body_z = rows3(np.asarray(R, dtype=float)[:, :, 2], n)
        has_hold = hold is not None
        accel_update_rows(self.residual_mps2, self._consts, self._thrust_mean_n, self._ff,
                          rows3(accel_mps2, n), body_z,
                          mask_rows(hold, n) if has_hold else _NO_HOLD, has_hold)

    def commanded(self, thrust_n: np.ndarray, feedforward_mps2: np.ndarray) -> None:
        """The collective thrust ``(n,)`` and the model's feed-forward ``(n, 3)`` that the next
        period flies with (advances the motor model)."""
        has_start = self._prepare_command()
        accel_commanded_rows(self._thrust_n, self._thrust_mean_n, self._ff, self._consts,
                             has_start, rows1(thrust_n, self.n),
                             rows3(feedforward_mps2, self.n), True)
        self._live = True

    def _tick_args(self, accel_mps2: np.ndarray, hold: np.ndarray | None) -> tuple:
        """The compiled step's arguments for this observer at a tick of the controller
        (``has_accel`` to ``has_hold`` of
        :func:`aerodock.control.controller_kernel.control_tick`, which runs :meth:`update` with
        the attitude measured and then :meth:`commanded` with its command; its constants are in
        the controller's)."""
        n, live = self.n, self._live
        has_start = self._prepare_command()
        self._live = True  # the command the kernel hands the motor model
        has_hold = hold is not None
        return (True, live, has_start, self.residual_mps2, self._thrust_n,
                self._thrust_mean_n, self._ff, rows3(accel_mps2, n),
                mask_rows(hold, n) if has_hold else _NO_HOLD, has_hold)

    def _prepare_command(self) -> bool:
        """Whether the motor model has a start (a reset or a command before); its memory made
        ready for the kernel to write in place."""
        if self._thrust_n is not None:
            return True
        self._thrust_n = np.zeros(self.n)
        return False


_NO_HOLD = np.zeros(0, dtype=np.bool_)
