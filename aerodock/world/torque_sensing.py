"""What a real follower can log about the torques on it: gyro and rotor speeds, per control period.

A flight computer cannot measure the wake's torque directly, but it logs two things that
explain it between them (rigid-body model only)::

    J dw/dt + w x J w  =  tau_rotors + tau_ext                  (body FRD, N m)

* the *kinematic* torque, the left-hand side, from the gyro's rate readings (with the world's
  gyro noise: the readings the autopilot flies on);
* the *rotor* torque its own rotors explain, from the measured rotor speeds (ESC telemetry):
  thrust moments and yaw reaction of :attr:`RigidBodyParams.rotor_torque_map` and the rotor
  drag's moments (:func:`aerodock.world.vehicles.rigid_body.body_wrench`), with the vehicle's
  *nominal* thrust coefficient (it cannot know its thrust gain error) and its velocity (the state
  estimate; the true one here, the drag moments being small).

Their difference is ``tau_ext`` (the wake's torque, plus any injected rotor fault), which
:mod:`aerodock.learning.labels` turns into torque labels. Over a control period of physics
steps ``a..b`` the rigid body integrates ``J (w_{k+1} - w_k) / dt = tau_k - w_k x J w_k`` exactly,
so the mean over the steps is ``J (w_{b+1} - w_a) / (m dt) + mean(w_k x J w_k) = mean(tau_k)``:
the window's kinematic torque needs the reading one step *after* its last step. A
:class:`TorqueLog` therefore holds each step's terms until the next step's reading arrives, so
a period's reading covers the steps from one physics step before the period to one step before
its end (a 2 ms shift at 500 Hz, far below the wake's 50-100 ms turbulence correlation).

The log costs nothing unless someone asks for it: the world keeps one only after the first
:meth:`aerodock.world.world.World.observed_torque` call (the flight recorder's), and draws no random
numbers of its own (it reads the gyro noise the autopilot already drew).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.world.vehicles.rigid_body import RigidBodyParams, body_wrench


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


# w x u's components as (w[_NEXT] * u[_PREV] - w[_PREV] * u[_NEXT]): one product each side,
# where np.cross's Python takes about 45 µs a call at a batch of four
_NEXT, _PREV = np.array([1, 2, 0]), np.array([2, 0, 1])


class TorqueLog:
    """Collects a batch of followers' per-step states over a control period and turns them
    into a :class:`TorqueReading` when read, all steps in one batch (a physics step only keeps
    references to arrays the world made anyway: it never modifies a state in place).

    Args:
        params: the followers' rigid-body constants.
        n: batch size.
        dt_s: physics step, s.
    """

    def __init__(self, params: RigidBodyParams, n: int, dt_s: float) -> None:
        self.params = params
        self.n = n
        self.dt_s = dt_s
        self._inertia = np.asarray(params.inertia_kgm2, dtype=float)
        # Per step: (true rates, gyro noise or None, rotor speeds, velocity, attitude, wake
        # torque or None); the last one's reading closes the window, its terms open the next.
        self._steps: list[tuple] = []

    def add_step(self, w_radps: np.ndarray, gyro_noise_radps: np.ndarray | None,
                 rotor_speed_radps: np.ndarray, v_mps: np.ndarray, rot: np.ndarray,
                 wake_torque_nm: np.ndarray | None) -> None:
        """One physics step, from the followers' state before it (the state's arrays are kept,
        not copied: the world makes new ones every step; the field's torque is copied).

        Args:
            w_radps: (n, 3) true body rates.
            gyro_noise_radps: (n, 3) the gyro noise of this step (None: a noiseless gyro).
            rotor_speed_radps: (n, 4) rotor speeds.
            v_mps: (n, 3) velocity, world NED.
            rot: (n, 3, 3) attitude, body to world.
            wake_torque_nm: (n, 3) the wake's torque this step, body FRD (None: zero).
        """
        wake = None if wake_torque_nm is None else np.array(wake_torque_nm)  # a plug-in's buffer?
        self._steps.append((w_radps, gyro_noise_radps, rotor_speed_radps, v_mps, rot, wake))

    def read(self) -> TorqueReading:
        """The window since the last read (zeros before two steps); starts the next window."""
        n, steps = self.n, self._steps
        if len(steps) < 2:
            zeros = np.zeros((n, 3))
            return TorqueReading(zeros, zeros.copy(), zeros.copy(), zeros.copy())
        count = len(steps) - 1
        gyro = np.stack([w if noise is None else w + noise for w, noise, *_ in steps])
        window = gyro[:-1].reshape(-1, 3)  # (count * n, 3): the window's steps in one batch
        speed = np.concatenate([step[2] for step in steps[:-1]])
        v = np.concatenate([step[3] for step in steps[:-1]])
        rot = np.concatenate([step[4] for step in steps[:-1]])
        v_body = np.matmul(v[:, None, :], rot)[:, 0]  # R^T v
        rotor = rotor_torque_nm(speed, v_body, window, self.params)
        spun = window * self._inertia  # w x J w, as np.cross's own products and differences
        gyroscopic = window[:, _NEXT] * spun[:, _PREV] - window[:, _PREV] * spun[:, _NEXT]
        wake = np.zeros((count, n, 3))
        for k, step in enumerate(steps[:-1]):  # the steps of one period (5): not trials
            if step[5] is not None:
                wake[k] = step[5]
        rate_change = (gyro[-1] - gyro[0]) / (count * self.dt_s)
        self._steps = steps[-1:]
        return TorqueReading(
            kinematic_nm=rate_change * self._inertia + gyroscopic.reshape(count, n, 3).mean(0),
            rotor_nm=rotor.reshape(count, n, 3).mean(0),
            body_rates_radps=gyro[:-1].mean(0),
            true_wake_nm=wake.mean(0),
        )
