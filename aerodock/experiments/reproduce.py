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
Step 5 and the costs of the levers the paper leaves unstated depend on nothing the other steps
compute, and the tuned controller's steps 2-4 only on the paper's model: on a machine with two
cores they run on a second process (:func:`aerodock.processes.side_worker`; step 5 from the
start, the other two once step 1 has saved its models), with the same numbers.

"Without model" is the paper's LQG baseline (bias observer); "with model" adds the learnt model's
feed-forward. The oracle (true mean field) is run as an upper bound.
"""

from __future__ import annotations

import contextlib
import os
import platform
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from aerodock.config import Config
from aerodock.control.observer_response import bias_step_response
from aerodock.control.profiles import controller_config
from aerodock.downwash import build_field
from aerodock.downwash.mean import has_mean
from aerodock.experiments.controller_costs import controller_costs
from aerodock.experiments.docking_runs import docking_experiments
from aerodock.experiments.paper_counts import paper_outcome_probabilities
from aerodock.experiments.provenance import provenance
from aerodock.experiments.records import (
    UNITS,
    ControllersRecord,
    DockingRecord,
    LearningRecord,
    OursController,
    PaperController,
    Record,
    ReproduceResults,
    RunHeader,
    TargetsResult,
    TunedController,
)
from aerodock.experiments.run_size import (  # SHORT_MISSION: where tests and studies find it
    FULL,
    QUICK,
    SHORT_MISSION,  # noqa: F401
    SMOKE,
    RunSize,
)
from aerodock.experiments.targets import learnt_mean_check, targets
from aerodock.fileio import building_dir, check_output_dir, json_ready, one_line, write_json
from aerodock.processes import SideWorker, side_worker

if TYPE_CHECKING:
    from aerodock.flightlog import FlightLog
    from aerodock.learning.dataset import Dataset
    from aerodock.learning.runtime import Predictor


WRENCH_ROW = "ours + learnt wrench (thrust-basis so2-wrench, torque feed-forward)"


OUTPUTS = ("results.json", "report.md", "figures", "data", "data-wrench")
"""What ``reproduce --out`` holds: the folder is replaced as a whole by the next reproduction."""


@dataclass
class LearningData:
    """What step 1 of the reproduction learns from: see :func:`learning_data`."""

    curriculum: dict[str, Any]  # run_curriculum's summary
    deep_predictor: Predictor  # the deep curriculum's model (down to the docking depth)
    predictor: Predictor  # the paper's curriculum's model (the deep one without deep stages)
    test_ds: Dataset  # held-out excitation flights
    train_logs: list[FlightLog]  # the curriculum's flights, then the sample-efficiency pool
    deep_model_dir: Path  # where deep_predictor was loaded from
    model_dir: Path  # where predictor was loaded from


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
    from aerodock.collect.curriculum import curriculum_stages, excitation_flights, run_curriculum
    from aerodock.flightlog import load_flightlogs
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
    deep_dir = data_dir / "models" / "final"
    paper_dir = data_dir / "models" / "paper" if "paper_model" in curriculum else deep_dir
    deep_predictor = Predictor.load(deep_dir)
    predictor = Predictor.load(paper_dir) if paper_dir != deep_dir else deep_predictor
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
    return LearningData(curriculum, deep_predictor, predictor, test_ds, train_logs, deep_dir,
                        paper_dir)


def run_reproduce(cfg: Config, out_dir: Path, quick: bool = False, seed: int = 0,
                  say: Callable[[str], None] = print,
                  shared_data: Path | None = None,
                  bar: Callable[[str, int, int], None] | None = None,
                  smoke: bool = False) -> ReproduceResults:
    """Run every experiment and write ``results.json``, ``report.md`` and ``figures/``.

    ``quick`` is a smaller run (a few minutes); ``smoke`` the smallest that crosses every step
    (for checking a plug-in field or a config end to end; it implies ``quick``).

    ``bar(description, done, total)``, if given, follows training epochs and the sample-efficiency
    runs (a progress bar); ``say`` reports each step. The folder is written as a whole
    (:func:`aerodock.fileio.building_dir`): it is built beside ``out_dir`` and swapped in at the
    end, so a kill leaves the old reproduction or the new one, never a mix; ``out_dir`` may hold
    only what a reproduction writes (:data:`OUTPUTS`).

    Returns:
        The results (``results.json`` is their :meth:`~ReproduceResults.to_json`), their paths
        naming ``out_dir``.
    """
    out_dir = Path(out_dir)
    check_output_dir(out_dir, OUTPUTS)
    with building_dir(out_dir, OUTPUTS) as work:
        results, report_error = _reproduce_into(cfg, work, out_dir, quick, seed, say,
                                                shared_data, bar, smoke)
    if report_error is not None:  # after the folder is in place: nothing flown is lost
        raise ReportError(f"{out_dir}: the experiments ran and results.json holds their "
                          f"numbers, but the report or a figure failed: {report_error}")
    return results


class ReportError(RuntimeError):
    """The experiments ran and ``results.json`` is written, but ``report.md`` or a figure
    could not be made (what is written stays written)."""


@dataclass
class _Run:
    """One reproduction: its settings, the folder being built and what its steps share."""

    cfg: Config  # the run size's overrides applied
    size: RunSize
    seed: int
    say: Callable[[str], None]
    bar: Callable[[str, int, int], None] | None
    out_dir: Path  # the folder being built
    named: Path  # the folder it becomes
    timings: dict[str, float] = field(default_factory=dict)
    traces: dict[str, Any] = field(default_factory=dict)

    @property
    def fig_dir(self) -> Path:
        return self.out_dir / "figures"

    def train_kwargs(self) -> dict[str, Any] | None:
        """What each curriculum stage's training is given: the progress bar, the epoch cap."""
        epochs: dict[str, Any] = {}
        if self.bar is not None:
            bar = self.bar
            epochs["progress"] = lambda e, n, *_: bar("training epochs", e, n)
        if self.size.train_max_epochs is not None:
            epochs["max_epochs"] = self.size.train_max_epochs
        return epochs or None

    def timed(self, key: str, t0: float) -> None:
        """Record the wall-clock time since ``t0`` (``time.perf_counter``) as ``key``."""
        self.timings[key] = time.perf_counter() - t0


