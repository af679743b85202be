"""The learnt models across curriculum seeds: is the deep model's miss of the 10 % check
(``results.json`` -> ``targets.learnt_mean``) a bias of the pipeline or one seed's, and how far
apart do the seeds' models dock (``--dock N``: the headline's hover at 0.36 m, ``N`` trials,
campaign seed 1, ours and the paper's controller with each seed's deep model)? With
``--config examples/learnt_wrench.toml`` the curriculum trains the learnt wrench (so2-wrench on
thrust-basis labels) and ours feeds its torque forward, as the headline's targets row.

    .venv/bin/python studies/learnt_mean_seeds.py [--seeds 0 1 2] [--config FILE]
        [--out DIR] [--dock N] [--json] [--smoke]

For each seed, the curriculum ``aerodock collect`` flies (the configuration's, as ``reproduce``
flies it), then ``learnt_mean_check`` for the deep curriculum's model (``models/final``) and the
paper's (``models/paper``) at 0.36 m, and the mean of the labels minus the simulator's mean field
over the curriculum's samples within 3 cm of the axis 0.3-0.4 m below the leader (what the
models learn from where the check looks). About a minute per seed. ``--smoke``: the first seed
only, ``reproduce --smoke``'s curriculum trained for a few epochs, the mission's waits cut.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from _smoke import SMOKE_CURRICULUM, SMOKE_EPOCHS, add_smoke_option, smoke_config

from aerodock.collect.curriculum import run_curriculum
from aerodock.config import Config, load_config
from aerodock.control.profiles import controller_config
from aerodock.experiments.targets import learnt_mean_check
from aerodock.flightlog import load_flightlogs
from aerodock.learning.labels import raw_labels
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionSpec, run_campaign
from aerodock.mission.spec import Compensation

TRUE_MEAN_KEY = "true_field_mean_mps2"


def label_minus_mean_on_axis(folder: Path, band_m: tuple[float, float] = (0.3, 0.4),
                             radius_m: float = 0.03) -> tuple[float, int]:
    """Mean vertical label minus the simulator's mean field (m/s², down +) over a curriculum's
    valid samples within ``radius_m`` of the leader's axis ``band_m`` below it, and their
    count."""
    errs = []
    for path in sorted(folder.glob("stage*.npz")):
        for log in load_flightlogs(path):
            dp = log.follower_pos_m - log.leader_pos_m
            keep = ((np.hypot(dp[:, 0], dp[:, 1]) < radius_m) & (dp[:, 2] > band_m[0])
                    & (dp[:, 2] < band_m[1]))
            if "label_valid" in log.extra:
                keep &= np.asarray(log.extra["label_valid"]).astype(bool)
            errs.append((raw_labels(log)[:, 2] - log.extra[TRUE_MEAN_KEY][:, 2])[keep])
    err = np.concatenate(errs) if errs else np.zeros(0)
    return (float(err.mean()) if err.size else float("nan")), int(err.size)


def docked_with(cfg: Config, model_dir: Path, trials: int) -> dict[str, int]:
    """Docked trials of ``trials`` at the headline's hover (0.36 m, campaign seed 1, as
    ``reproduce`` flies it), ours and the paper's controller with the model at ``model_dir``."""
    predictor = Predictor.load(model_dir)
    out = {}
    for profile in ("ours", "paper"):
        res = run_campaign(controller_config(cfg, profile),
                           MissionSpec(trials=trials, offset_m=0.36,
                                       compensation=Compensation.MODEL, seed=1), predictor)
        out[profile] = int(res.summary()["docked"])
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--config", type=Path, help="TOML overriding aerodock's defaults")
    parser.add_argument("--out", type=Path, help="keep each seed's curriculum in DIR/seed-N")
    parser.add_argument("--dock", type=int, default=0,
                        help="also fly N hover docking trials with each seed's deep model")
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    cfg = load_config(args.config) if args.config else load_config()
    train_kwargs = None
    if args.smoke:
        cfg = smoke_config(cfg).with_overrides({"curriculum": SMOKE_CURRICULUM})
        args.seeds, train_kwargs = args.seeds[:1], {"max_epochs": SMOKE_EPOCHS}
    kind = cfg.curriculum.model  # the deep curriculum's kind (so2-wrench: the learnt wrench)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        base = args.out if args.out is not None else Path(tmp)
        for seed in args.seeds:
            folder = base / f"seed-{seed}"
            run_curriculum(cfg, folder, seed=seed, progress=lambda m: None,
                           train_kwargs=train_kwargs)
            deep = learnt_mean_check(cfg, Predictor.load(folder / "models" / "final"))[0]
            paper_dir = folder / "models" / "paper"
            paper = (learnt_mean_check(cfg, Predictor.load(paper_dir))[0]
                     if paper_dir.is_dir() else None)
            bias, samples = label_minus_mean_on_axis(folder)
            row = {"seed": seed, "deep_relative_error": deep.relative_error,
                   "paper_relative_error": paper.relative_error if paper else None,
                   "label_minus_mean_on_axis_mps2": bias, "axis_samples": samples}
            if args.dock:
                row["docked"] = docked_with(cfg, folder / "models" / "final", args.dock)
            rows.append(row)
            if not args.json:
                paper_txt = ("-" if paper is None else f"{paper.relative_error:+.1%}")
                dock_txt = ("" if not args.dock else "; docked of {}: {}".format(
                    args.dock, ", ".join(f"{k} {v}" for k, v in row["docked"].items())))
                print(f"seed {seed}: {kind} model {deep.relative_error:+.1%}, paper's "
                      f"{paper_txt}; labels minus the mean field on the axis 0.3-0.4 m "
                      f"{bias:+.3f} m/s^2 ({samples} samples){dock_txt}", flush=True)
    deep_all = np.array([r["deep_relative_error"] for r in rows])
    summary = {"model": kind, "seeds": rows, "deep_mean_relative_error": float(deep_all.mean()),
               "deep_sd_relative_error": float(deep_all.std(ddof=1)) if len(rows) > 1 else None}
    if args.dock:
        summary["docked_range"] = {k: [min(r["docked"][k] for r in rows),
                                       max(r["docked"][k] for r in rows)]
                                   for k in ("ours", "paper")}
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        sd = summary["deep_sd_relative_error"]
        print(f"{kind} model over {len(rows)} seeds: "
              f"{summary['deep_mean_relative_error']:+.1%} "
              f"mean" + (f", sd {sd:.1%}" if sd is not None else ""))
        if args.dock:
            print("docked of {} over the seeds: {}".format(args.dock, ", ".join(
                f"{k} {lo}-{hi}" for k, (lo, hi) in summary["docked_range"].items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
