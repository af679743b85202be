"""``aerodock reproduce``: the paper's experiments end to end, in simulation, with the learnt model.

1. curriculum data collection and training (the paper's SO(2) model) and the sample-efficiency
   study (SO(2), extended SO(2), plain MLP);
2. the cable-length study (leader on a rigid stand, six offsets (three with ``--quick``), with
   and without the model);
3. docking with the leader hovering (d_p = 0.36 m, four start locations);
4. the leader in motion at 0.25 m/s (meet at 6 s, hold formation for 5 s);
5. the real-data study on the Neural-Swarm flights, when the data location holds them
   (:mod:`aerodock.ingest.data_dir`);
then ``results.json``, ``report.md`` and ``figures/`` (:mod:`aerodock.experiments.report`).

"Without model" is the paper's LQG baseline (bias observer); "with model" adds the learnt model's
feed-forward. The oracle (true mean field) is run as an upper bound.
"""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import Compensation
from aerodock.control.observer_response import bias_step_response
from aerodock.control.profiles import controller_config
from aerodock.downwash import build_field
from aerodock.downwash.mean import has_mean, mean_acceleration_fn, mean_source
from aerodock.experiments.cable_study import CABLE_OFFSETS_M, cable_study
from aerodock.experiments.controller_costs import (
    GATE_HEIGHTS_M,
    OBSERVER_TAUS_S,
    TERMINAL_MIX,
    CostSize,
    controller_costs,
)
from aerodock.experiments.paper_counts import paper_outcome_probabilities
from aerodock.experiments.provenance import provenance
from aerodock.experiments.targets import learnt_mean_check, targets
from aerodock.fileio import building_dir, check_output_dir, json_ready, write_json
from aerodock.mission import CampaignResult, MissionSpec, Phase, run_campaign

if TYPE_CHECKING:
    from aerodock.flightlog import FlightLog
    from aerodock.learning.dataset import Dataset
    from aerodock.learning.runtime import Predictor


@dataclass(frozen=True)
class RunSize:
    """How big each experiment is (``--quick`` or full)."""

    cable_reps: int
    cable_offsets_m: tuple[float, ...]
    hover_trials: int
    moving_trials: int
    se_minutes: tuple[float, ...]
    se_seeds: tuple[int, ...]
    se_pool_flights: int
    test_flights_per_stage: int
    se_max_time_s: float | None
    costs: CostSize  # the sweeps of the levers the paper leaves unstated
    target_trials: int
    target_all_rows: bool  # every controller + model row (quick: the paper's and ours only)
    # [curriculum] keys changed for this size ({}: the configuration's curriculum) and the
    # training epochs of each stage's model (None: train's own stopping rule)
    curriculum: dict[str, Any] = field(default_factory=dict)
    train_max_epochs: int | None = None
    tuned_row: bool = True  # the tuned controller's experiments (its code is ours' minus one term)
    # config overrides for this size ({}: the configuration's own): the smoke run cuts the
    # mission's waiting times (:data:`SHORT_MISSION`)
    overrides: dict[str, Any] = field(default_factory=dict)


SHORT_MISSION: dict[str, dict[str, float]] = {
    "mission": {"settle_s": 1.0, "post_dock_s": 0.5, "dock_window_s": 1.0, "backoff_s": 1.0,
                "leader_ramp_s": 1.0},
    "planner": {"hold_s": 2.0}}
"""The mission's waiting times cut: settled start 1 s (configured: 3), hold after capture 0.5 s,
docking window and back-off 1 s, a moving leader's ramp 1 s and hold 2 s. A docked hover trial
flies 5.1 simulated seconds instead of 8.1 (settled start included); what the mission achieves
changes, every step it takes does not. ``reproduce --smoke`` flies it (it checks that a field
or a config goes through, not a figure), and the tests of properties that hold whatever the
timing."""

