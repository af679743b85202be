"""Where the follower is and how it leans in the last second of the approach, with a model's
torque feed-forward off and on: the measurement behind README's "learnt wrench" paragraph.

    aerodock collect --out out/wrench --config examples/learnt_wrench.toml
    .venv/bin/python studies/torque_pairing.py out/wrench/models/final --offset 0.36 --trials 100
    .venv/bin/python studies/torque_pairing.py DIR --smoke   # feed-forward on, two trials, short

For each setting: docked trials and the terminal tilt (the campaign summary), then medians over
the approaching trials in the final second before the planned arrival: the follower's distance
from the leader's axis, the radial (outward) part of the model's feed-forward and of the true mean
wake force, and the radial acceleration its thrust gives it (its lean, times g). A model of
command-basis labels leans on the wake's torque; one of thrust-basis labels needs the torque
feed-forward.
"""

from __future__ import annotations

import argparse

import numpy as np
from _smoke import SMOKE_TRIALS, add_smoke_option, smoke_config  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.control.compensation import Compensation, OraclePredictor
from aerodock.control.profiles import controller_config
from aerodock.downwash.base import BodyState
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionBatch, MissionSpec, Phase


def _radial(vectors: np.ndarray, e_r: np.ndarray) -> np.ndarray:
    return np.einsum("ni,ni->n", vectors[:, :2], e_r)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", help="a trained model directory")
    ap.add_argument("--offset", type=float, default=0.36, help="cable length d_p, m")
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    add_smoke_option(ap)
    args = ap.parse_args()
    predictor = Predictor.load(args.model)
    base = controller_config(load_config(), "ours")
    if args.smoke:
        base, args.trials = smoke_config(base), SMOKE_TRIALS
    g = base.sim.gravity_mps2
    for torque_ff in (True,) if args.smoke else (False, True):
        cfg = base.with_overrides({"control": {"torque_feedforward": torque_ff}})
        batch = MissionBatch(cfg, MissionSpec(trials=args.trials, offset_m=args.offset,
                                              compensation=Compensation.MODEL, seed=args.seed),
                             predictor)
        oracle = OraclePredictor(batch.world.field, dt_s=batch.world.dt_s)
        mass = np.full(batch.n, cfg.vehicle.mass_kg)
        rows = []
        while not batch.finished:
            batch.fly()
            t = batch.k * batch.dt_s
            if not batch.arrival_s - 1.0 <= t < batch.arrival_s:
                continue
            lead, fol = batch.world.leader, batch.world.follower
            dp = fol.p - lead.p
            r = np.hypot(dp[:, 0], dp[:, 1])
            e_r = dp[:, :2] / np.maximum(r, 1e-9)[:, None]
            true = oracle.predict_bodies(BodyState(lead.p, lead.v, lead.R, mass * g, mass),
                                         BodyState(fol.p, fol.v, fol.R, mass * g, mass))
            lean = _radial(-fol.R[:, :, 2], e_r) * g  # thrust along -body z, at hover thrust
            rows.append(np.stack([r, _radial(batch.last_fout.feedforward_mps2, e_r),
                                  _radial(true, e_r), lean, batch.phase <= Phase.TERMINAL], 1))
        s = batch.result().summary()
        a = np.array(rows)
        sel = a[..., 4] > 0
        med = [float(np.median(a[..., j][sel])) for j in range(4)]
        print(f"torque feed-forward {'on ' if torque_ff else 'off'}: docked "
              f"{s['docked']}/{s['trials']}, aborts {s['aborts']}, terminal tilt "
              f"{s['terminal_tilt_rms_deg_median']:.2f} deg")
        print(f"  last second: off axis {med[0]:.3f} m; outward: model {med[1]:+.3f}, "
              f"true wake {med[2]:+.3f}, lean {med[3]:+.3f} m/s^2")


if __name__ == "__main__":
    main()
