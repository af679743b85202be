"""Recording simulated flights as FlightLogs, one row per control tick, batch-first.

Besides the FlightLog's fields, every log carries ``extra`` arrays: the simulator's truth
(``true_field_mean_mps2``, ``bar_pos_m``, ...) and ``label_valid``. With rigid-body vehicles it
also carries what a real follower logs about torques
(:meth:`aerodock.world.world.World.observed_torque`, one reading per control period, body FRD):
``follower_obs_torque_nm`` (``J dw/dt + w x J w`` from the gyro), ``follower_rotor_torque_nm``
(what the rotors explain from their measured speeds), ``follower_body_rates_radps`` (the gyro), and
the truth ``true_wake_torque_nm`` (evaluation only). :mod:`aerodock.learning.labels` turns the
first two into torque labels.

``follower_cmd_accel_mps2`` is what the follower's own actuation explains, on one of the two
bases real logs have (``meta["label_basis"]``, ``curriculum.label_basis``): ``"command"``, the
acceleration ``u_1:3`` the controller sent to the inversion map (the paper's labels ``a_obs - u``),
or ``"thrust"``, ``g e3 - R e3 T / m`` with the measured attitude ``R`` and the commanded
collective ``T`` (what a log without the outer loop's command gives). On a rigid body they
differ by the attitude loop's tracking error: the wake's torque tilts the follower off its
commanded attitude, and ``a_obs - u`` counts the thrust that tilt redirects as wake force;
``a_obs - (g e3 - R e3 T / m)`` is the force on the body alone, the right partner of a torque
feed-forward that removes the tilt.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from aerodock.control.controller import ControlOutput
from aerodock.flightlog import LABEL_BASES, FlightLog
from aerodock.geometry import rotmat_to_quat, thrust_accel
from aerodock.world import Observation, World

_KEYS = ("t", "lp", "lv", "lq", "fp", "fv", "fq", "u", "thrust", "aobs", "fmean", "ref", "ff",
         "phase", "bar", "valid", "contact", "tau_obs", "tau_rotor", "rates", "tau_true")
_ATTITUDE_CHUNK = 64
"""Periods of attitudes the recorder converts to quaternions at once (the rotation matrices it
holds meanwhile are 9 numbers a vehicle, the quaternions 4)."""
# Recorded rows -> FlightLog extras of the torque observations (rigid-body vehicles only).
TORQUE_EXTRAS = {"tau_obs": "follower_obs_torque_nm", "tau_rotor": "follower_rotor_torque_nm",
                 "rates": "follower_body_rates_radps", "tau_true": "true_wake_torque_nm"}


class FlightRecorder:
    """Collects what a real vehicle would log (mocap state, commands, accelerometer) plus the
    simulator's truth as ``extra`` arrays, then splits the batch into one FlightLog per trial.

    Call :meth:`before_step` after the controllers ran and before ``world.advance``, and
    :meth:`after_step` right after it (the observed acceleration covers the control period that
    the logged command was applied over, so ``a_obs - u`` is the residual of that period).

    Args:
        label_basis: ``"command"`` or ``"thrust"`` (see the module docstring).
        mass_kg: the follower's mass (for the ``"thrust"`` basis).
    """

    def __init__(self, label_basis: str = "command", mass_kg: float | None = None) -> None:
        if label_basis not in LABEL_BASES:
            raise ValueError(f"label_basis must be one of {'|'.join(LABEL_BASES)}, "
                             f"got {label_basis!r}")
        if label_basis == "thrust" and not (mass_kg is not None and mass_kg > 0):
            raise ValueError("the thrust basis needs the follower's mass (mass_kg > 0)")
        self.label_basis, self.mass_kg = label_basis, mass_kg
        self.rows: dict[str, list] = {k: [] for k in _KEYS}
        # (leader, follower) attitudes of the periods not yet in rows["lq"] / rows["fq"]
        self._attitudes: list[tuple[np.ndarray, np.ndarray]] = []

    def before_step(self, t_s: float, world: World, obs_l: Observation, obs_f: Observation,
                    out: ControlOutput, ref_p: np.ndarray, phase: np.ndarray) -> None:
        """Record the state the controllers saw and the commands they sent."""
        r = self.rows
        r["t"].append(t_s)
        r["lp"].append(obs_l.p)
        r["lv"].append(obs_l.v)
        self._attitudes.append((obs_l.R.copy(), obs_f.R.copy()))  # (as quaternions: below)
        if len(self._attitudes) == _ATTITUDE_CHUNK:
            self._convert_attitudes()
        r["fp"].append(obs_f.p)
        r["fv"].append(obs_f.v)
        r["u"].append(out.applied_accel_mps2 if self.label_basis == "command"
                      else thrust_accel(obs_f.R, out.command.thrust_n, self.mass_kg))
        r["thrust"].append(out.command.thrust_n)
        r["fmean"].append(world.true_mean_field_mps2())
        r["ref"].append(np.array(ref_p, copy=True))
        r["ff"].append(out.feedforward_mps2)
        r["phase"].append(np.array(phase, copy=True))
        r["bar"].append(world.bar.p.copy())
        if world.rigid and len(r["t"]) == 1:
            world.observed_torque()  # the first read starts the torque log's window
        world.contact_seen[:] = False
        world.contact_sensed[:] = False

    def after_step(self, world: World, docked: np.ndarray | None = None,
                   sensed: bool = True) -> None:
        """Record the accelerometer over the control period just flown; ``docked`` (n,): the
        trials whose follower acts as docked (hanging from the bar); ``sensed``: the labels'
        mask from the strain gauge (False: from the world's true contact, as earlier worlds)."""
        self.rows["aobs"].append(world.observed_accel())
        if world.rigid:
            torque = world.observed_torque()
            self.rows["tau_obs"].append(torque.kinematic_nm)
            self.rows["tau_rotor"].append(torque.rotor_nm)
            self.rows["rates"].append(torque.body_rates_radps)
            self.rows["tau_true"].append(torque.true_wake_nm)
        # Touching the bar (as the strain gauge senses it) or hanging on the cables: the
        # residual is not downwash. What the gauge missed is kept for evaluation.
        docked = np.zeros(world.n, dtype=bool) if docked is None else docked
        touched = world.contact_sensed if sensed else world.contact_seen
        self.rows["valid"].append(~(touched | docked))
        self.rows["contact"].append(world.contact_seen | world.captured)

    def _convert_attitudes(self) -> None:
        """The pending periods' attitudes as quaternions, in one conversion per vehicle (each
        row's quaternion is its own arithmetic, so the same numbers as period by period; a
        period's two conversions cost 170 µs at a batch of four, a sixth of a recorded
        period)."""
        if self._attitudes:
            lead, fol = (rotmat_to_quat(np.asarray(rots)) for rots in zip(*self._attitudes))
            self.rows["lq"].extend(lead)
            self.rows["fq"].extend(fol)
            self._attitudes.clear()

    def flightlogs(self, meta: Callable[[int], dict[str, Any]]) -> list[FlightLog]:
        """One FlightLog per trial; ``meta(i)`` gives trial ``i``'s metadata."""
        self._convert_attitudes()
        arr = {k: np.asarray(v) for k, v in self.rows.items()}  # (T, n, ...)
        n = arr["lp"].shape[1]
        torque = {name: arr[key] for key, name in TORQUE_EXTRAS.items()
                  if len(self.rows[key]) == len(self.rows["t"]) and self.rows["t"]}
        return [
            FlightLog(
                t_s=arr["t"], leader_pos_m=arr["lp"][:, i], leader_vel_mps=arr["lv"][:, i],
                leader_quat=arr["lq"][:, i], follower_pos_m=arr["fp"][:, i],
                follower_vel_mps=arr["fv"][:, i], follower_quat=arr["fq"][:, i],
                follower_cmd_accel_mps2=arr["u"][:, i], follower_thrust_n=arr["thrust"][:, i],
                follower_obs_accel_mps2=arr["aobs"][:, i], meta=meta(i),
                extra={"true_field_mean_mps2": arr["fmean"][:, i], "ref_pos_m": arr["ref"][:, i],
                       "feedforward_mps2": arr["ff"][:, i], "phase": arr["phase"][:, i],
                       "bar_pos_m": arr["bar"][:, i], "label_valid": arr["valid"][:, i],
                       "true_contact": arr["contact"][:, i],
                       **{name: a[:, i] for name, a in torque.items()}},
            )
            for i in range(n)
        ]