QUICK = RunSize(cable_reps=2, cable_offsets_m=(0.36, 0.87, 1.35), hover_trials=24,
                moving_trials=8, se_minutes=(0.5, 2),
                se_seeds=(0,), se_pool_flights=0, test_flights_per_stage=2, se_max_time_s=5.0,
                costs=CostSize(trials=8, taus_s=(4.0,), mixes=(0.0, 1.0),
                               cable_offsets_m=(0.36,), cable_reps=2, gate_heights_m=(0.10,)),
                target_trials=4,
                target_all_rows=False)
# The smallest run that crosses every step (one offset, a handful of trials, one sample-efficiency
# point, one observer setting): for checking that a plug-in field or a config goes through the
# whole pipeline, not for any figure.
SMOKE = RunSize(cable_reps=1, cable_offsets_m=(0.36,), hover_trials=4, moving_trials=2,
                se_minutes=(0.5,), se_seeds=(0,), se_pool_flights=0, test_flights_per_stage=1,
                se_max_time_s=3.0,
                costs=CostSize(trials=2, taus_s=(), mixes=(0.0,), cable_offsets_m=(0.36,),
                               cable_reps=1, gate_heights_m=()),
                target_trials=2, target_all_rows=False,
                # two paper stages and one deep stage of two flights each (the configuration's
                # curriculum flies seven stages of five to ten): every step, at its smallest
                curriculum={"stage_step_m": 0.65, "deep_depths_m": [0.27],
                            "flights_per_stage": 2, "deep_flights_per_stage": 2},
                train_max_epochs=20, tuned_row=False, overrides=SHORT_MISSION)
FULL = RunSize(cable_reps=10, cable_offsets_m=CABLE_OFFSETS_M, hover_trials=200, moving_trials=100,
               se_minutes=(0.5, 1, 2, 5, 10), se_seeds=(0, 1, 2), se_pool_flights=25,
               test_flights_per_stage=4, se_max_time_s=None,
               costs=CostSize(trials=60, taus_s=OBSERVER_TAUS_S, mixes=TERMINAL_MIX,
                              cable_offsets_m=CABLE_OFFSETS_M, cable_reps=10,
                              gate_heights_m=GATE_HEIGHTS_M),
               target_trials=100, target_all_rows=True)


WRENCH_ROW = "ours + learnt wrench (thrust-basis so2-wrench, torque feed-forward)"


OUTPUTS = ("results.json", "report.md", "figures", "data", "data-wrench")
"""What ``reproduce --out`` holds: the folder is replaced as a whole by the next reproduction."""


def _window_mean(trace: dict[str, np.ndarray], t0: float, t1: float) -> dict[str, Any]:
    """Mean |vertical error| (follower vs its reference) in [t0, t1) over approaching trials."""
    t = trace["t_s"]
    sel = (t >= t0) & (t < t1)
    err = np.abs(trace["follower_p"][sel, :, 2] - trace["ref_p"][sel, :, 2])
    ok = trace["phase"][sel] <= Phase.TERMINAL
    per_trial = np.array([np.mean(err[ok[:, i], i]) if ok[:, i].any() else np.nan
                          for i in range(err.shape[1])])
    good = per_trial[np.isfinite(per_trial)]
    return {"window_s": [t0, t1], "mean_abs_err_down_m": float(np.mean(good)) if good.size
            else None, "sd_m": float(np.std(good)) if good.size else None,
            "trials": int(good.size)}


def _campaign_record(res: CampaignResult) -> dict[str, Any]:
    s = res.summary()
    s["arrival_s"] = res.arrival_s
    return s


def _traces_subset(res: CampaignResult, keep: int) -> dict[str, np.ndarray]:
    return {k: (v[:, :keep] if v.ndim >= 2 else v) for k, v in res.trace.items()}