def _reproduce_into(cfg: Config, out_dir: Path, named: Path, quick: bool, seed: int,
                    say: Callable[[str], None], shared_data: Path | None,
                    bar: Callable[[str, int, int], None] | None, smoke: bool = False
                    ) -> tuple[ReproduceResults, str | None]:
    """:func:`run_reproduce` writing into the folder ``out_dir`` (being built), its results
    naming the folder ``named`` it becomes; and why the report failed (None: it did not)."""
    from aerodock.experiments.report import write_report

    quick = quick or smoke
    size = SMOKE if smoke else QUICK if quick else FULL
    header = _run_header(cfg, size, quick, smoke, seed)
    if size.overrides:
        cfg = cfg.with_overrides(size.overrides, source="reproduce's run size")
    run = _Run(cfg, size, seed, say, bar, Path(out_dir), named)
    run.fig_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    # Step 5, the levers' costs and the tuned controller's rows depend on nothing the
    # simulations after them compute: they run on a second process beside the rest (the same
    # numbers: every training runs on one thread and every campaign draws its own trials'
    # streams, wherever they run).
    with side_worker() as side, _cores_shared_with(side) as share_cores:
        if not side.run_here:
            say(("the real-data study and the levers' costs run" if _real_dir(shared_data)
                 else "the levers' costs run") + " on a second process, beside the rest")
        real_data_job = side.submit(_real_data_job, shared_data, run.fig_dir, quick, smoke, seed,
                                    run.cfg)
        share_cores()
        learned, learning = _learning_step(run)
        costs_job = side.submit(_costs_job, run.cfg, run.size, run.seed,
                                learned.model_dir,
                                learned.deep_model_dir if run.size.target_all_rows else None)
        # the tuned controller's steps 2-4 need only the paper's model: after the levers' costs
        tuned_job = (side.submit(_tuned_job, run.cfg, run.size, run.seed, learned.model_dir)
                     if run.size.tuned_row else None)
        if tuned_job is not None and not side.run_here:
            run.say("    the tuned controller's steps 2-4 run on the second process too")
        share_cores()
        se = _sample_efficiency_step(run, learned)
        share_cores()
        docking, controllers = _controllers_step(run, learned)
        paper_counts = paper_outcome_probabilities(
            docking.hover_docking.with_model, docking.hover_docking.without_model,
            docking.cable_study)
        share_cores()
        targets_result, wrench_curriculum = _targets_step(run, learned, controllers.ours)
        costs = _costs_step(run, costs_job)
        if tuned_job is not None:
            controllers = replace(controllers,
                                  tuned=_tuned_step(run, tuned_job, here=side.run_here))
        real_data, compensation = _real_data_step(run, real_data_job)
    run.timings["total_s"] = time.perf_counter() - started
    results = ReproduceResults(
        aerodock_reproduce=header, units=UNITS,
        learning=replace(learning, wrench_curriculum=wrench_curriculum),
        sample_efficiency=se, docking=docking, paper_counts=paper_counts,
        controllers=controllers, targets=targets_result, controller_costs=costs,
        real_data=real_data, compensation=compensation, timings_s=run.timings)
    say("writing results.json, report.md and figures/")
    report_error = None
    try:
        figures = write_report(results, run.traces, run.out_dir, cfg)
    except Exception as err:  # noqa: BLE001 - a figure or the report failed after the run:
        # the numbers are still written, and the failure is said in one line at the end
        figures, report_error = None, one_line(f"{type(err).__name__}: {err}")
    # Paths name the folder the run becomes, not the one it is built in; a figure that could not
    # be computed (NaN) is written as null.
    results = _renamed(replace(results, figures=figures), run.out_dir, named)
    write_json(run.out_dir / "results.json", json_ready(results.to_json()))
    return results, report_error


