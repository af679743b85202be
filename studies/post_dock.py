"""What happens to a campaign's trials after their own missions end, and how far the docked
pairs sink.

    .venv/bin/python studies/post_dock.py --controller ours --compensation observer --seed 1
    .venv/bin/python studies/post_dock.py --controller ours --compensation model --model DIR
    .venv/bin/python studies/post_dock.py --smoke    # two trials, the mission's waits cut

A campaign flies until its last trial is done; a trial that finished earlier (phase DONE: docked
and hung on the cables for ``mission.post_dock_s``, or backed off) goes on being simulated.
Collisions then do not count against it (a trial's outcome is its own), but they show what the
flight would have come to: without a model the hanging follower does not answer the wake on it,
the pair sinks, and it hits the ground soon after. This prints the docked count, the trials
captured, the collisions (rotor strikes, ground contacts) before and after each trial's own end,
and how far the leader has sunk below its altitude when a docked trial ends. The seeds are
``reproduce``'s: hover at ``seed + 1``, the moving leader at ``seed + 2``.
"""

from __future__ import annotations

import argparse

from _smoke import SMOKE_TRIALS, add_smoke_option, smoke_config  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.control.profiles import controller_config
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionBatch, MissionSpec
from aerodock.world.gripper import GateState


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--controller", default="ours", choices=("paper", "tuned", "ours"))
    ap.add_argument("--compensation", default="observer",
                    choices=("none", "observer", "model", "oracle"))
    ap.add_argument("--model", help="a trained model directory (for --compensation model)")
    ap.add_argument("--leader-speed", type=float, default=0.0, help="m/s")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    add_smoke_option(ap)
    args = ap.parse_args()
    cfg = controller_config(load_config(), args.controller)
    if args.smoke:
        cfg, args.trials = smoke_config(cfg), SMOKE_TRIALS
    predictor = Predictor.load(args.model) if args.model else None
    n = args.trials
    batch = MissionBatch(cfg, MissionSpec(trials=n, offset_m=0.36,
                                          leader_speed_mps=args.leader_speed,
                                          compensation=args.compensation, seed=args.seed),
                         predictor)
    while not batch.finished:
        batch.fly()
    res = batch.result()
    captured = batch.world.gripper.gate == GateState.CAPTURED
    later = batch.world.ground_contact & ~res.ground_contact  # the world keeps counting
    print(f"{args.controller} controller, compensation {args.compensation}, leader "
          f"{args.leader_speed:g} m/s, {n} trials; the campaign flew {batch.k} of "
          f"{batch.steps} control periods")
    print(f"  docked: {int(res.success.sum())} (captured: {int(captured.sum())}); collisions "
          f"before the trials' own end: {int(res.rotor_strike.sum())} rotor strikes, "
          f"{int(res.ground_contact.sum())} ground contacts; ground contacts after it (not "
          f"counted): {int(later.sum())}")
    sink = res.summary()
    if sink["post_dock_sink_median_m"] is not None:
        print(f"  the leader's sink when a docked trial ends: median "
              f"{sink['post_dock_sink_median_m']:.2f} m, max {sink['post_dock_sink_max_m']:.2f} m "
              "(down positive)")

if __name__ == "__main__":
    main()