def _docking_experiments(cfg: Config, size: RunSize, predictor: Any, seed: int,
                         say: Callable[[str], None], label: str
                         ) -> tuple[dict[str, Any], dict[str, Any], dict[str, float]]:
    """The cable-length study, hover docking and the moving leader with one controller.

    Returns (results by experiment, traces for the figures, timings).
    """
    results: dict[str, Any] = {}
    traces: dict[str, Any] = {}
    timings: dict[str, float] = {}
    # 2. Cable-length study -----------------------------------------------------------------
    t0 = time.perf_counter()
    say(f"2/5 cable-length study (leader on a rigid stand), {label}")
    results["cable_study"], traces["cable"] = cable_study(
        cfg, size.cable_offsets_m, size.cable_reps, predictor, seed, record="trace")
    timings["cable_study_s"] = time.perf_counter() - t0

    # 3. Hover docking ----------------------------------------------------------------------
    t0 = time.perf_counter()
    say(f"3/5 docking with the leader hovering ({size.hover_trials} trials per mode), {label}")
    hover: dict[str, Any] = {"offset_m": 0.36, "aperture_m": cfg.gripper.aperture_m,
                             "trials": size.hover_trials}
    hover_res: dict[str, CampaignResult] = {}
    for key, comp in (("without_model", Compensation.OBSERVER),
                      ("with_model", Compensation.MODEL), ("oracle", Compensation.ORACLE)):
        res = run_campaign(cfg, MissionSpec(trials=size.hover_trials, offset_m=0.36,
                                            compensation=comp, seed=seed + 1), predictor,
                           record="trace")
        hover[key] = _campaign_record(res)
        hover_res[key] = res
    w, m = hover["without_model"], hover["with_model"]
    err_w, err_m = w["terminal_err_down_median_m"], m["terminal_err_down_median_m"]
    hover["terminal_error_reduction_x"] = (None if err_w is None or err_m is None
                                           else err_w / max(err_m, 1e-9))
    hover["oracle_mean_source"] = mean_source(mean_acceleration_fn(build_field(cfg)))
    results["hover_docking"] = hover
    traces["hover"] = {k: _trace_keep(v) for k, v in hover_res.items()}
    timings["hover_s"] = time.perf_counter() - t0

    # 4. Leader in motion --------------------------------------------------------------------
    t0 = time.perf_counter()
    say(f"4/5 leader in motion at 0.25 m/s ({size.moving_trials} trials per mode), {label}")
    moving: dict[str, Any] = {"leader_speed_mps": 0.25, "meet_s": cfg.planner.horizon_moving_s,
                              "hold_s": cfg.planner.hold_s, "trials": size.moving_trials}
    moving_traces = {}
    meet, hold = cfg.planner.horizon_moving_s, cfg.planner.hold_s
    n = size.moving_trials
    armed = (True,) * n + (False,) * n
    for key, comp in (("without_model", Compensation.OBSERVER),
                      ("with_model", Compensation.MODEL)):
        # Docking, and formation tracking as in the paper's figure: the same flights with the
        # gripper disarmed, flown in one batch (trial ids 0..n-1 twice; outcomes are per trial).
        both = run_campaign(cfg, MissionSpec(trials=2 * n, offset_m=0.36, leader_speed_mps=0.25,
                                             compensation=comp, seed=seed + 2,
                                             passive_trigger=armed, active_trigger=armed),
                            predictor, record="trace", trials=np.r_[0:n, 0:n])
        dock_res, track = both.take(np.arange(n)), both.take(np.arange(n, 2 * n))
        rec = _campaign_record(dock_res)
        rec["altitude_error_approach"] = _window_mean(track.trace, meet - 2.0, meet)
        rec["altitude_error_hold"] = _window_mean(track.trace, meet, meet + hold)
        moving[key] = rec
        moving_traces[key] = track.trace
    results["moving_leader"] = moving
    traces["moving"] = moving_traces
    timings["moving_s"] = time.perf_counter() - t0

    return results, traces, timings


@dataclass
class LearningData:
    """What step 1 of the reproduction learns from: see :func:`learning_data`."""

    curriculum: dict[str, Any]  # run_curriculum's summary
    deep_predictor: Predictor  # the deep curriculum's model (down to the docking depth)
    predictor: Predictor  # the paper's curriculum's model (the deep one without deep stages)
    test_ds: Dataset  # held-out excitation flights
    train_logs: list[FlightLog]  # the curriculum's flights, then the sample-efficiency pool


