"""Running a sweep: one docking campaign per cell, on local processes or on Ray.

Every cell is a campaign of :func:`aerodock.mission.batch.run_campaign` with its own seed, so a
cell's numbers do not depend on where or in which order it runs: the local and the Ray backends
give the same table (tested). Cells that differ only in their seed share a world and are flown as
one batch (:func:`batches`), each trial drawing its own cell's numbers: the same table, at the
cost per trial of a larger batch. The table is tidy: one row per trial, the cell's settings in
columns beside the trial's outcome (:data:`OUTCOME_COLUMNS`).

With a :class:`aerodock.sweep.store.CellStore`, every cell is saved as it finishes and a cell
already in the store's folders is taken from there instead of flown (``sweep --resume``).
An interrupt (Ctrl-C) or any other exception while local worker processes run stops them all
before it propagates: the workers ignore ``SIGINT`` (a terminal's Ctrl-C reaches the whole
process group; the driver alone reacts, so no worker prints a traceback) and are terminated.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable
from concurrent.futures import Future, as_completed
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.processes import (
    portable_call,
    sigint_ignored,
    single_threaded_children,
    stop_pool,
    worker_pool,
)
from aerodock.sweep.spec import Cell, SweepSpec, cell_config, check_against_config
from aerodock.sweep.store import OUTCOME_NAMES, CellStore, cell_key, cell_settings, model_digest

OUTCOME_COLUMNS = (
    ("trial", "trial index within the campaign"),
    ("docked", "the bar was captured (bool)"),
    ("missed", "the gate closed without the bar (bool)"),
    ("slipped", "the bar slipped through the closing gate (bool)"),
    ("aborted", "the mission aborted (bool)"),
    ("abort_reason", "none | timeout | leader_lost | unsafe_tracking"),
    ("clearance_violation", "the follower's top came closer than clearance_m (bool)"),
    ("min_clearance_m", "closest follower-top to leader distance, m"),
    ("capture_time_s", "mission time of the capture, s (empty if not docked)"),
    ("err_down_m", "mean |vertical tracking error| over the final 0.5 s of the approach, m"),
    ("err_3d_m", "mean 3-D tracking error over the same window, m"),
)

Progress = Callable[[int, int], None]
Rows = list[dict[str, Any]]


def cell_rows(cell: Cell, cell_cfg: Config, outcomes: list[dict[str, Any]]) -> Rows:
    """A cell's rows of the tidy table: its settings (the cable length the config gives when the
    cell sets none) beside each trial's outcome."""
    base = cell.row()
    if base["cable_length_m"] is None:
        base["cable_length_m"] = cell_cfg.platform.cable_length_m
    return [{**base, **outcome} for outcome in outcomes]


def run_cell(cfg: Config, cell: Cell, trials: int, model: str | None) -> Rows:
    """Fly one cell's campaign on ``cfg`` (the sweep's configuration; the cell's config keys,
    controller and noise scale are applied here); its rows of the tidy table."""
    return run_cells(cfg, (cell,), trials, model)[0][1]


def run_cells(cfg: Config, cells: tuple[Cell, ...], trials: int, model: str | None
              ) -> list[tuple[int, Rows]]:
    """Fly cells that differ only in their campaign seed (:func:`same_world`) as one batch
    (each trial draws the numbers it draws in its own cell's campaign:
    :func:`aerodock.mission.batch.run_campaign`'s ``seeds``); (cell index, its rows) each."""
    from aerodock.mission import AbortReason, MissionSpec, run_campaign

    first = cells[0]
    if any(same_world(c) != same_world(first) for c in cells):
        raise ValueError("cells flown as one batch must differ only in their seed")
    cfg = cell_config(cfg, first)
    predictor = None
    if first.compensation == "model":
        from aerodock.learning.runtime import Predictor

        predictor = Predictor.load(model)
    spec = MissionSpec(trials=trials * len(cells), offset_m=first.cable_length_m,
                       leader_speed_mps=first.leader_speed_mps, compensation=first.compensation,
                       seed=first.seed, leader_dropout_s=first.leader_dropout_s)
    res = run_campaign(cfg, spec, predictor, trials=np.tile(np.arange(trials), len(cells)),
                       seeds=np.repeat([c.seed for c in cells], trials))
    out = []
    for k, cell in enumerate(cells):
        part = res.take(np.arange(k * trials, (k + 1) * trials))
        outcomes = []
        for i in range(trials):
            cap = float(part.capture_time_s[i])
            outcomes.append({"trial": i, "docked": bool(part.success[i]),
                             "missed": bool(part.missed[i]), "slipped": bool(part.slipped[i]),
                             "aborted": bool(part.aborted[i]),
                             "abort_reason": AbortReason(int(part.abort_reason[i])).name.lower(),
                             "clearance_violation": bool(part.clearance_violation[i]),
                             "min_clearance_m": float(part.min_clearance_m[i]),
                             "capture_time_s": None if np.isnan(cap) else cap,
                             "err_down_m": float(part.err_down_m[i]),
                             "err_3d_m": float(part.err_3d_m[i])})
        out.append((cell.index, cell_rows(cell, cfg, outcomes)))
    return out


