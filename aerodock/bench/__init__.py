"""The measured speed of every hot path (``aerodock bench``; README, "Performance").

Each figure is the median of several timed repetitions after an untimed warm-up, reported with
its spread (the fastest and slowest repetition) and the number of repetitions. A figure whose
part is not available (PyTorch, ONNX Runtime, RotorPy not installed, no ``reproduce`` command)
is ``null`` with a one-line ``reason``; the benchmark never fails because of it.

Figures (``aerodock bench --json``; ``--quick`` runs fewer, shorter repetitions):

- ``simulator``: vehicle-steps per second (trials x 2 vehicles x physics steps) for batches of
  1, 64, 256 and 1024 trials: the whole world (both vehicles, bar, gripper, default downwash) at
  500 Hz physics with both position controllers (LQR + bias observer) at 100 Hz
  (``with_controllers``), and the physics alone under held commands (``physics_only``), with
  rigid-body vehicles (``[vehicle] model = "rigid-body"``: attitude, rotors, autopilot, IMU).
- ``simulator_point_mass``: the same with point-mass vehicles (``model = "point-mass"``), for
  comparison. Each simulator figure also gives ``per_cpu_s``: vehicle-steps per second of the
  process's CPU time (median), which a busy shared machine does not dilute.
- ``simulator_python_field``: the rigid-body world with a plug-in field written in Python (the
  template's uniform column) instead of the compiled jet, at batches of 1 and 256: what a
  Python term between the compiled ones costs.
- ``kernels``: a fresh process's import and first two control periods with the compiled kernels
  cached (``cached_s``) and, without ``--quick``, with an empty cache (``cold_s``: every kernel
  compiled, about a minute).
- ``vehicle_step``: the vehicles' own step alone (``Fleet.step`` on 2n vehicles: for rigid
  bodies the autopilot, rotor wrench and attitude step), per model and batch of 1, 256 and 1024.
- ``docking``: wall time of one docking trial and of a 100-trial campaign
  (:func:`aerodock.mission.batch.run_campaign`, oracle compensation, summary only).
- ``predictor``: the learnt model's time per single-sample call and per sample in a batch of 1024,
  for the NumPy runtime, ONNX Runtime and PyTorch (reference), all on one thread.
- ``training``: wall time to train the SO(2)-equivariant model on 5 minutes of data.
- ``reproduce_quick``: wall time of ``aerodock reproduce --quick`` (one run, subprocess).
- ``memory``: peak memory of a 1024-trial campaign (fresh subprocesses): of the whole process,
  and of the campaign's own allocations.
- ``gym_vector_env``: env-steps per second of :class:`aerodock.envs.DockingVectorEnv` at 1, 128
  and 256 environments (:func:`aerodock.bench.vector_env.bench_vector_env`; needs
  ``aerodock[gym]``).
- ``gym_env_reset``: wall time of :meth:`aerodock.envs.DockingEnv.reset`: a trial settled alone,
  a reset that settles a block of upcoming trials, one served from the block, and the mean over
  a block's resets (:func:`aerodock.bench.env_reset.bench_env_reset`; needs ``aerodock[gym]``).
- ``peer``: the RotorPy comparison of ``studies/compare_rotorpy.py`` (:func:`compare_rotorpy`),
  and ``peer_crazyflow``: crazyflow, aerodock's rigid body and aerodock's full world on the same
  scenario at batches of 1, 256 and 1024 (:func:`compare_crazyflow`; needs ``aerodock[peer]``,
  else one line says why).

The same functions serve ``studies/compare_rotorpy.py`` and the pytest-benchmark tests.
:func:`run_all` measures them all (or one part, :data:`PARTS`) as one JSON-ready document.

Modules: :mod:`~aerodock.bench.timing` (how a figure is measured), :mod:`~aerodock.bench.simulator`,
:mod:`~aerodock.bench.docking` (with ``reproduce --quick``), :mod:`~aerodock.bench.learning`
(training and the predictor), :mod:`~aerodock.bench.memory` (a campaign in a fresh process,
``python -m aerodock.bench.memory``), :mod:`~aerodock.bench.vector_env`,
:mod:`~aerodock.bench.env_reset`,
:mod:`~aerodock.bench.peer` (RotorPy), :mod:`~aerodock.bench.peer_batches` (crazyflow),
:mod:`~aerodock.bench.report` (machine, targets, the
table's rows) and :mod:`~aerodock.bench.node` (the ROS 2 node's latency, on its own:
``python -m aerodock.bench.node``).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from aerodock.bench.timing import Progress, quiet  # (no NumPy)
from aerodock.lazy import lazy_names

# The names below load their modules on first use: the command line lists :data:`PARTS` for
# ``bench --only`` at start-up, and every command (``aerodock --help`` too) would otherwise wait
# for NumPy and the bench's modules.
_HOMES = {
    **dict.fromkeys(("bench_docking", "bench_reproduce"), "aerodock.bench.docking"),
    **dict.fromkeys(("bench_predictor", "bench_training", "predictor_inputs",
                     "synthetic_dataset"), "aerodock.bench.learning"),
    **dict.fromkeys(("PEER_CONTROL_HZ", "PEER_HOVER_S", "PEER_MOVE_NED_M", "PEER_MOVE_S",
                     "PEER_PHYSICS_HZ", "compare_rotorpy", "peer_aerodock", "peer_reference",
                     "peer_rotorpy", "peer_rotorpy_batched"), "aerodock.bench.peer"),
    **dict.fromkeys(("PEER_BATCHES", "compare_crazyflow"), "aerodock.bench.peer_batches"),
    **dict.fromkeys(("TARGETS", "machine_info", "table_rows", "targets"),
                    "aerodock.bench.report"),
    **dict.fromkeys(("SIM_BATCHES", "SimLoop", "bench_kernels", "bench_python_field",
                     "bench_simulator", "bench_vehicle_step"), "aerodock.bench.simulator"),
    **dict.fromkeys(("failure_reason", "figure", "measure", "unavailable"),
                    "aerodock.bench.timing"),
}

__all__ = sorted([*_HOMES, "PARTS", "Progress", "quiet", "run_all"])

__getattr__ = lazy_names(__name__, _HOMES)


PARTS = ("simulator", "docking", "predictor", "memory", "reproduce", "gym", "peer")


def run_all(cfg: Any, quick: bool = False, progress: Progress = quiet,
            include_reproduce: bool | None = None, include_peer: bool = True,
            config_path: Path | None = None, only: str | None = None) -> dict[str, Any]:
    """Every figure (see the module docstring), as a JSON-ready document.

    ``config_path`` is the file ``cfg`` came from (if any), for the subprocesses; ``only`` (one
    of :data:`PARTS`) measures that part alone (``predictor`` includes training).
    """
    import aerodock.bench as b  # each part read from the package (loaded on use, or replaced)

    if only is not None and only not in PARTS:
        raise ValueError(f"unknown bench part {only!r}; choose one of {', '.join(PARTS)}")

    def wanted(part: str) -> bool:
        return only is None or only == part

    started = time.perf_counter()
    figs: dict[str, Any] = {}
    if wanted("simulator"):
        figs["simulator"] = b.bench_simulator(cfg, quick=quick, progress=progress,
                                              model="rigid-body")
        figs["simulator_point_mass"] = b.bench_simulator(cfg, quick=quick, progress=progress,
                                                         model="point-mass")
        figs["vehicle_step"] = b.bench_vehicle_step(cfg, quick=quick, progress=progress)
        figs["simulator_python_field"] = b.bench_python_field(cfg, quick=quick,
                                                              progress=progress)
        figs["kernels"] = b.bench_kernels(cold=not quick, progress=progress)
    if wanted("docking"):
        figs["docking"] = b.bench_docking(cfg, quick=quick, progress=progress)
    if wanted("predictor"):
        figs["training"], trained = b.bench_training(cfg, quick=quick, progress=progress)
        figs["predictor"] = b.bench_predictor(trained, quick=quick, progress=progress)
    if wanted("memory"):
        from aerodock.bench.memory import bench_memory  # also the probe's script: not eager

        figs["memory"] = bench_memory(progress=progress, config_path=config_path)
    if include_reproduce is None:
        include_reproduce = not quick or only == "reproduce"
    if wanted("reproduce"):
        figs["reproduce_quick_s"] = (
            b.bench_reproduce(progress, config_path) if include_reproduce
            else b.unavailable("skipped with --quick (takes minutes)", "s"))
    if wanted("gym"):
        try:
            from aerodock.bench.env_reset import bench_env_reset
            from aerodock.bench.vector_env import bench_vector_env
        except ImportError as err:  # gymnasium is an optional extra
            why = b.failure_reason(err)
            figs["gym_vector_env"] = {"1": b.unavailable(why, "env-steps/s")}
            figs["gym_env_reset"] = {"block_mean_reset": b.unavailable(why, "s")}
        else:
            figs["gym_vector_env"] = bench_vector_env(cfg, quick=quick, progress=progress)
            figs["gym_env_reset"] = bench_env_reset(cfg, quick=quick, progress=progress)
    if include_peer and wanted("peer"):
        figs["peer"] = b.compare_rotorpy(cfg, quick=quick, progress=progress)
        figs["peer_crazyflow"] = b.compare_crazyflow(cfg, quick=quick, progress=progress)
    return {
        "machine": b.machine_info(),
        "settings": {"quick": quick, "physics_rate_hz": cfg.sim.physics_rate_hz,
                     "control_rate_hz": cfg.sim.control_rate_hz,
                     "statistic": "median of the repetitions after a warm-up; min and max "
                                  "give the spread"},
        "figures": figs,
        "targets": b.targets(figs),
        "bench_wall_s": round(time.perf_counter() - started, 1),
    }