def _run_header(cfg: Config, size: RunSize, quick: bool, smoke: bool, seed: int) -> RunHeader:
    """How the run was asked for: ``cfg`` as resolved from --config and --set (before the run
    size's overrides), the code's version and the machine."""
    return RunHeader(quick=quick, smoke=smoke, seed=seed, provenance=provenance(cfg),
                     size_overrides=size.overrides,
                     machine=f"{platform.machine()}, {os.cpu_count()} cores, "
                             f"Python {platform.python_version()}")


def _learning_step(run: _Run) -> tuple[LearningData, LearningRecord]:
    """Step 1: the curriculum and its models, judged on held-out flights."""
    from aerodock.learning.evaluate import evaluate

    t0 = time.perf_counter()
    run.say("1/5 curriculum data collection and training")
    learned = learning_data(run.cfg, run.size, run.out_dir / "data", run.seed, say=run.say,
                            train_kwargs=run.train_kwargs(), name_as=run.named / "data")
    heldout_eval = evaluate(learned.deep_predictor, learned.test_ds)
    record = LearningRecord(curriculum=learned.curriculum, heldout=heldout_eval,
                            heldout_paper_model=evaluate(learned.predictor, learned.test_ds),
                            **_floor_ratio(heldout_eval, run.cfg))
    run.timed("curriculum_s", t0)
    return learned, record


def _sample_efficiency_step(run: _Run, learned: LearningData) -> dict[str, Any]:
    """Held-out RMSE against minutes of training data for the SO(2), extended SO(2) and MLP
    models."""
    from aerodock.experiments.sample_efficiency import sample_efficiency
    from aerodock.learning.dataset import build_dataset

    t0 = time.perf_counter()
    run.say("    sample efficiency (so2, so2-ext, mlp)")
    size = run.size
    se = sample_efficiency(
        build_dataset(learned.train_logs), learned.test_ds, kinds=("so2", "so2-ext", "mlp"),
        minutes=size.se_minutes, seeds=size.se_seeds, out_dir=run.fig_dir,
        train_kwargs={"max_epochs": size.se_max_epochs} if size.se_max_epochs else None,
        progress=run.bar,
    )
    run.timed("sample_efficiency_s", t0)
    return se


def _controllers_step(run: _Run, learned: LearningData
                      ) -> tuple[DockingRecord, ControllersRecord]:
    """Steps 2-4 flown by the paper's controller (the reproduction, its traces the figures'),
    then by ours; the tuned controller's row is :func:`_tuned_job`'s, left None here."""
    cfg, size, seed, say = run.cfg, run.size, run.seed, run.say
    paper_cfg = controller_config(cfg, "paper")
    docking, traces, times = docking_experiments(paper_cfg, size, learned.predictor, seed, say,
                                                  "paper's controller")
    run.traces.update(traces)
    run.timings.update(times)
    paper = PaperController(
        source="as its flight stack publishes it: Freyja's LQR weights in every phase, "
               "Freyja's bias estimator and state filter, 50 Hz, no reference feed-forward",
        q_diag=list(paper_cfg.control.q_diag),
        terminal_q_diag=list(paper_cfg.control.terminal_q_diag),
        bias_estimator=paper_cfg.control.bias_estimator,
        command_rate_hz=paper_cfg.control.command_rate_hz,
        reference_ff_factor=paper_cfg.control.reference_ff_factor,
        observer_rise_63_s=bias_step_response(paper_cfg).rise_63_s)
    ours_cfg = controller_config(cfg, "ours")
    ours_docking, _, times = docking_experiments(
        ours_cfg, size, learned.deep_predictor, seed, say,
        "our controller (accelerometer observer, deep model)")
    ours = OursController(
        source="tuned + the accelerometer observer (INDI-like), with the deep curriculum's "
               "model", accel_observer_tau_s=ours_cfg.control.accel_observer_tau_s,
        terminal_q_diag=list(ours_cfg.control.terminal_q_diag), docking=ours_docking)
    run.timings.update({f"ours_{k}": v for k, v in times.items()})
    return docking, ControllersRecord(paper=paper, tuned=None, ours=ours)