def same_world(cell: Cell) -> Cell:
    """``cell`` without its index and seed: cells equal under it fly the same world and mission
    and can be flown as one batch."""
    return replace(cell, index=0, seed=0)


def batches(cells: list[Cell], workers: int) -> list[tuple[Cell, ...]]:
    """The cells grouped into batches of cells that share a world (:func:`same_world`), in the
    order of their first cell; a batch is split in halves while there are fewer batches than
    ``workers`` (each worker then has one to fly)."""
    groups: dict[Cell, list[Cell]] = {}
    for cell in cells:
        groups.setdefault(same_world(cell), []).append(cell)
    out = [tuple(g) for g in groups.values()]
    while len(out) < workers:
        big = max(range(len(out)), key=lambda i: len(out[i]))
        if len(out[big]) < 2:
            break
        half = (len(out[big]) + 1) // 2
        out[big:big + 1] = [out[big][:half], out[big][half:]]
    return out


def _cell_job(cfg_data: dict[str, Any], cfg_source: str, cells: tuple[Cell, ...], trials: int,
              model: str | None) -> list[tuple[int, Rows]]:
    """A picklable job: one batch of cells; (cell index, rows) each."""
    return run_cells(Config(cfg_data, cfg_source), cells, trials, model)


def _run_local(args: list[tuple], workers: int, finished: Callable[[int, Rows], None]) -> None:
    """The batches of cells on ``workers`` local processes (or in this process for one
    worker); ``finished(cell index, rows)`` for each cell."""
    if workers == 1:
        for a in args:
            for done in _cell_job(*a):
                finished(*done)
        return
    # Fresh interpreters with one BLAS/OpenMP thread each: N processes on N cores (inherited
    # thread pools oversubscribe the cores and spin in the kernel).
    with single_threaded_children(), sigint_ignored():
        pool = worker_pool(workers)
        futures: list[Future] = []
        try:
            # (the first submit starts the workers)
            futures = [pool.submit(portable_call, _cell_job, *a) for a in args]
        except BaseException:
            stop_pool(pool, futures)
            raise
    try:
        for fut in as_completed(futures):
            for done in fut.result():
                finished(*done)
    except BaseException:
        stop_pool(pool, futures)
        raise
    pool.shutdown(wait=True)


def run_sweep(spec: SweepSpec, cfg: Config, backend: str = "local", jobs: int | None = None,
              address: str | None = None, progress: Progress | None = None,
              store: CellStore | None = None) -> Rows:
    """Every cell of ``spec``; the rows of the tidy table, ordered by cell then trial.

    Args:
        spec: the sweep.
        cfg: the configuration every cell starts from.
        backend: ``"local"`` (processes on this machine) or ``"ray"``.
        jobs: parallel workers (local: processes, default the CPU count; ray: CPUs of a local
            Ray instance it starts, default all).
        address: an existing Ray cluster's address (``ray`` backend), e.g. ``"auto"``.
        progress: called as ``progress(done, total)`` after every cell (and once first with
            the cells taken from ``store``, if any).
        store: where every cell is saved as it finishes, and where finished cells are looked
            up (its ``reuse_from``); its ``reused`` and ``flown`` lists say which was which.

    Raises:
        SweepSpecError: a cell ``dock`` would refuse, or a campaign too large.
        ValueError: an unknown backend, or ``jobs`` < 1.
    """
    if backend not in ("local", "ray"):
        raise ValueError(f"--backend must be local or ray, got {backend!r}")
    if jobs is not None and jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {jobs}")
    check_against_config(spec, cfg)  # every cell as dock would check it, before any runs
    model = None if spec.model is None else str(spec.model)
    results: dict[int, Rows] = {}
    total = len(spec.cells)
    saved: dict[int, tuple[str, dict[str, Any]]] = {}
    if store is not None:
        saved = _look_up(spec, cfg, model, store, results)
        if results and progress:
            progress(len(results), total)

    def finished(idx: int, rows: Rows) -> None:
        if store is not None:
            key, settings = saved[idx]
            store.save(key, settings, [{k: r[k] for k in OUTCOME_NAMES} for r in rows])
            store.flown.append(idx)
        results[idx] = rows
        if progress:
            progress(len(results), total)

    left = [c for c in spec.cells if c.index not in results]
    workers = jobs or os.cpu_count() or 1
    args = [(cfg.data, cfg.source, batch, spec.trials, model)
            for batch in batches(left, workers)]
    if args and backend == "local":
        _run_local(args, min(workers, len(args)), finished)
    elif args:
        _run_ray(args, jobs, address, finished)
    return [row for idx in sorted(results) for row in results[idx]]


