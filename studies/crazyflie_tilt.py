"""The follower's tilt below a leader: the real Crazyflie swap flights against the Crazyflie
world, with the jet's force on the rotor disks (its wake torque) and at the centre of mass.

    .venv/bin/python studies/crazyflie_tilt.py [--config examples/crazyflie.toml]
        [--depth 0.3] [--trials 16] [--data $AERODOCK_DATA_DIR/neural-swarm/swap_ss] [--json]
        [--smoke]    # two followers, a settled start of 1 s

Real: the tilt (angle of the body z axis from the vertical) of every sample of the swap_ss
flights with the follower 0.25-0.35 m below the other vehicle and within 3 cm of its axis, and
of the samples more than 0.3 m to the side (free air). Simulated: the follower of the world
holding station ``--depth`` below a hovering leader, on its axis, and 3 m to the side, under the
tuned controller with the bias observer, 5 s after a settled start (``mission.settle_s``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from _smoke import SMOKE_TRIALS, add_smoke_option, smoke_config  # studies/, on sys.path

from aerodock.config import Config, load_config
from aerodock.control.controller import PositionController, Reference
from aerodock.downwash import build_field
from aerodock.geometry import quat_to_rotmat
from aerodock.ingest import read_logs
from aerodock.ingest.data_dir import find_data_dir
from aerodock.mission.settle import settle
from aerodock.rng import TrialRNG
from aerodock.world import World

ROOT = Path(__file__).resolve().parents[1]
# The data location (aerodock.ingest.data_dir): AERODOCK_DATA_DIR, else ../shared/data.
DATA_DIR = find_data_dir().path or ROOT.parent / "shared" / "data"
AT_CENTRE = "aerodock.downwash.at_centre:RoundJetAtCentre"


def tilt_deg(R: np.ndarray) -> np.ndarray:  # noqa: N803
    """Angle of the body z axis from the vertical, deg, of rotations (..., 3, 3)."""
    return np.degrees(np.arccos(np.clip(R[..., 2, 2], -1.0, 1.0)))


def real_tilts(folder: Path) -> dict[str, float]:
    """RMS tilt of the real followers below the other vehicle (on its axis) and in free air."""
    below, free = [], []
    for log in read_logs("neural-swarm", [folder]):
        dp = log.follower_pos_m - log.leader_pos_m
        r = np.hypot(dp[:, 0], dp[:, 1])
        tilt = tilt_deg(quat_to_rotmat(log.follower_quat))
        below.append(tilt[(r < 0.03) & (dp[:, 2] > 0.25) & (dp[:, 2] < 0.35)])
        free.append(tilt[r > 0.3])
    b, f = np.concatenate(below), np.concatenate(free)
    return {"below_rms_deg": float(np.sqrt(np.mean(b**2))), "below_samples": int(b.size),
            "free_air_rms_deg": float(np.sqrt(np.mean(f**2))), "free_air_samples": int(f.size)}


def simulated_tilt(cfg: Config, depth_m: float, side_m: float, trials: int, seed: int) -> float:
    """RMS tilt of ``trials`` followers holding station ``depth_m`` below and ``side_m`` beside
    a hovering leader, over 5 s after a settled start, deg."""
    n = trials
    world = World(cfg, n, TrialRNG(seed, n), field=build_field(cfg))
    lead_p = np.tile([0.0, 0.0, -cfg.mission.leader_altitude_m], (n, 1))
    fol_p = lead_p + np.array([side_m, 0.0, depth_m])
    world.reset(lead_p, fol_p)
    lead = PositionController(cfg, n, use_observer=True, vehicle=cfg.leader)
    fol = PositionController(cfg, n, use_observer=True, has_accelerometer=True)
    z, zn = np.zeros((n, 3)), np.zeros(n)
    lead_ref, fol_ref = Reference(lead_p, z, z, zn, zn), Reference(fol_p, z, z, zn, zn)
    settle(world, lead, fol, lambda t: lead_ref, lambda t: fol_ref, cfg.mission.settle_s)
    tilts = []
    for _ in range(int(round(5.0 / world.dt_control_s))):
        obs_l, obs_f = world.observe()
        lout = lead.step(obs_l.p, obs_l.v, obs_l.rpy, lead_ref)
        accel = world.observed_accel() if fol.uses_accelerometer else None
        fout = fol.step(obs_f.p, obs_f.v, obs_f.rpy, fol_ref, None, None, accel)
        world.advance(lout.command, fout.command)
        tilts.append(tilt_deg(world.follower.R))
    return float(np.sqrt(np.mean(np.square(tilts))))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, default=ROOT / "examples" / "crazyflie.toml")
    parser.add_argument("--data", type=Path,
                        default=DATA_DIR / "neural-swarm" / "swap_ss")
    parser.add_argument("--depth", type=float, default=0.3)
    parser.add_argument("--trials", type=int, default=16)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    cfg = load_config(args.config)
    if args.smoke:
        cfg, args.trials = smoke_config(cfg), SMOKE_TRIALS
    centre = cfg.with_overrides(  # a new field takes only the params given with it
        {"downwash": {"field": AT_CENTRE, "params": dict(cfg.data["downwash"]["params"])}},
        source="force at centre")
    out = {
        "real": real_tilts(args.data),
        "depth_m": args.depth, "trials": args.trials, "config": str(args.config),
        "sim_below_rms_deg": {
            "jet (force on the rotor disks)": simulated_tilt(cfg, args.depth, 0.0, args.trials,
                                                            args.seed),
            "jet at the centre of mass": simulated_tilt(centre, args.depth, 0.0, args.trials,
                                                        args.seed)},
        "sim_free_air_rms_deg": simulated_tilt(cfg, args.depth, 3.0, args.trials, args.seed),
    }
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    real = out["real"]
    print(f"real, below (0.25-0.35 m, < 3 cm off axis): {real['below_rms_deg']:.1f} deg RMS "
          f"({real['below_samples']} samples); free air {real['free_air_rms_deg']:.1f} deg")
    for name, value in out["sim_below_rms_deg"].items():
        print(f"simulated, {args.depth:g} m below, {name}: {value:.1f} deg RMS")
    print(f"simulated, free air: {out['sim_free_air_rms_deg']:.1f} deg RMS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
