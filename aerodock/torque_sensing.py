"""What a real follower can log about the torques on it: gyro and rotor speeds, per control period.

A flight computer cannot measure the wake's torque directly, but it logs two things that
explain it between them (rigid-body model only)::

    J dw/dt + w x J w  =  tau_rotors + tau_ext                  (body FRD, N m)

* the *kinematic* torque, the left-hand side, from the gyro's rate readings (with the world's
  gyro noise: the readings the autopilot flies on);
* the *rotor* torque its own rotors explain, from the measured rotor speeds (ESC telemetry):
  thrust moments and yaw reaction of :attr:`RigidBodyParams.rotor_torque_map` and the rotor
  drag's moments (:func:`aerodock.rigid_body.body_wrench`), with the vehicle's *nominal* thrust
  coefficient (it cannot know its thrust gain error) and its velocity (the state estimate; the
  true one here, the drag moments being small).

Their difference is ``tau_ext`` (the wake's torque, plus any injected rotor fault), which
:mod:`aerodock.learning.labels` turns into torque labels. Over a control period of physics
steps ``a..b`` the rigid body integrates ``J (w_{k+1} - w_k) / dt = tau_k - w_k x J w_k`` exactly,
so the mean over the steps is ``J (w_{b+1} - w_a) / (m dt) + mean(w_k x J w_k) = mean(tau_k)``:
the window's kinematic torque needs the reading one step *after* its last step. A
:class:`TorqueLog` therefore holds each step's terms until the next step's reading arrives, so
a period's reading covers the steps from one physics step before the period to one step before
its end (a 2 ms shift at 500 Hz, far below the wake's 50-100 ms turbulence correlation).

The log costs nothing unless someone asks for it: the world keeps one only after the first
:meth:`aerodock.sim.World.observed_torque` call (the flight recorder's), and draws no random
numbers of its own (it reads the gyro noise the autopilot already drew).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.rigid_body import RigidBodyParams, body_wrench


@dataclass(frozen=True)
class TorqueReading:
    """One control period's torque observations of N followers (body FRD, batch-first).

    Attributes:
        kinematic_nm: (n, 3) ``J dw/dt + w x J w`` from the gyro, mean over the period, N m.
        rotor_nm: (n, 3) mean torque the rotors explain from their measured speeds, N m.
        body_rates_radps: (n, 3) mean gyro reading over the period, rad/s.
        true_wake_nm: (n, 3) the simulator's mean wake torque over the same steps, N m
            (evaluation only: no controller or label reads it).
    """

    kinematic_nm: np.ndarray
    rotor_nm: np.ndarray
    body_rates_radps: np.ndarray
    true_wake_nm: np.ndarray


def rotor_torque_nm(rotor_speed_radps: np.ndarray, v_body_mps: np.ndarray,
                    gyro_radps: np.ndarray, params: RigidBodyParams) -> np.ndarray:
    """(n, 3) torque the rotors explain, body FRD, N m, at the nominal thrust coefficient.

    Args:
        rotor_speed_radps: (n, 4) measured rotor speeds.
        v_body_mps: (n, 3) velocity in the body frame (for the rotor drag's moments).
        gyro_radps: (n, 3) body rates (for the rotor drag's damping moments).
        params: vehicle constants.
    """
    nominal = np.ones(rotor_speed_radps.shape[0])
    return body_wrench(rotor_speed_radps, nominal, v_body_mps, gyro_radps, params)[1]


class TorqueLog:
    """Accumulates a batch of followers' torque terms, one physics step at a time.

    Args:
        params: the followers' rigid-body constants.
        n: batch size.
        dt_s: physics step, s.
    """

    def __init__(self, params: RigidBodyParams, n: int, dt_s: float) -> None:
        self.params = params
        self.dt_s = dt_s
        self._inertia = np.asarray(params.inertia_kgm2, dtype=float)
        self._sums = np.zeros((4, n, 3))  # rotor, gyroscopic, wake, gyro readings
        self._count = 0
        self._pending: np.ndarray | None = None  # (4, n, 3): the last step's terms
        self._gyro_start: np.ndarray | None = None  # reading at the window's first step
        self._gyro_last = np.zeros((n, 3))  # reading at the step after the window's last

    def add_step(self, w_radps: np.ndarray, gyro_noise_radps: np.ndarray | None,
                 rotor_speed_radps: np.ndarray, v_mps: np.ndarray, rot: np.ndarray,
                 wake_torque_nm: np.ndarray | None) -> None:
        """The terms of one physics step, from the followers' state before it.

        Args:
            w_radps: (n, 3) true body rates.
            gyro_noise_radps: (n, 3) the gyro noise of this step (None: a noiseless gyro).
            rotor_speed_radps: (n, 4) rotor speeds.
            v_mps: (n, 3) velocity, world NED.
            rot: (n, 3, 3) attitude, body to world.
            wake_torque_nm: (n, 3) the wake's torque this step, body FRD (None: zero).
        """
        gyro = np.array(w_radps) if gyro_noise_radps is None else w_radps + gyro_noise_radps
        if self._pending is not None:
            self._sums += self._pending
            self._count += 1
        elif self._gyro_start is None:
            self._gyro_start = gyro
        v_body = np.einsum("nji,nj->ni", rot, v_mps)
        terms = np.empty_like(self._sums)
        terms[0] = rotor_torque_nm(rotor_speed_radps, v_body, gyro, self.params)
        terms[1] = np.cross(gyro, gyro * self._inertia)
        terms[2] = 0.0 if wake_torque_nm is None else wake_torque_nm
        terms[3] = gyro
        self._pending = terms
        self._gyro_last = gyro

    def read(self) -> TorqueReading:
        """The window since the last read (zeros before two steps); starts the next window."""
        count = max(self._count, 1)
        mean = self._sums / count
        if self._count and self._gyro_start is not None:
            rate_change = (self._gyro_last - self._gyro_start) / (self._count * self.dt_s)
            kinematic = rate_change * self._inertia + mean[1]
        else:
            kinematic = np.zeros_like(mean[1])
        reading = TorqueReading(kinematic_nm=kinematic, rotor_nm=mean[0],
                                body_rates_radps=mean[3], true_wake_nm=mean[2])
        self._sums = np.zeros_like(self._sums)
        self._count = 0
        if self._pending is not None:
            self._gyro_start = self._gyro_last
        return reading