def _look_up(spec: SweepSpec, cfg: Config, model: str | None, store: CellStore,
             results: dict[int, Rows]) -> dict[int, tuple[str, dict[str, Any]]]:
    """Every cell's key and settings; the cells ``store`` holds go into ``results``."""
    digest = model_digest(model) if any(c.compensation == "model" for c in spec.cells) else None
    configs: dict[str, Config] = {}
    saved = {}
    for cell in spec.cells:
        point = repr((cell.settings, cell.controller, cell.mocap_noise_scale))
        if point not in configs:
            configs[point] = cell_config(cfg, cell)
        settings = cell_settings(configs[point], cell, spec.trials, digest)
        key = cell_key(settings)
        saved[cell.index] = (key, settings)
        store.keys[cell.index] = key
        outcomes = store.load(key, spec.trials)
        if outcomes is not None:
            results[cell.index] = cell_rows(cell, configs[point], outcomes)
            store.reused.append(cell.index)
    return saved


def _run_ray(args: list[tuple], jobs: int | None, address: str | None,
             finished: Callable[[int, Rows], None]) -> None:
    """The cells as Ray tasks; ``finished(cell index, rows)`` as each one ends.

    A Ray instance started here (no ``address``, Ray not yet initialised) is watched by
    :class:`aerodock.sweep.raycleanup.RayReaper` (no Ray process outlives a killed driver), and
    ``SIGTERM`` stops the sweep with ``ray.shutdown()`` and exit status 143
    (:func:`aerodock.sweep.raycleanup.sigterm_exits_cleanly`).
    """
    try:
        import ray
    except ImportError:
        raise ValueError("--backend ray needs Ray: pip install 'aerodock[ray]'") from None
    from aerodock.sweep.raycleanup import RayReaper, reinstall_sigterm, sigterm_exits_cleanly

    started_here = not ray.is_initialized()
    with contextlib.ExitStack() as stack:
        if started_here:
            stack.enter_context(sigterm_exits_cleanly())
            if address is None:
                stack.enter_context(RayReaper())
        try:
            if started_here:
                if address is not None:
                    ray.init(address=address, log_to_driver=False)
                else:
                    ray.init(num_cpus=jobs, include_dashboard=False, log_to_driver=False)
                reinstall_sigterm()  # ray.init put its C++ failure handler on SIGTERM
            _ray_cells(ray, args, finished)
        finally:
            if started_here:
                ray.shutdown()


def _ray_cells(ray: Any, args: list[tuple], finished: Callable[[int, Rows], None]) -> None:
    """Submit every batch of cells and collect each cell's rows (waits in short slices:
    signals get through)."""
    job = ray.remote(num_cpus=1)(_cell_job)
    pending = [job.remote(*a) for a in args]
    while pending:
        done, pending = ray.wait(pending, num_returns=1, timeout=0.5)
        for ref in done:
            for cell_done in ray.get(ref):
                finished(*cell_done)


def columns(rows: list[dict[str, Any]]) -> list[str]:
    """Column names of the tidy table, in order."""
    return list(rows[0]) if rows else []


def write_table(rows: list[dict[str, Any]], out_dir: Path) -> dict[str, str]:
    """Write ``results.csv`` (always) and ``results.parquet`` (if pyarrow is installed)."""
    import csv
    import io

    from aerodock.fileio import atomic_open

    out_dir = Path(out_dir)
    names = columns(rows)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=names, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: "" if v is None else repr(v) if isinstance(v, float) else v
                         for k, v in row.items()})
    with atomic_open(out_dir / "results.csv", "w") as fh:
        fh.write(buf.getvalue())
    written = {"csv": str(out_dir / "results.csv")}
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    table = pa.Table.from_pylist(rows)
    with atomic_open(out_dir / "results.parquet", "wb") as fh:
        pq.write_table(table, fh)
    written["parquet"] = str(out_dir / "results.parquet")
    return written