def _tuned_job(cfg: Config, size: RunSize, seed: int, model: Path
               ) -> tuple[DockingRecord, dict[str, float]]:
    """Steps 2-4 flown by the tuned controller with the model saved in ``model`` (the paper's
    curriculum's), and their timings (picklable: it may run on another process; every campaign
    draws its own trials' streams, so its numbers are the same wherever it runs)."""
    from aerodock.learning.runtime import Predictor

    docking, _, times = docking_experiments(controller_config(cfg, "tuned"), size,
                                            Predictor.load(model), seed, lambda _line: None,
                                            "tuned controller")
    return docking, times


def _tuned_step(run: _Run, job: Callable[[], tuple[DockingRecord, dict[str, float]]],
                here: bool) -> TunedController:
    """The tuned controller's row (:func:`_tuned_job`, waited for through ``job``; ``here``:
    the job runs in this process now)."""
    cfg = run.cfg
    if here:
        run.say("2-4/5 cable-length study, hover docking and the moving leader, tuned controller")
    docking, times = job()
    run.timings.update({f"tuned_{k}": v for k, v in times.items()})
    return TunedController(
        source="the configuration's weights (terminal gain schedule)",
        q_diag=list(cfg.control.q_diag), terminal_q_diag=list(cfg.control.terminal_q_diag),
        observer_bias_tau_s=cfg.control.observer_bias_tau_s, docking=docking)


def _targets_step(run: _Run, learned: LearningData, ours: OursController
                  ) -> tuple[TargetsResult, dict[str, Any] | None]:
    """The targets beyond the paper for each (controller, model) row, and (in a full run) the
    learnt wrench's curriculum (returned beside the targets: ``None`` when not flown)."""
    from aerodock.collect.curriculum import run_curriculum
    from aerodock.learning.runtime import Predictor

    cfg, say, deep = run.cfg, run.say, learned.deep_predictor
    t0 = time.perf_counter()
    say("    targets beyond the paper: d_p 0.36 and 0.27 m, leader at 0.25 and 0.5 m/s")
    paper_cfg, ours_cfg = controller_config(cfg, "paper"), controller_config(cfg, "ours")
    ours_tff_cfg = ours_cfg.with_overrides({"control": {"torque_feedforward": True}})
    rows = {
        "paper's controller + paper's model": (paper_cfg, learned.predictor),
        "paper's controller + deep model": (paper_cfg, deep),
        "tuned + deep model": (cfg, deep),
        "ours + deep model": (ours_cfg, deep),
        "ours + torque feed-forward + deep model": (ours_tff_cfg, deep),
    }
    wrench_predictor = wrench_curriculum = None
    if run.size.target_all_rows:
        # The learnt wrench: so2-wrench on thrust-basis labels (the force on the body alone),
        # its learnt torque fed to the autopilot; a curriculum of its own, flown the same way.
        say("    learnt wrench: the deep curriculum again, so2-wrench on thrust-basis labels")
        wrench_cfg = cfg.with_overrides({"curriculum": {"label_basis": "thrust"}})
        wrench_curriculum = run_curriculum(wrench_cfg, run.out_dir / "data-wrench", seed=run.seed,
                                           model_kind="so2-wrench",
                                           progress=lambda m: say("    " + m),
                                           train_kwargs=run.train_kwargs(),
                                           name_as=run.named / "data-wrench")
        wrench_predictor = Predictor.load(run.out_dir / "data-wrench" / "models" / "final")
        rows[WRENCH_ROW] = (ours_tff_cfg, wrench_predictor)
    else:
        rows = {k: v for k, v in rows.items() if k in ("paper's controller + paper's model",
                                                       "ours + deep model")}
    result = targets(rows, run.size.target_trials, deep, run.seed + 5, say)
    result = replace(
        result, learnt_mean_paper_model=learnt_mean_check(cfg, learned.predictor),
        learnt_mean_wrench_model=(None if wrench_predictor is None
                                  else learnt_mean_check(cfg, wrench_predictor)))
    run.timed("targets_s", t0)
    return result, wrench_curriculum