def learning_data(cfg: Config, size: RunSize, data_dir: Path, seed: int = 0, *,
                  say: Callable[[str], None] = print,
                  train_kwargs: dict[str, Any] | None = None,
                  name_as: Path | None = None) -> LearningData:
    """Step 1 of the reproduction: the curriculum (data and models) in ``data_dir``, held-out
    excitation flights (``size.test_flights_per_stage`` per stage, saved as ``heldout.npz``) and
    the sample-efficiency pool (``size.se_pool_flights // 5`` more flights per stage, flown with
    the paper's model, added to the curriculum's flights).

    ``train_kwargs`` go to each stage's training; ``name_as`` is the folder the results name
    (``data_dir`` itself unless it is being built under another name)."""
    from aerodock.flightlog import load_flightlogs
    from aerodock.learning.curriculum import curriculum_stages, excitation_flights, run_curriculum
    from aerodock.learning.datafiles import save_dataset
    from aerodock.learning.dataset import build_dataset
    from aerodock.learning.runtime import Predictor

    data_dir = Path(data_dir)
    learn_cfg = cfg.with_overrides({"curriculum": size.curriculum}) if size.curriculum else cfg
    curriculum = run_curriculum(learn_cfg, data_dir, seed=seed,
                                progress=lambda m: say("    " + m),
                                train_kwargs=train_kwargs, name_as=name_as)
    # The deep curriculum's model (down to the docking depth) and the paper's (down to 0.5 m),
    # trained before the deep stages: the reproduction flies the paper's.
    deep_predictor = Predictor.load(data_dir / "models" / "final")
    predictor = (Predictor.load(data_dir / "models" / "paper")
                 if "paper_model" in curriculum else deep_predictor)
    test_logs = []
    for st in curriculum_stages(learn_cfg):
        test_logs += excitation_flights(cfg, size.test_flights_per_stage, st.depth_min_m,
                                        st.depth_max_m, seed + 7919 + st.index,
                                        name=f"test{st.index}")
    test_ds = build_dataset(test_logs)
    save_dataset(data_dir / "heldout.npz", test_ds)
    train_logs = [lg for st in curriculum_stages(learn_cfg)
                  for lg in load_flightlogs(data_dir / f"stage{st.index}.npz")]
    if size.se_pool_flights:
        # More flights (nominal controller + the paper's model) so that 10 minutes exist to
        # draw from.
        for st in curriculum_stages(learn_cfg):
            train_logs += excitation_flights(cfg, size.se_pool_flights // 5, st.depth_min_m,
                                             st.depth_max_m, seed + 4241 + st.index, predictor,
                                             name=f"pool{st.index}")
    return LearningData(curriculum, deep_predictor, predictor, test_ds, train_logs)


def run_reproduce(cfg: Config, out_dir: Path, quick: bool = False, seed: int = 0,
                  say: Callable[[str], None] = print,
                  shared_data: Path | None = None,
                  bar: Callable[[str, int, int], None] | None = None,
                  smoke: bool = False) -> dict[str, Any]:
    """Run every experiment and write ``results.json``, ``report.md`` and ``figures/``.

    ``quick`` is a smaller run (a few minutes); ``smoke`` the smallest that crosses every step
    (for checking a plug-in field or a config end to end; it implies ``quick``).

    ``bar(description, done, total)``, if given, follows training epochs and the sample-efficiency
    runs (a progress bar); ``say`` reports each step. The folder is written as a whole
    (:func:`aerodock.fileio.building_dir`): it is built beside ``out_dir`` and swapped in at the
    end, so a kill leaves the old reproduction or the new one, never a mix; ``out_dir`` may hold
    only what a reproduction writes (:data:`OUTPUTS`)."""
    out_dir = Path(out_dir)
    check_output_dir(out_dir, OUTPUTS)
    with building_dir(out_dir, OUTPUTS) as work:
        return _reproduce_into(cfg, work, out_dir, quick, seed, say, shared_data, bar, smoke)


