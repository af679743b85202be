"""Recording simulated flights as FlightLogs, one row per control tick, batch-first."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from aerodock.control.controller import ControlOutput
from aerodock.flightlog import FlightLog
from aerodock.geometry import rotmat_to_quat
from aerodock.sim import Observation, World

_KEYS = ("t", "lp", "lv", "lq", "fp", "fv", "fq", "u", "thrust", "aobs", "fmean", "ref", "ff",
         "phase", "bar", "valid")


class FlightRecorder:
    """Collects what a real vehicle would log (mocap state, commands, accelerometer) plus the
    simulator's truth as ``extra`` arrays, then splits the batch into one FlightLog per trial.

    Call :meth:`before_step` after the controllers ran and before ``world.advance``, and
    :meth:`after_step` right after it (the observed acceleration covers the control period that
    the logged command was applied over, so ``a_obs - u`` is the residual of that period).
    """

    def __init__(self) -> None:
        self.rows: dict[str, list] = {k: [] for k in _KEYS}

    def before_step(self, t_s: float, world: World, obs_l: Observation, obs_f: Observation,
                    out: ControlOutput, ref_p: np.ndarray, phase: np.ndarray) -> None:
        """Record the state the controllers saw and the commands they sent."""
        r = self.rows
        r["t"].append(t_s)
        r["lp"].append(obs_l.p)
        r["lv"].append(obs_l.v)
        r["lq"].append(rotmat_to_quat(obs_l.R))
        r["fp"].append(obs_f.p)
        r["fv"].append(obs_f.v)
        r["fq"].append(rotmat_to_quat(obs_f.R))
        r["u"].append(out.applied_accel_mps2)
        r["thrust"].append(out.command.thrust_n)
        r["fmean"].append(world.true_mean_field_mps2())
        r["ref"].append(np.array(ref_p, copy=True))
        r["ff"].append(out.feedforward_mps2)
        r["phase"].append(np.array(phase, copy=True))
        r["bar"].append(world.bar.p.copy())
        world.contact_seen[:] = False

    def after_step(self, world: World) -> None:
        """Record the accelerometer over the control period just flown."""
        self.rows["aobs"].append(world.observed_accel())
        # Touching the bar or hanging on the cables: the residual is not downwash (a real
        # pipeline flags the same samples from the gripper's strain gauge).
        self.rows["valid"].append(~(world.contact_seen | world.captured))

    def flightlogs(self, meta: Callable[[int], dict[str, Any]]) -> list[FlightLog]:
        """One FlightLog per trial; ``meta(i)`` gives trial ``i``'s metadata."""
        arr = {k: np.asarray(v) for k, v in self.rows.items()}  # (T, n, ...)
        n = arr["lp"].shape[1]
        return [
            FlightLog(
                t_s=arr["t"], leader_pos_m=arr["lp"][:, i], leader_vel_mps=arr["lv"][:, i],
                leader_quat=arr["lq"][:, i], follower_pos_m=arr["fp"][:, i],
                follower_vel_mps=arr["fv"][:, i], follower_quat=arr["fq"][:, i],
                follower_cmd_accel_mps2=arr["u"][:, i], follower_thrust_n=arr["thrust"][:, i],
                follower_obs_accel_mps2=arr["aobs"][:, i], meta=meta(i),
                extra={"true_field_mean_mps2": arr["fmean"][:, i], "ref_pos_m": arr["ref"][:, i],
                       "feedforward_mps2": arr["ff"][:, i], "phase": arr["phase"][:, i],
                       "bar_pos_m": arr["bar"][:, i], "label_valid": arr["valid"][:, i]},
            )
            for i in range(n)
        ]


def vehicle_meta(cfg: Any) -> dict[str, Any]:
    """FlightLog metadata of both simulated vehicles (model files record what they learnt on)."""
    v = cfg.vehicle
    return {"leader_rotor_radius_m": v.rotor_radius_m, "follower_rotor_radius_m": v.rotor_radius_m,
            "leader_n_rotors": int(v.n_rotors), "follower_n_rotors": int(v.n_rotors),
            "vehicle_model": v.model}