def _costs_job(cfg: Config, size: RunSize, seed: int, model: Path, ours_model: Path | None
               ) -> tuple[dict[str, Any], float]:
    """What each lever the paper leaves unstated costs, flown with the models saved in
    ``model`` (the paper's curriculum's) and ``ours_model`` (None: none for ours); and its
    seconds of wall time. Picklable: it may run on another process."""
    from aerodock.learning.runtime import Predictor

    t0 = time.perf_counter()
    costs = controller_costs(
        cfg, size.costs, Predictor.load(model), seed + 3,
        ours_predictor=None if ours_model is None else Predictor.load(ours_model))
    return costs, time.perf_counter() - t0


def _costs_step(run: _Run, job: Callable[[], tuple[dict[str, Any], float]]) -> dict[str, Any]:
    """What each lever the paper leaves unstated costs (:func:`_costs_job`, waited for through
    ``job``); ``controller_costs_s`` is the job's own wall time, wherever it ran."""
    run.say("    what each unstated lever costs: observer bandwidth, terminal gains, gripper "
            "window")
    costs, seconds = job()
    run.timings["controller_costs_s"] = seconds
    return costs


@contextlib.contextmanager
def _cores_shared_with(side: SideWorker) -> Iterator[Callable[[], None]]:
    """Yields a function to call between steps: the simulations' threads (numba's, for a
    period's blocks of trials) leave a core to the side worker while it works, and take it back
    when it is done (a period's blocks wait for each other, so a block on a core the worker
    holds would slow them all). numba's thread count is restored on leaving."""
    import numba

    before = numba.get_num_threads()

    def share() -> None:
        numba.set_num_threads(max(1, before - 1) if side.busy() else before)

    try:
        yield share
    finally:
        numba.set_num_threads(before)


def _real_dir(shared_data: Path | None) -> Path | None:
    """The real-data study's flights (``neural-swarm/swap_ss`` in the data location), or None
    when the data location lacks them."""
    real_dir = None if shared_data is None else shared_data / "neural-swarm" / "swap_ss"
    return real_dir if real_dir is not None and real_dir.is_dir() else None


def _real_data_job(shared_data: Path | None, fig_dir: Path, quick: bool, smoke: bool, seed: int,
                   cfg: Config) -> tuple[dict[str, Any] | None, dict[str, Any] | None,
                                         list[str], float]:
    """Step 5's work (picklable: it may run on another process): the real-data study and the
    compensations scored on real flights, each ``None`` when the data location lacks their
    flights; the lines to say about it; its seconds of wall time."""
    t0 = time.perf_counter()
    real_dir = _real_dir(shared_data)
    if real_dir is None or shared_data is None:
        why = ("no data location: --no-real-data, or neither --data-dir nor AERODOCK_DATA_DIR"
               if shared_data is None else f"{shared_data / 'neural-swarm' / 'swap_ss'} not found")
        return None, None, [f"5/5 real-data study skipped ({why})"], time.perf_counter() - t0
    from aerodock.experiments.compensation_study import FOLDERS, compensation_section
    from aerodock.experiments.real_data import real_data_study

    other = shared_data / "neural-swarm" / "swap_sl_2020-06-19"
    real = real_data_study(real_dir, fig_dir, quick=quick, seed=seed,
                           other_pair=other if other.is_dir() else None, smoke=smoke)
    compensation = None
    lines = ["5/5 real-data study (Neural-Swarm, leave flights out)"]
    if all((shared_data / "neural-swarm" / name).is_dir() for name in FOLDERS):
        lines.append("    the compensations scored on real flights (held-out swap flights)")
        compensation = compensation_section(shared_data, fig_dir, quick=quick, smoke=smoke,
                                            seed=seed, cfg=cfg)
    else:
        lines.append("    the compensations not scored (swap_ss and swap_sl_2020-06-19 both "
                     "needed)")
    return real, compensation, lines, time.perf_counter() - t0


def _real_data_step(run: _Run,
                    job: Callable[[], tuple[dict[str, Any] | None, dict[str, Any] | None,
                                            list[str], float]]
                    ) -> tuple[dict[str, Any] | None, dict[str, Any] | None]:
    """Step 5: the real-data study and the compensations scored on real flights
    (:func:`_real_data_job`, its result waited for through ``job``), each ``None`` when the data
    location lacks its flights. ``real_data_s`` is the job's own wall time, wherever it ran."""
    real, compensation, lines, seconds = job()
    for line in lines:
        run.say(line)
    run.timings["real_data_s"] = seconds
    return real, compensation


def _renamed(node: Any, built: Path, named: Path) -> Any:
    """``node`` with every string path inside ``built`` (the folder being built) naming the same
    file inside ``named`` (the folder it becomes), in records, dicts and lists at any depth."""
    if isinstance(node, Record):
        return replace(node, **{f.name: _renamed(getattr(node, f.name), built, named)
                                for f in fields(node)})
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