def _reproduce_into(cfg: Config, out_dir: Path, named: Path, quick: bool, seed: int,
                    say: Callable[[str], None], shared_data: Path | None,
                    bar: Callable[[str, int, int], None] | None, smoke: bool = False
                    ) -> dict[str, Any]:
    """:func:`run_reproduce` writing into the folder ``out_dir`` (being built), its results
    naming the folder ``named`` it becomes."""
    from aerodock.experiments.report import write_report
    from aerodock.experiments.sample_efficiency import sample_efficiency
    from aerodock.learning.curriculum import run_curriculum
    from aerodock.learning.dataset import build_dataset
    from aerodock.learning.evaluate import evaluate
    from aerodock.learning.runtime import Predictor

    quick = quick or smoke
    size = SMOKE if smoke else QUICK if quick else FULL
    given = provenance(cfg)  # the config as resolved from --config and --set, the code's version
    if size.overrides:
        cfg = cfg.with_overrides(size.overrides, source="reproduce's run size")
    out_dir = Path(out_dir)
    fig_dir = out_dir / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    timings: dict[str, float] = {}
    traces: dict[str, Any] = {}
    results: dict[str, Any] = {
        "aerodock_reproduce": {"quick": quick, "smoke": smoke, "seed": seed,
                               **given, "size_overrides": size.overrides,
                               "machine": f"{platform.machine()}, {os.cpu_count()} cores, "
                                          f"Python {platform.python_version()}"},
        "units": {"errors": "m", "integrals_over_0.5s": "m*s (errors), m/s (force)",
                  "accelerations": "m/s^2, NED (down positive)", "rates": "fraction"},
    }

    # 1. Curriculum + training ---------------------------------------------------------------
    t0 = time.perf_counter()
    say("1/5 curriculum data collection and training")
    data_dir = out_dir / "data"
    epochs: dict[str, Any] = {}
    if bar is not None:
        epochs["progress"] = lambda e, n, *_: bar("training epochs", e, n)
    if size.train_max_epochs is not None:
        epochs["max_epochs"] = size.train_max_epochs
    learning = learning_data(cfg, size, data_dir, seed, say=say, train_kwargs=epochs or None,
                             name_as=named / "data")
    curriculum, test_ds, train_logs = learning.curriculum, learning.test_ds, learning.train_logs
    deep_predictor, predictor = learning.deep_predictor, learning.predictor
    heldout_eval = evaluate(deep_predictor, test_ds)
    results["learning"] = {
        "curriculum": curriculum,
        "heldout": heldout_eval,
        "heldout_paper_model": evaluate(predictor, test_ds),
        **_floor_ratio(heldout_eval, cfg),
    }
    timings["curriculum_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    say("    sample efficiency (so2, so2-ext, mlp)")
    se = sample_efficiency(
        build_dataset(train_logs), test_ds, kinds=("so2", "so2-ext", "mlp"),
        minutes=size.se_minutes, seeds=size.se_seeds, out_dir=fig_dir,
        train_kwargs={"max_time_s": size.se_max_time_s} if size.se_max_time_s else None,
        progress=bar,
    )
    results["sample_efficiency"] = se
    timings["sample_efficiency_s"] = time.perf_counter() - t0

    # 2-4. Docking experiments: the paper's controller (the reproduction), then ours --------
    paper_cfg = controller_config(cfg, "paper")
    docking, traces_paper, times = _docking_experiments(paper_cfg, size, predictor, seed, say,
                                                        "paper's controller")
    results.update(docking)
    results["paper_counts"] = paper_outcome_probabilities(
        docking["hover_docking"]["with_model"], docking["hover_docking"]["without_model"],
        docking["cable_study"])
    traces.update(traces_paper)
    timings.update(times)
    results["controllers"] = {
        "paper": {"source": "as its flight stack publishes it: Freyja's LQR weights in every "
                            "phase, Freyja's bias estimator and state filter, 50 Hz, no reference "
                            "feed-forward",
                  "q_diag": list(paper_cfg.control.q_diag),
                  "terminal_q_diag": list(paper_cfg.control.terminal_q_diag),
                  "bias_estimator": paper_cfg.control.bias_estimator,
                  "command_rate_hz": paper_cfg.control.command_rate_hz,
                  "reference_ff_factor": paper_cfg.control.reference_ff_factor,
                  "observer_rise_63_s": bias_step_response(paper_cfg).rise_63_s},
    }
    if size.tuned_row:
        tuned, _, times = _docking_experiments(controller_config(cfg, "tuned"), size, predictor,
                                               seed, say, "tuned controller")
        results["controllers"]["tuned"] = {
            "source": "the configuration's weights (terminal gain schedule)",
            "q_diag": list(cfg.control.q_diag),
            "terminal_q_diag": list(cfg.control.terminal_q_diag),
            "observer_bias_tau_s": cfg.control.observer_bias_tau_s, **tuned}
        timings.update({f"tuned_{k}": v for k, v in times.items()})
    ours_cfg = controller_config(cfg, "ours")
    ours, _, times = _docking_experiments(ours_cfg, size, deep_predictor, seed, say,
                                          "our controller (accelerometer observer, deep model)")
    results["controllers"]["ours"] = {
        "source": "tuned + the accelerometer observer (INDI-like), with the deep curriculum's "
                  "model", "accel_observer_tau_s": ours_cfg.control.accel_observer_tau_s,
        "terminal_q_diag": list(ours_cfg.control.terminal_q_diag), **ours}
    timings.update({f"ours_{k}": v for k, v in times.items()})
    t0 = time.perf_counter()
    say("    targets beyond the paper: d_p 0.36 and 0.27 m, leader at 0.25 and 0.5 m/s")
    ours_tff_cfg = ours_cfg.with_overrides({"control": {"torque_feedforward": True}})
    rows = {
        "paper's controller + paper's model": (paper_cfg, predictor),
        "paper's controller + deep model": (paper_cfg, deep_predictor),
        "tuned + deep model": (cfg, deep_predictor),
        "ours + deep model": (ours_cfg, deep_predictor),
        "ours + torque feed-forward + deep model": (ours_tff_cfg, deep_predictor),
    }
    wrench_predictor = None
    if size.target_all_rows:
        # The learnt wrench: so2-wrench on thrust-basis labels (the force on the body alone),
        # its learnt torque fed to the autopilot; a curriculum of its own, flown the same way.
        say("    learnt wrench: the deep curriculum again, so2-wrench on thrust-basis labels")
        wrench_cfg = cfg.with_overrides({"curriculum": {"label_basis": "thrust"}})
        wrench_curriculum = run_curriculum(wrench_cfg, out_dir / "data-wrench", seed=seed,
                                           model_kind="so2-wrench",
                                           progress=lambda m: say("    " + m),
                                           train_kwargs=epochs or None,
                                           name_as=named / "data-wrench")
        results["learning"]["wrench_curriculum"] = wrench_curriculum
        wrench_predictor = Predictor.load(out_dir / "data-wrench" / "models" / "final")
        rows[WRENCH_ROW] = (ours_tff_cfg, wrench_predictor)
    else:
        rows = {k: v for k, v in rows.items() if k in ("paper's controller + paper's model",
                                                       "ours + deep model")}
    results["targets"] = targets(rows, size.target_trials, deep_predictor, seed + 5, say)
    results["targets"]["learnt_mean_paper_model"] = learnt_mean_check(cfg, predictor)
    if wrench_predictor is not None:
        results["targets"]["learnt_mean_wrench_model"] = learnt_mean_check(cfg,
                                                                            wrench_predictor)
    timings["targets_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    say("    what each unstated lever costs: observer bandwidth, terminal gains, gripper window")
    results["controller_costs"] = controller_costs(
        cfg, size.costs, predictor, seed + 3,
        ours_predictor=deep_predictor if size.target_all_rows else None)
    timings["controller_costs_s"] = time.perf_counter() - t0

    # 5. Real data ----------------------------------------------------------------------------
    t0 = time.perf_counter()
    real_dir = None if shared_data is None else shared_data / "neural-swarm" / "swap_ss"
    if real_dir is not None and real_dir.is_dir():
        say("5/5 real-data study (Neural-Swarm, leave flights out)")
        from aerodock.experiments.real_data import real_data_study

        other = shared_data / "neural-swarm" / "swap_sl_2020-06-19"
        results["real_data"] = real_data_study(real_dir, fig_dir, quick=quick, seed=seed,
                                               other_pair=other if other.is_dir() else None,
                                               smoke=smoke)
        from aerodock.experiments.compensation_study import FOLDERS, compensation_section

        if all((shared_data / "neural-swarm" / name).is_dir() for name in FOLDERS):
            say("    the compensations scored on real flights (held-out swap flights)")
            results["compensation"] = compensation_section(shared_data, fig_dir, quick=quick,
                                                           seed=seed, cfg=cfg)
        else:
            say("    the compensations not scored (swap_ss and swap_sl_2020-06-19 both needed)")
            results["compensation"] = None
    else:
        why = ("no data location: --no-real-data, or neither --data-dir nor AERODOCK_DATA_DIR"
               if shared_data is None else f"{real_dir} not found")
        say(f"5/5 real-data study skipped ({why})")
        results["real_data"] = results["compensation"] = None
    timings["real_data_s"] = time.perf_counter() - t0

    results["timings_s"] = timings
    results["timings_s"]["total_s"] = time.perf_counter() - started
    say("writing results.json, report.md and figures/")
    figures = write_report(results, traces, out_dir, cfg)
    results["figures"] = figures
    # Paths name the folder the run becomes, not the one it is built in; a figure that could not
    # be computed (NaN) is written as null.
    results = _renamed(results, out_dir, named)
    write_json(out_dir / "results.json", json_ready(results))
    return results


def _renamed(node: Any, built: Path, named: Path) -> Any:
    """``node`` with every string path inside ``built`` (the folder being built) naming the same
    file inside ``named`` (the folder it becomes)."""
    if isinstance(node, dict):
        return {k: _renamed(v, built, named) for k, v in node.items()}
    if isinstance(node, list):
        return [_renamed(v, built, named) for v in node]
    if isinstance(node, str) and (node == str(built) or node.startswith(f"{built}{os.sep}")):
        return str(named) + node[len(str(built)):]
    return node


def _floor_ratio(heldout_eval: dict[str, Any], cfg: Config) -> dict[str, Any]:
    """The model's held-out RMSE over the error floor, per region, and where the floor's mean
    field came from; ``None`` (with a note for ``report.md``) where no floor could be computed.

    The floor needs the simulator's mean field recorded beside each label
    (``World.true_mean_field_mps2``). A plug-in field without ``mean_acceleration`` has it only
    if the world estimates it (:func:`aerodock.downwash.mean.mean_acceleration_fn`); otherwise
    the figure is reported as unavailable rather than guessed.
    """
    ratio: dict[str, float | None] = {}
    for region in ("all", "interaction"):
        floor = heldout_eval[region].get("error_floor")
        floor_rmse = None if floor is None else floor["rmse_mps2"]["overall"]
        model_rmse = heldout_eval[region]["model"]["rmse_mps2"]["overall"]
        ratio[region] = (model_rmse / floor_rmse if floor_rmse and model_rmse is not None
                         else None)
    exact = has_mean(build_field(cfg))
    if all(v is None for v in ratio.values()):
        note = (f"unavailable: the field {cfg.downwash.field} has no mean_acceleration() and "
                "the recorded flights carry no estimate of its mean, so no error floor (and no "
                "ratio to it) is computed" if not exact else
                "unavailable: no held-out label had a recorded mean field")
    elif exact:
        note = "the field's own mean_acceleration(), recorded beside each label"
    else:
        note = (f"estimated: the field {cfg.downwash.field} has no mean_acceleration(); its mean "
                "was estimated by averaging acceleration() over turbulence samples "
                "(aerodock.downwash.mean)")
    return {"rmse_ratio_to_floor": ratio, "error_floor_source": note}


def _trace_keep(res: CampaignResult) -> dict[str, Any]:
    tr = dict(res.trace)
    tr["success"] = res.success
    tr["arrival_s"] = res.arrival_s
    return tr
