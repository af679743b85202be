"""When do a campaign's collisions happen: before or after each trial's own end?

    .venv/bin/python bench/post_dock.py --controller ours --compensation observer --seed 1
    .venv/bin/python bench/post_dock.py --controller ours --compensation model --model DIR

A campaign flies until its last trial is done; a trial that finished earlier (phase DONE: docked
and hung on the cables for ``mission.post_dock_s``, or backed off) goes on being simulated, and a
rotor strike or ground contact then still counts against it. This prints, for one campaign: the
docked count as ``dock`` reports it, the trials captured, the collisions before and after each
trial's own end, and how far the leader has sunk below its altitude when a docked trial ends
(the pair it carries). The seeds are ``reproduce``'s: hover at ``seed + 1``, the moving leader at
``seed + 2``.
"""

from __future__ import annotations

import argparse

import numpy as np

from aerodock.config import load_config
from aerodock.control.profiles import controller_config
from aerodock.gripper import GateState
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionBatch, MissionSpec, Phase


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--controller", default="ours", choices=("paper", "tuned", "ours"))
    ap.add_argument("--compensation", default="observer",
                    choices=("none", "observer", "model", "oracle"))
    ap.add_argument("--model", help="a trained model directory (for --compensation model)")
    ap.add_argument("--leader-speed", type=float, default=0.0, help="m/s")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    cfg = controller_config(load_config(), args.controller)
    predictor = Predictor.load(args.model) if args.model else None
    n = args.trials
    batch = MissionBatch(cfg, MissionSpec(trials=n, offset_m=0.36,
                                          leader_speed_mps=args.leader_speed,
                                          compensation=args.compensation, seed=args.seed),
                         predictor)
    ended = np.zeros(n, dtype=bool)
    hit_by_end = np.zeros(n, dtype=bool)
    sink_m = np.full(n, np.nan)
    while not batch.finished:
        batch.fly()
        hit = batch.strikes | batch.world.ground_contact
        now = (batch.phase == Phase.DONE) & ~ended
        hit_by_end = np.where(now, hit, hit_by_end)
        sink_m = np.where(now & batch.world.captured,
                          batch.world.leader.p[:, 2] - batch.leader_p0[:, 2], sink_m)
        ended |= now
    res = batch.result()
    hit = res.rotor_strike | res.ground_contact
    own = np.where(ended, hit_by_end, hit)
    captured = batch.world.gripper.gate == GateState.CAPTURED
    print(f"{args.controller} controller, compensation {args.compensation}, leader "
          f"{args.leader_speed:g} m/s, {n} trials; the campaign flew {batch.k} of "
          f"{batch.steps} control periods")
    print(f"  docked as reported: {int(res.success.sum())}; captured: {int(captured.sum())}; "
          f"captured with no collision by the trial's own end: {int((captured & ~own).sum())}")
    print(f"  collisions (rotor strike or ground) before the trial's own end: {int(own.sum())}, "
          f"after it: {int((hit & ~own).sum())} (strikes {int(res.rotor_strike.sum())}, ground "
          f"contacts {int(res.ground_contact.sum())} in all)")
    if np.isfinite(sink_m).any():
        print(f"  the leader's sink when a docked trial ends: median {np.nanmedian(sink_m):.2f} m, "
              f"max {np.nanmax(sink_m):.2f} m (down positive)")


if __name__ == "__main__":
    main()
