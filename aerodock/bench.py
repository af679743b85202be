"""``aerodock bench``: the measured speed of every hot path (README, "Performance").

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
- ``gym_vector_env``: env-steps per second of :class:`aerodock.envs.DockingVectorEnv` at 1 and
  256 environments (:func:`aerodock.envs.bench.bench_vector_env`; needs ``aerodock[gym]``).
- ``peer``: the RotorPy comparison of ``bench/compare_rotorpy.py`` (:func:`compare_rotorpy`).

The same functions serve ``bench/compare_rotorpy.py`` and the pytest-benchmark tests.
"""

from __future__ import annotations

import contextlib
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

SIM_BATCHES = (1, 64, 256, 1024)
TARGETS = {
    "vehicle_steps_per_s_at_256": 500_000.0,  # rigid-body world (issue 10)
    "point_mass_vehicle_steps_per_s_at_256": 1_000_000.0,
    "rotorpy_sequential_speedup": 20.0,
    "predictor_single_call_us": 50.0,
    "reproduce_quick_s": 300.0,
}
_SUBPROCESS_TIMEOUT_S = 1800.0

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    pass


# -- measuring ---------------------------------------------------------------------------------
def measure(fn: Callable[[], Any], repeats: int, warmup: int = 1,
            setup: Callable[[], Any] | None = None,
            cpu_times: list[float] | None = None) -> list[float]:
    """Wall times (s) of ``repeats`` calls of ``fn`` after ``warmup`` untimed ones.

    ``setup``, if given, runs (untimed) before every call, the warm-up ones included; the
    process CPU time of each timed call is appended to ``cpu_times`` if given.
    """
    times = []
    for i in range(warmup + repeats):
        if setup is not None:
            setup()
        c0 = time.process_time()
        t0 = time.perf_counter()
        fn()
        if i >= warmup:
            times.append(time.perf_counter() - t0)
            if cpu_times is not None:
                cpu_times.append(time.process_time() - c0)
    return times


def figure(samples: list[float], unit: str, note: str | None = None) -> dict[str, Any]:
    """A figure: median of ``samples`` with its spread (min and max) and repetition count."""
    out: dict[str, Any] = {
        "value": float(statistics.median(samples)),
        "min": float(min(samples)),
        "max": float(max(samples)),
        "repeats": len(samples),
        "unit": unit,
    }
    if note:
        out["note"] = note
    return out


def unavailable(reason: str, unit: str = "") -> dict[str, Any]:
    """A figure that could not be measured, and why."""
    return {"value": None, "unit": unit, "reason": reason}


def _reason(err: BaseException) -> str:
    text = str(err).splitlines()[0] if str(err) else ""
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


# -- simulator ---------------------------------------------------------------------------------
class SimLoop:
    """N trials of the world with both position controllers, as :func:`run_campaign` flies them.

    The leader hovers; the follower holds a point 0.6 m below it, 5 cm off the wake's axis (in
    the wake, the bar above it). ``run(k)`` flies ``k`` control periods: motion capture, both
    controllers (LQR + bias observer, 100 Hz), then ``substeps`` physics steps (500 Hz).
    ``run(k, controllers=False)`` holds level hover commands: the physics alone.
    """

    def __init__(self, cfg: Any, n: int, seed: int = 0):
        from aerodock.control.controller import PositionController, Reference
        from aerodock.rng import TrialRNG
        from aerodock.world import World, hover_command

        self.n = n
        self.cfg = cfg
        self.world = World(cfg, n, TrialRNG(seed, n))
        self.leader_p = np.tile([0.0, 0.0, -cfg.mission.leader_altitude_m], (n, 1))
        self.follower_p = self.leader_p + np.array([0.05, 0.0, 0.6])
        self.leader_ctl = PositionController(cfg, n, use_observer=True)
        self.follower_ctl = PositionController(cfg, n, use_observer=True)
        zero3, zero = np.zeros((n, 3)), np.zeros(n)
        self.leader_ref = Reference(self.leader_p, zero3, zero3, zero, zero)
        self.follower_ref = Reference(self.follower_p, zero3, zero3, zero, zero)
        self.hover = hover_command(self.world.vehicle, n)
        self.reset()

    def reset(self) -> None:
        """Back to the start: both vehicles at rest, controllers reset (every run flies the
        same scenario, so repetitions time the same work)."""
        world = self.world
        world.reset(self.leader_p, self.follower_p)
        self.leader_ctl.reset(world.leader.p, world.leader.v,
                              world.cable_force_n / self.cfg.vehicle.mass_kg)
        self.follower_ctl.reset(world.follower.p, world.follower.v)

    @property
    def vehicle_steps_per_period(self) -> int:
        """Vehicle-steps in one control period: trials x 2 vehicles x physics substeps."""
        return 2 * self.n * self.world.substeps

    def run(self, periods: int, controllers: bool = True) -> None:
        """Fly ``periods`` control periods."""
        world = self.world
        lead_cmd = fol_cmd = self.hover
        for _ in range(periods):
            if controllers:
                obs_l, obs_f = world.observe()
                lead_cmd = self.leader_ctl.step(obs_l.p, obs_l.v, obs_l.rpy,
                                                self.leader_ref).command
                fol_cmd = self.follower_ctl.step(obs_f.p, obs_f.v, obs_f.rpy,
                                                 self.follower_ref).command
            world.advance(lead_cmd, fol_cmd)


def bench_simulator(cfg: Any, batches: tuple[int, ...] = SIM_BATCHES, quick: bool = False,
                    progress: Progress = _quiet, model: str | None = None) -> dict[str, Any]:
    """Vehicle-steps per second, with controllers and physics only, per batch size.

    ``model`` (``"rigid-body"`` or ``"point-mass"``) overrides ``cfg``'s ``[vehicle] model``.
    """
    if model is not None:
        cfg = cfg.with_overrides({"vehicle": {"model": model}}, source="bench")
    out: dict[str, Any] = {}
    repeats = 3 if quick else 5
    for n in batches:
        progress(f"simulator ({cfg.vehicle.model}): batch of {n}")
        loop = SimLoop(cfg, n)
        # About 0.1-0.3 s per repetition on a 2-core machine.
        periods = max(4, int((100 if n <= 64 else 60 if n <= 256 else 24) * (0.5 if quick else 1)))
        steps = loop.vehicle_steps_per_period * periods
        row = {}
        for key, ctl in (("with_controllers", True), ("physics_only", False)):
            cpu: list[float] = []
            times = measure(lambda loop=loop, k=periods, ctl=ctl: loop.run(k, ctl), repeats,
                            warmup=1, setup=loop.reset, cpu_times=cpu)
            row[key] = figure([steps / t for t in times], "vehicle-steps/s")
            # Per second of this process's CPU time: what wall time would be on an idle core
            # (on a shared machine the wall-time figure also counts other processes' turns).
            row[key]["per_cpu_s"] = float(statistics.median(steps / max(c, 1e-9) for c in cpu))
        row["with_controllers"]["note"] = (
            f"{cfg.vehicle.model}, {n} trials x 2 vehicles, 500 Hz physics, LQR + observer at "
            "100 Hz")
        row["physics_only"]["note"] = f"{cfg.vehicle.model}, World.step under held commands"
        out[str(n)] = row
    return out


def bench_vehicle_step(cfg: Any, batches: tuple[int, ...] = (1, 256, 1024), quick: bool = False,
                       progress: Progress = _quiet) -> dict[str, Any]:
    """Vehicle-steps per second of the vehicles' own step (``Fleet.step``: for rigid bodies the
    autopilot, rotor wrench and attitude step) on 2n vehicles, without the rest of the world:
    per model and batch, wall and per CPU-second."""
    from aerodock.world.vehicles.fleet import build_fleet
    from aerodock.world.vehicles.point_mass import AttitudeCommand

    out: dict[str, Any] = {}
    repeats = 3 if quick else 5
    dt = 1.0 / cfg.sim.physics_rate_hz
    for model in ("rigid-body", "point-mass"):
        fleet = build_fleet(cfg.with_overrides({"vehicle": {"model": model}}, source="bench"))
        row: dict[str, Any] = {}
        for n in batches:
            progress(f"vehicle step ({model}): batch of {n}")
            rng = np.random.default_rng(0)
            start = fleet.hover(np.tile([0.0, 0.0, -2.0], (2 * n, 1)), 0.0, np.ones(2 * n))
            cmd = AttitudeCommand(np.full(n, 0.05), np.full(n, -0.03), np.full(n, 0.1),
                                  np.full(n, 7.5))
            targets = fleet.targets(cmd, cmd, start, n, dt)
            force = 0.1 * rng.standard_normal((2 * n, 3))
            torque = 1e-3 * rng.standard_normal((2 * n, 3))
            noise = 0.02 * rng.standard_normal((2 * n, 3))
            steps = max(20, (200 if n <= 256 else 60) // (2 if quick else 1))

            def fly(fleet: Any = fleet, start: Any = start, targets: Any = targets,
                    force: np.ndarray = force, torque: np.ndarray = torque,
                    noise: np.ndarray = noise, steps: int = steps) -> None:
                state = start
                for _ in range(steps):
                    state, _ = fleet.step(state, targets, force, torque, dt, noise)

            cpu: list[float] = []
            times = measure(fly, repeats, warmup=1, cpu_times=cpu)
            fig = figure([2 * n * steps / t for t in times], "vehicle-steps/s",
                         f"{model}, Fleet.step alone, {2 * n} vehicles")
            fig["per_cpu_s"] = float(statistics.median(2 * n * steps / max(c, 1e-9)
                                                       for c in cpu))
            row[str(n)] = fig
        out[model] = row
    return out


# -- docking -----------------------------------------------------------------------------------
def bench_docking(cfg: Any, quick: bool = False, progress: Progress = _quiet) -> dict[str, Any]:
    """Wall time of one docking trial and of a 100-trial campaign (oracle compensation)."""
    from aerodock.mission import MissionSpec, run_campaign

    out: dict[str, Any] = {}
    for key, trials, repeats in (("trial_1", 1, 3 if quick else 5),
                                 ("campaign_100", 100, 2 if quick else 3)):
        progress(f"docking: {trials} trial(s)")
        spec = MissionSpec(trials=trials, compensation="oracle", seed=0)
        flown: list[float] = []

        def fly(spec: Any = spec, flown: list[float] = flown) -> None:
            result = run_campaign(cfg, spec, record="summary")
            flown.append(result.arrival_s)

        times = measure(fly, repeats, warmup=1 if key == "trial_1" else 0)
        out[key] = figure(times, "s", f"{trials} trial(s), {flown[-1]:g} s approach, oracle "
                          "compensation, until every trial is done")
    return out


# -- learnt model --------------------------------------------------------------------------------
def synthetic_dataset(cfg: Any, minutes: float = 5.0, flights: int = 10, rate_hz: float = 100.0,
                      seed: int = 0) -> Any:
    """``minutes`` of flight data below a hovering leader, labelled with the default field.

    Followers wander smoothly 0.45-1.9 m below a slightly tilted, yawed leader (``flights``
    flights of equal length at ``rate_hz``); labels are the field's turbulent acceleration plus
    accelerometer-like noise. Enough to time training on the paper's amount of data.
    """
    from aerodock.downwash import BodyState, build_field
    from aerodock.geometry import euler_to_rotmat
    from aerodock.learning.dataset import Dataset

    rng = np.random.default_rng(seed)
    field = build_field(cfg)
    n_t = int(round(minutes * 60.0 * rate_hz / flights))
    dt = 1.0 / rate_hz
    t = np.arange(n_t) * dt

    def smooth(amp: float) -> np.ndarray:
        out = np.zeros((flights, n_t))
        for _ in range(3):
            period = rng.uniform(6.0, 30.0, (flights, 1))
            phase = rng.uniform(0.0, 2.0 * np.pi, (flights, 1))
            out += amp / 3.0 * np.sin(2.0 * np.pi * t / period + phase)
        return out

    sep = rng.uniform(0.45, 1.6, (flights, 1)) + smooth(0.3)
    dp = np.stack([smooth(0.4), smooth(0.4), sep], axis=-1)  # (flights, T, 3)
    fol_v = np.gradient(dp, dt, axis=1)
    lead_R = euler_to_rotmat(smooth(0.05), smooth(0.05),
                             rng.uniform(-np.pi, np.pi, (flights, 1)) + smooth(0.3))
    lead_v = np.zeros_like(dp)
    mass = np.full(flights, cfg.vehicle.mass_kg)
    thrust = mass * cfg.sim.gravity_mps2
    eye = np.repeat(np.eye(3)[None], flights, 0)
    field.reset(flights, rng)
    y = np.empty_like(dp)
    for k in range(n_t):
        lead = BodyState(np.zeros((flights, 3)), lead_v[:, k], lead_R[:, k], thrust, mass)
        fol = BodyState(dp[:, k], fol_v[:, k], eye, thrust, mass)
        y[:, k] = field.acceleration(lead, fol, dt)
    y += cfg.vehicle.accel_noise_mps2 * rng.standard_normal(y.shape)
    meta = {"flights": [{"name": f"bench-synthetic-{i}", "n_samples": n_t, "dt_s": dt}
                        for i in range(flights)], "sources": ["aerodock-bench-synthetic"]}
    return Dataset(x=np.concatenate([dp, lead_v, fol_v], axis=-1).reshape(-1, 9),
                   leader_R=lead_R.reshape(-1, 3, 3), y=y.reshape(-1, 3),
                   flight_id=np.repeat(np.arange(flights), n_t), t_s=np.tile(t, flights),
                   meta=meta)


def predictor_inputs(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """``n`` model inputs ``x`` (n, 9) and leader attitudes (n, 3, 3) around and below a leader."""
    from aerodock.geometry import euler_to_rotmat

    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform([-0.5, -0.5, 0.2], [0.5, 0.5, 1.8], (n, 3)),
                        rng.normal(0.0, 0.3, (n, 6))], axis=1)
    rot = euler_to_rotmat(rng.normal(0.0, 0.1, n), rng.normal(0.0, 0.1, n),
                          rng.uniform(-np.pi, np.pi, n))
    return x, rot


def _per_call(fn: Callable[[], Any], calls: int, repeats: int, scale: float, unit: str,
              note: str | None = None) -> dict[str, Any]:
    """Figure of ``fn``'s time per call (x ``scale``), ``calls`` calls per repetition."""

    def loop() -> None:
        for _ in range(calls):
            fn()

    times = measure(loop, repeats, warmup=1)
    return figure([t / calls * scale for t in times], unit, note)


def bench_training(cfg: Any, quick: bool = False,
                   progress: Progress = _quiet) -> tuple[dict[str, Any], Any]:
    """Wall time to train the SO(2) model on 5 minutes of data; also returns the trained model."""
    try:
        from aerodock.learning.train import train_model
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"training not available ({_reason(err)})", "s"), None
    progress("training: building 5 minutes of data")
    try:
        data = synthetic_dataset(cfg)
        progress("training: warm-up")
        train_model("so2", data, seed=0, max_epochs=2)
        trained: list[Any] = []

        def train() -> None:
            trained.append(train_model("so2", data, seed=0))

        progress("training: the SO(2) model on 5 minutes")
        times = measure(train, 1 if quick else 3, warmup=0)
    except Exception as err:  # noqa: BLE001 - optional part, never crash the benchmark
        return unavailable(f"training failed ({_reason(err)})", "s"), None
    info = trained[-1].info
    note = (f"so2, {data.n} samples ({data.minutes:g} min at 100 Hz), defaults "
            f"(early stopping: {info.get('epochs')} epochs), 1 torch thread")
    return figure(times, "s", note), trained[-1]


def _numpy_predictor(trained: Any) -> Any:
    """The NumPy runtime of ``trained``, or of an untrained default SO(2) network."""
    if trained is not None:
        return trained.predictor()
    from aerodock.learning.features import N_FEATURES, N_OUTPUTS
    from aerodock.learning.modelfile import ModelSpec
    from aerodock.learning.runtime import Predictor

    sizes = (N_FEATURES["so2"], 64, 64, N_OUTPUTS["so2"])
    rng = np.random.default_rng(0)
    weights = [(rng.normal(0, 0.3, (b, a)), rng.normal(0, 0.1, b))
               for a, b in zip(sizes[:-1], sizes[1:])]
    spec = ModelSpec(kind="so2", layer_sizes=sizes, in_mean=np.zeros(sizes[0]),
                     in_std=np.ones(sizes[0]), out_mean=np.zeros(sizes[-1]),
                     out_std=np.ones(sizes[-1]))
    return Predictor(spec, weights)


def bench_predictor(trained: Any, quick: bool = False,
                    progress: Progress = _quiet) -> dict[str, Any]:
    """Single-call and per-sample batch-of-1024 times: NumPy runtime, ONNX Runtime, PyTorch."""
    repeats = 5 if quick else 7
    single_calls = 500 if quick else 2000
    batch_calls = 10 if quick else 30
    x1, r1 = predictor_inputs(1)
    xb, rb = predictor_inputs(1024)
    out: dict[str, Any] = {}
    untrained = " (untrained network: no trained model available)" if trained is None else ""

    progress("predictor: NumPy runtime")
    try:
        from aerodock.downwash import BodyState

        pred = _numpy_predictor(trained)
        x0, rot0 = x1[0], r1[0]
        mass = np.ones(1)
        lead = BodyState(np.zeros((1, 3)), x1[:, 3:6], r1, mass * 9.81, mass)
        fol = BodyState(x1[:, 0:3], x1[:, 6:9], r1, mass * 9.81, mass)
        out["numpy"] = {
            "single_call_us": _per_call(lambda: pred.predict_one(x0, rot0), single_calls,
                                        repeats, 1e6, "us",
                                        f"Predictor.predict_one{untrained}"),
            "controller_call_us": _per_call(lambda: pred.predict_bodies(lead, fol),
                                            single_calls, repeats, 1e6, "us",
                                            "Predictor.predict_bodies, batch of 1 (the "
                                            "controller's call)"),
            "batch1024_per_sample_us": _per_call(lambda: pred.predict(xb, rb), batch_calls,
                                                 repeats, 1e6 / 1024, "us",
                                                 "Predictor.predict on 1024 samples"),
        }
    except Exception as err:  # noqa: BLE001 - optional part
        out["numpy"] = unavailable(f"NumPy runtime not available ({_reason(err)})", "us")

    progress("predictor: ONNX Runtime")
    out["onnx"] = _bench_onnx(trained, x1, r1, xb, rb, repeats, single_calls, batch_calls)
    progress("predictor: PyTorch")
    out["torch"] = _bench_torch(trained, x1, r1, xb, rb, repeats, single_calls, batch_calls)
    return out


def _bench_onnx(trained: Any, x1: np.ndarray, r1: np.ndarray, xb: np.ndarray, rb: np.ndarray,
                repeats: int, single_calls: int, batch_calls: int) -> dict[str, Any]:
    if trained is None:
        return unavailable("no trained model to export (training not available)", "us")
    try:
        import onnxruntime as ort

        from aerodock.learning.export import export_onnx
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"ONNX export/runtime not available ({_reason(err)})", "us")
    try:
        with tempfile.TemporaryDirectory(prefix="aerodock-bench-") as tmp:
            path = export_onnx(trained, Path(tmp) / "model.onnx")
            opts = ort.SessionOptions()
            opts.intra_op_num_threads = 1
            opts.inter_op_num_threads = 1
            sess = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
        one = {"x": x1.astype(np.float32), "leader_R": r1.astype(np.float32)}
        many = {"x": xb.astype(np.float32), "leader_R": rb.astype(np.float32)}
        return {
            "single_call_us": _per_call(lambda: sess.run(None, one), single_calls, repeats, 1e6,
                                        "us", "InferenceSession.run, float32, 1 thread"),
            "batch1024_per_sample_us": _per_call(lambda: sess.run(None, many), batch_calls,
                                                 repeats, 1e6 / 1024, "us"),
        }
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"ONNX benchmark failed ({_reason(err)})", "us")


def _bench_torch(trained: Any, x1: np.ndarray, r1: np.ndarray, xb: np.ndarray, rb: np.ndarray,
                 repeats: int, single_calls: int, batch_calls: int) -> dict[str, Any]:
    if trained is None:
        return unavailable("no trained model (training not available)", "us")
    try:
        import torch
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"PyTorch not available ({_reason(err)})", "us")
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        model = trained.model.eval()
        t1 = (torch.as_tensor(x1, dtype=torch.float32), torch.as_tensor(r1, dtype=torch.float32))
        tb = (torch.as_tensor(xb, dtype=torch.float32), torch.as_tensor(rb, dtype=torch.float32))

        def call(args: tuple[Any, Any]) -> Any:
            with torch.inference_mode():
                return model(*args)

        return {
            "single_call_us": _per_call(lambda: call(t1), single_calls, repeats, 1e6, "us",
                                        "module call under inference_mode, float32, 1 thread"),
            "batch1024_per_sample_us": _per_call(lambda: call(tb), batch_calls, repeats,
                                                 1e6 / 1024, "us"),
        }
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"PyTorch benchmark failed ({_reason(err)})", "us")
    finally:
        torch.set_num_threads(threads)


# -- whole commands, memory ----------------------------------------------------------------------
def _aerodock_argv(*args: str) -> list[str]:
    return [sys.executable, "-c", "from aerodock.cli import main; main()", *args]


def bench_reproduce(progress: Progress = _quiet,
                    config_path: Path | None = None) -> dict[str, Any]:
    """Wall time of ``aerodock reproduce --quick`` in a subprocess (one run: it takes minutes)."""
    try:
        probe = subprocess.run(_aerodock_argv("reproduce", "--help"), capture_output=True,
                               text=True, timeout=120)
    except (OSError, subprocess.SubprocessError) as err:
        return unavailable(f"not available ({_reason(err)})", "s")
    if probe.returncode != 0:
        return unavailable("not available", "s")
    progress("reproduce --quick (a few minutes)")
    with tempfile.TemporaryDirectory(prefix="aerodock-bench-") as tmp:
        t0 = time.perf_counter()
        try:
            extra = () if config_path is None else ("--config", str(config_path))
            run = subprocess.run(_aerodock_argv("reproduce", "--quick", "--out", tmp, *extra),
                                 capture_output=True, text=True, timeout=_SUBPROCESS_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            return unavailable(f"did not finish within {_SUBPROCESS_TIMEOUT_S:.0f} s", "s")
        wall = time.perf_counter() - t0
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or ["no message"])[-1]
        return unavailable(f"exit code {run.returncode}: {last}", "s")
    return figure([wall], "s", "one run in a subprocess (includes interpreter start-up)")


_MEMORY_SCRIPT = """
import json, sys, time
from aerodock.config import load_config
from aerodock.mission import MissionSpec, run_campaign

def status_mib(key):
    # VmHWM is the peak resident set of this process image; unlike ru_maxrss it does not
    # start from the parent's size (ru_maxrss is inherited through fork and exec on Linux).
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource
    scale = 1.0 / 2**20 if sys.platform == "darwin" else 1.0 / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale

traced = {traced}
if traced:
    import tracemalloc
    tracemalloc.start()
cfg = load_config({config_path!r})
spec = MissionSpec(trials={trials}, compensation="oracle", seed=0)
base = status_mib("VmRSS")
t0 = time.perf_counter()
run_campaign(cfg, spec, record="summary")
wall = time.perf_counter() - t0
out = {{"rss_after_imports_mib": base, "peak_rss_mib": status_mib("VmHWM"), "wall_s": wall}}
if traced:
    out["traced_peak_mib"] = tracemalloc.get_traced_memory()[1] / 2**20
print(json.dumps(out))
"""


def _memory_run(trials: int, traced: bool, config_path: Path | None) -> dict[str, float]:
    path = None if config_path is None else str(config_path)
    run = subprocess.run(
        [sys.executable, "-c",
         _MEMORY_SCRIPT.format(trials=trials, traced=traced, config_path=path)],
        capture_output=True, text=True, timeout=_SUBPROCESS_TIMEOUT_S)
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or ["no message"])[-1]
        raise RuntimeError(f"campaign failed: {last}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def bench_memory(trials: int = 1024, traced: bool = True, progress: Progress = _quiet,
                 config_path: Path | None = None) -> dict[str, Any]:
    """Peak memory (MiB) of a ``trials``-trial campaign, each in a fresh subprocess.

    ``peak_rss_mib``: the process's peak resident set (interpreter, imports and campaign);
    ``rss_after_imports_mib``: its resident set before the campaign; ``traced_peak_mib`` (if
    ``traced``): the peak of the campaign's own allocations (``tracemalloc``, a second run).
    """
    progress(f"memory: {trials}-trial campaign in a subprocess")
    try:
        plain = _memory_run(trials, False, config_path)
        if traced:
            progress(f"memory: {trials}-trial campaign under tracemalloc")
            allocs = _memory_run(trials, True, config_path)
    except (OSError, subprocess.SubprocessError, RuntimeError, ValueError, IndexError) as err:
        return {"peak_rss_mib": unavailable(f"could not run ({_reason(err)})", "MiB")}
    what = f"{trials}-trial campaign, oracle compensation, record='summary', one run"
    out = {
        "peak_rss_mib": figure([plain["peak_rss_mib"]], "MiB",
                               f"{what}: peak resident set of the whole process"),
        "rss_after_imports_mib": figure([plain["rss_after_imports_mib"]], "MiB",
                                        "the same process before the campaign"),
        "campaign_wall_s": figure([plain["wall_s"]], "s", what),
    }
    if traced:
        out["traced_peak_mib"] = figure([allocs["traced_peak_mib"]], "MiB",
                                        f"{what}: peak of the campaign's own allocations "
                                        "(tracemalloc)")
    return out


# -- peer comparison: RotorPy ------------------------------------------------------------------
PEER_HOVER_S = 1.0
PEER_MOVE_S = 4.0
PEER_PHYSICS_HZ = 500.0
PEER_CONTROL_HZ = 100.0
PEER_MOVE_NED_M = (1.0, 0.5, -0.3)  # 1 m north, 0.5 m east, 0.3 m up


def peer_reference(n_steps: int, dt: float) -> dict[str, np.ndarray]:
    """The scenario's reference at every physics step: hover, then a 4 s minimum-jerk move.

    Flat outputs in NED, ``(n_steps, 3)`` each: position, velocity, acceleration, jerk, snap
    (from :func:`aerodock.planning.minjerk.minjerk`, rest to rest).
    """
    from aerodock.planning.minjerk import minjerk

    zero = np.zeros((1, 3))
    plan = minjerk(zero, zero, zero, np.array([PEER_MOVE_NED_M]), zero, zero, PEER_MOVE_S,
                   PEER_HOVER_S)
    t = np.arange(n_steps) * dt
    ref = {k: np.zeros((n_steps, 3)) for k in ("x", "x_dot", "x_ddot", "x_dddot", "x_ddddot")}
    c = plan.coeffs[0]  # (3, 6)
    for k, tk in enumerate(t):
        pos, vel, acc = plan.sample(np.array([tk]))
        ref["x"][k], ref["x_dot"][k], ref["x_ddot"][k] = pos[0], vel[0], acc[0]
        tau = min(max(tk - PEER_HOVER_S, 0.0), PEER_MOVE_S)
        moving = PEER_HOVER_S <= tk <= PEER_HOVER_S + PEER_MOVE_S
        if moving:
            ref["x_dddot"][k] = 6 * c[:, 3] + 24 * c[:, 4] * tau + 60 * c[:, 5] * tau**2
            ref["x_ddddot"][k] = 24 * c[:, 4] + 120 * c[:, 5] * tau
    return ref


def _peer_steps(quick: bool) -> int:
    return int(round((PEER_HOVER_S + PEER_MOVE_S) * PEER_PHYSICS_HZ)) // (2 if quick else 1)


def peer_aerodock(cfg: Any, n: int, steps: int, ref: dict[str, np.ndarray]) -> tuple[float, float]:
    """aerodock's side: ``n`` quadrotors, the vehicle step at 500 Hz and the LQR position
    controller at 100 Hz (no observer, true state), flying ``ref``; the command is clipped once
    per control period and held, as :meth:`aerodock.world.world.World.advance` does.

    Returns the final position error of the first vehicle (m: a check that it tracked) and the
    time spent in the vehicle step alone (s).
    """
    from aerodock.control.controller import PositionController, Reference
    from aerodock.world.vehicles.point_mass import (
        VehicleParams,
        command_targets,
        hover_state,
        step_vehicle_targets,
    )

    params = VehicleParams.from_config(cfg)
    dt = 1.0 / PEER_PHYSICS_HZ
    every = int(round(PEER_PHYSICS_HZ / PEER_CONTROL_HZ))
    ctl = PositionController(cfg, n, use_observer=False)
    state = hover_state(params, np.zeros((n, 3)))
    zero3, zero = np.zeros((n, 3)), np.zeros(n)
    # The reference of every control step, for the whole batch (as a planner would hand it).
    refs = [Reference(*(np.repeat(ref[key][k][None], n, 0) for key in ("x", "x_dot", "x_ddot")),
                      zero, zero) for k in range(0, steps, every)]
    clock = time.perf_counter
    physics_s = 0.0
    targets = None
    for k in range(steps):
        if k % every == 0:
            cmd = ctl.step(state.p, state.v, state.rpy, refs[k // every]).command
            t0 = clock()
            targets = command_targets(cmd, params, dt, n)
            physics_s += clock() - t0
        t0 = clock()
        state, _ = step_vehicle_targets(state, targets, zero3, params, dt)
        physics_s += clock() - t0
    return float(np.linalg.norm(state.p[0] - ref["x"][steps - 1])), physics_s


_NED_TO_ZUP = np.array([1.0, -1.0, -1.0])  # RotorPy's world is z-up: (x, y, z) -> (x, -y, -z)
_FLAT_KEYS = ("x", "x_dot", "x_ddot", "x_dddot", "x_ddddot")


def _rotorpy_params() -> dict[str, Any]:
    from rotorpy.vehicles.hummingbird_params import quad_params

    return quad_params


def _hover_rotor_speed(quad: dict[str, Any]) -> float:
    return float(np.sqrt(quad["mass"] * 9.81 / (quad["num_rotors"] * quad["k_eta"])))


def peer_rotorpy(steps: int, ref: dict[str, np.ndarray]) -> tuple[float, float]:
    """RotorPy's side: one ``Multirotor`` (Hummingbird parameters, its default RK45 integrator
    and motor-speed commands) stepped sequentially at 500 Hz under ``SE3Control``, which runs at
    every step as in RotorPy's own ``simulate`` loop.

    Returns the final position error (m) and the time spent in ``Multirotor.step`` alone (s).
    """
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.vehicles.multirotor import Multirotor

    quad = _rotorpy_params()
    state = {"x": np.zeros(3), "v": np.zeros(3), "q": np.array([0.0, 0.0, 0.0, 1.0]),
             "w": np.zeros(3), "wind": np.zeros(3),
             "rotor_speeds": np.full(quad["num_rotors"], _hover_rotor_speed(quad))}
    vehicle = Multirotor(quad, initial_state={k: v.copy() for k, v in state.items()})
    controller = SE3Control(quad)
    dt = 1.0 / PEER_PHYSICS_HZ
    clock = time.perf_counter
    physics_s = 0.0
    for k in range(steps):
        flat = {key: ref[key][k] * _NED_TO_ZUP for key in _FLAT_KEYS}
        flat["yaw"], flat["yaw_dot"] = 0.0, 0.0
        control = controller.update(k * dt, state, flat)
        t0 = clock()
        state = vehicle.step(state, control, dt)
        physics_s += clock() - t0
    return float(np.linalg.norm(state["x"] - ref["x"][steps - 1] * _NED_TO_ZUP)), physics_s


def peer_rotorpy_batched(n: int, steps: int, ref: dict[str, np.ndarray]) -> tuple[float, float]:
    """RotorPy's batched simulator (PyTorch): ``BatchedMultirotor`` with ``BatchedSE3Control``
    at 500 Hz, ``n`` Hummingbirds on the CPU, fixed-step RK4 (its faster integrator option).

    Returns the final position error of the first vehicle (m) and the time spent in
    ``BatchedMultirotor.step`` alone (s).
    """
    import torch
    from rotorpy.controllers.quadrotor_control import BatchedSE3Control

    try:
        from rotorpy.vehicles.multirotor import BatchedMultirotor, BatchedMultirotorParams
    except ImportError:  # rotorpy < 3 kept them in their own module
        from rotorpy.vehicles.batched_multirotor import (  # type: ignore[no-redef]
            BatchedDynamicsParams as BatchedMultirotorParams,
        )
        from rotorpy.vehicles.batched_multirotor import (  # type: ignore[no-redef]
            BatchedMultirotor,
        )
    quad = _rotorpy_params()
    device = torch.device("cpu")
    params = BatchedMultirotorParams([quad] * n, n, device)
    f64 = torch.double
    state = {
        "x": torch.zeros(n, 3, dtype=f64), "v": torch.zeros(n, 3, dtype=f64),
        "q": torch.tensor([0.0, 0.0, 0.0, 1.0], dtype=f64).repeat(n, 1),
        "w": torch.zeros(n, 3, dtype=f64), "wind": torch.zeros(n, 3, dtype=f64),
        "rotor_speeds": torch.full((n, quad["num_rotors"]), _hover_rotor_speed(quad), dtype=f64),
    }
    vehicles = BatchedMultirotor(params, n, state, device, integrator="rk4")
    controller = BatchedSE3Control(params, n, device)
    dt = 1.0 / PEER_PHYSICS_HZ
    zero = torch.zeros(n, dtype=f64)
    clock = time.perf_counter
    physics_s = 0.0
    for k in range(steps):
        flat = {key: torch.from_numpy(ref[key][k] * _NED_TO_ZUP).repeat(n, 1)
                for key in _FLAT_KEYS}
        flat["yaw"], flat["yaw_dot"] = zero, zero
        control = controller.update(k * dt, state, flat)
        t0 = clock()
        state = vehicles.step(state, control, dt)
        physics_s += clock() - t0
    final = state["x"][0].numpy()
    return float(np.linalg.norm(final - ref["x"][steps - 1] * _NED_TO_ZUP)), physics_s


def _rotorpy_batched_missing() -> str | None:
    """Why RotorPy's batched simulator cannot run here (None: it can)."""
    try:
        import roma  # noqa: F401
        import torch  # noqa: F401
        import torchdiffeq  # noqa: F401
        from rotorpy.controllers.quadrotor_control import BatchedSE3Control  # noqa: F401
    except Exception as err:  # noqa: BLE001 - optional part
        return _reason(err)
    return None


@contextlib.contextmanager
def _torch_threads(n: int) -> Iterator[None]:
    """Run with ``n`` torch threads (if torch is imported), then restore the setting."""
    torch = sys.modules.get("torch")
    if torch is None:
        yield
        return
    old = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(old)


def compare_rotorpy(cfg: Any, quick: bool = False, batch: int = 256,
                    progress: Progress = _quiet) -> dict[str, Any]:
    """Time the peer scenario with RotorPy and with aerodock in one run; times and ratios.

    Scenario: one quadrotor hovers for 1 s, then flies a 4 s minimum-jerk move (1 m north,
    0.5 m east, 0.3 m up) under its position controller, 500 Hz physics; ``quick`` flies the
    first half of it. RotorPy: ``Multirotor`` stepped sequentially (one trial), and its batched
    simulator when importable (PyTorch, ``torchdiffeq``, ``roma``). aerodock: the vehicle step
    with its LQR position controller, batch of 1 and of ``batch``.

    Each run's figure is its whole wall time (``value``, median over repetitions after a
    warm-up) and the part of it spent in the physics step (``physics_s``, of the median run).
    The two simulators' runs alternate (aerodock, RotorPy, aerodock, ...), so that a change of
    load on the machine hits both; a ratio is the median of the ratios of these pairs.
    """
    steps = _peer_steps(quick)
    dt = 1.0 / PEER_PHYSICS_HZ
    ref = peer_reference(steps, dt)
    out: dict[str, Any] = {"scenario": {
        "physics_hz": PEER_PHYSICS_HZ, "steps": steps, "simulated_s": steps * dt,
        "move_ned_m": list(PEER_MOVE_NED_M), "hover_s": PEER_HOVER_S, "move_s": PEER_MOVE_S,
    }}
    try:
        import rotorpy  # noqa: F401
        have_rotorpy = True
    except ImportError:
        have_rotorpy = False

    Runner = Callable[[int], tuple[float, float]]

    def pairs(ours: Runner, theirs: Runner | None, reps: int, warm_theirs: int
              ) -> tuple[list[tuple[float, float, float]], list[tuple[float, float, float]]]:
        """Alternating timed runs ``(wall, physics, error)`` of ``ours`` and ``theirs``."""
        ours(steps)
        if theirs is not None:
            theirs(warm_theirs)
        a, b = [], []
        for _ in range(reps):
            for runner, runs in ((ours, a), (theirs, b)):
                if runner is None:
                    continue
                t0 = time.perf_counter()
                err, physics = runner(steps)
                runs.append((time.perf_counter() - t0, physics, err))
        return a, b

    def fig(runs: list[tuple[float, float, float]], vehicles: int, note: str) -> dict[str, Any]:
        wall, physics, err = sorted(runs)[len(runs) // 2]  # the median run (odd counts)
        out_fig = figure([r[0] for r in runs], "s", note)
        out_fig.update({"value": wall, "physics_s": physics,
                        "vehicle_steps_per_s": vehicles * steps / wall,
                        "physics_vehicle_steps_per_s": vehicles * steps / physics,
                        "final_error_m": err})
        return out_fig

    def ratio(theirs: list, ours: list, index: int) -> float:
        return float(statistics.median(t[index] / o[index] for t, o in zip(theirs, ours)))

    reps = (3 if quick else 5) if not have_rotorpy else 3
    progress("peer: aerodock batch of 1" + (" and RotorPy Multirotor, alternating"
                                            if have_rotorpy else ""))
    one, seq = pairs(lambda k: peer_aerodock(cfg, 1, k, ref),
                     (lambda k: peer_rotorpy(k, ref)) if have_rotorpy else None, reps, 50)
    out["aerodock_1"] = fig(one, 1, "step_vehicle 500 Hz + LQR PositionController 100 Hz")
    ratios: dict[str, float] = {}
    if have_rotorpy:
        out["rotorpy_sequential"] = fig(
            seq, 1, "Multirotor.step (RK45) 500 Hz + SE3Control at every step")
        ratios["single_trial"] = ratio(seq, one, 0)
        ratios["single_trial_physics_step"] = ratio(seq, one, 1)

    batched: Runner | None = None
    if have_rotorpy:
        missing = _rotorpy_batched_missing()
        if missing is None:
            batched = lambda k: peer_rotorpy_batched(batch, k, ref)  # noqa: E731
        else:
            out["rotorpy_batched"] = unavailable(
                f"RotorPy's batched simulator not available ({missing})", "s")
    progress(f"peer: aerodock batch of {batch}"
             + (" and RotorPy batched, alternating" if batched else ""))
    ours = lambda k: peer_aerodock(cfg, batch, k, ref)  # noqa: E731
    try:
        with _torch_threads(1):
            many, bat = pairs(ours, batched, 1 if (quick and batched) else 3, 20)
    except Exception as err:  # noqa: BLE001 - RotorPy's batched simulator failed: go on
        if batched is None:
            raise
        out["rotorpy_batched"] = unavailable(
            f"RotorPy's batched simulator failed ({_reason(err)})", "s")
        batched = None
        many, bat = pairs(ours, None, 3, 20)
    out[f"aerodock_{batch}"] = fig(many, batch, f"the same, {batch} vehicles at once")
    if have_rotorpy:
        ratios[f"aerodock_batch_{batch}_vs_rotorpy_sequential"] = (
            out[f"aerodock_{batch}"]["vehicle_steps_per_s"]
            / out["rotorpy_sequential"]["vehicle_steps_per_s"])
    if batched is not None:
        out["rotorpy_batched"] = fig(
            bat, batch, f"BatchedMultirotor (RK4) + BatchedSE3Control 500 Hz, {batch} vehicles, "
            "CPU, 1 torch thread")
        ratios[f"batched_{batch}"] = ratio(bat, many, 0)
        ratios[f"batched_{batch}_physics_step"] = ratio(bat, many, 1)
    if not have_rotorpy:
        reason = "rotorpy not installed (pip install --no-deps rotorpy)"
        out["rotorpy_sequential"] = unavailable(reason, "s")
        out["rotorpy_batched"] = unavailable(reason, "s")
    out["ratios"] = ratios or None
    return out


# -- everything --------------------------------------------------------------------------------
def machine_info() -> dict[str, Any]:
    """The machine and software the figures were measured with."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem_gib = None
    try:
        mem_gib = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    except (ValueError, OSError, AttributeError):
        pass
    versions = {"python": platform.python_version(), "numpy": np.__version__}
    for mod in ("scipy", "torch", "onnxruntime", "rotorpy"):
        try:
            from importlib.metadata import version

            versions[mod] = version(mod)
        except Exception:  # noqa: BLE001 - not installed
            versions[mod] = None
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except (OSError, AttributeError):
        load = None
    return {"cpu": cpu, "cores": os.cpu_count(), "load_average_1_5_15_min": load,
            "memory_gib": None if mem_gib is None else round(mem_gib, 1),
            "os": f"{platform.system()} {platform.release()}", "versions": versions}


def _value(fig: Any) -> float | None:
    return fig.get("value") if isinstance(fig, dict) else None


def targets(figs: dict[str, Any]) -> list[dict[str, Any]]:
    """The issue's targets (benchmarks, not tests): measured value, threshold, met or not."""
    sim = figs.get("simulator", {}).get("256", {})
    point_mass = figs.get("simulator_point_mass", {}).get("256", {})
    numpy_pred = figs.get("predictor", {}).get("numpy", {})
    peer = figs.get("peer") or {}
    ratios = peer.get("ratios") or {}
    rows = [
        ("vehicle-steps/s at a batch of 256, rigid-body, physics (World.step)", ">=",
         TARGETS["vehicle_steps_per_s_at_256"], _value(sim.get("physics_only"))),
        ("vehicle-steps/s at a batch of 256, rigid-body, with controllers at 100 Hz", ">=",
         TARGETS["vehicle_steps_per_s_at_256"], _value(sim.get("with_controllers"))),
        ("vehicle-steps/s at a batch of 256, point-mass, with controllers at 100 Hz", ">=",
         TARGETS["point_mass_vehicle_steps_per_s_at_256"],
         _value(point_mass.get("with_controllers"))),
        ("speed-up over RotorPy sequential, single trial", ">=",
         TARGETS["rotorpy_sequential_speedup"], ratios.get("single_trial")),
        ("NumPy predictor, single call (us)", "<", TARGETS["predictor_single_call_us"],
         _value(numpy_pred.get("single_call_us") if isinstance(numpy_pred, dict) else None)),
        ("aerodock reproduce --quick (s)", "<", TARGETS["reproduce_quick_s"],
         _value(figs.get("reproduce_quick_s"))),
    ]
    out = []
    for name, op, threshold, measured in rows:
        met = None if measured is None else (measured >= threshold if op == ">="
                                             else measured < threshold)
        out.append({"target": name, "threshold": f"{op} {threshold:g}", "measured": measured,
                    "met": met})
    return out


PARTS = ("simulator", "docking", "predictor", "memory", "reproduce", "gym", "peer")


def run_all(cfg: Any, quick: bool = False, progress: Progress = _quiet,
            include_reproduce: bool | None = None, include_peer: bool = True,
            config_path: Path | None = None, only: str | None = None) -> dict[str, Any]:
    """Every figure (see the module docstring), as a JSON-ready document.

    ``config_path`` is the file ``cfg`` came from (if any), for the subprocesses; ``only`` (one
    of :data:`PARTS`) measures that part alone (``predictor`` includes training).
    """
    if only is not None and only not in PARTS:
        raise ValueError(f"unknown bench part {only!r}; choose one of {', '.join(PARTS)}")

    def wanted(part: str) -> bool:
        return only is None or only == part

    started = time.perf_counter()
    figs: dict[str, Any] = {}
    if wanted("simulator"):
        figs["simulator"] = bench_simulator(cfg, quick=quick, progress=progress,
                                            model="rigid-body")
        figs["simulator_point_mass"] = bench_simulator(cfg, quick=quick, progress=progress,
                                                       model="point-mass")
        figs["vehicle_step"] = bench_vehicle_step(cfg, quick=quick, progress=progress)
    if wanted("docking"):
        figs["docking"] = bench_docking(cfg, quick=quick, progress=progress)
    if wanted("predictor"):
        figs["training"], trained = bench_training(cfg, quick=quick, progress=progress)
        figs["predictor"] = bench_predictor(trained, quick=quick, progress=progress)
    if wanted("memory"):
        figs["memory"] = bench_memory(progress=progress, config_path=config_path)
    if include_reproduce is None:
        include_reproduce = not quick or only == "reproduce"
    if wanted("reproduce"):
        figs["reproduce_quick_s"] = (
            bench_reproduce(progress, config_path) if include_reproduce
            else unavailable("skipped with --quick (takes minutes)", "s"))
    if wanted("gym"):
        try:
            from aerodock.envs.bench import bench_vector_env
        except ImportError as err:  # gymnasium is an optional extra
            figs["gym_vector_env"] = {"1": unavailable(_reason(err), "env-steps/s")}
        else:
            figs["gym_vector_env"] = bench_vector_env(cfg, quick=quick, progress=progress)
    if include_peer and wanted("peer"):
        figs["peer"] = compare_rotorpy(cfg, quick=quick, progress=progress)
    return {
        "machine": machine_info(),
        "settings": {"quick": quick, "physics_rate_hz": cfg.sim.physics_rate_hz,
                     "control_rate_hz": cfg.sim.control_rate_hz,
                     "statistic": "median of the repetitions after a warm-up; min and max "
                                  "give the spread"},
        "figures": figs,
        "targets": targets(figs),
        "bench_wall_s": round(time.perf_counter() - started, 1),
    }


# -- presentation ------------------------------------------------------------------------------
def _fmt(value: float | None, unit: str) -> str:
    if value is None:
        return "-"
    if unit == "vehicle-steps/s":
        return f"{value:,.0f}"
    if abs(value) >= 100:
        return f"{value:,.0f}"
    return f"{value:.3g}"


def table_rows(doc: dict[str, Any]) -> list[tuple[str, str, str, str, str]]:
    """(figure, median, spread, unit, note or reason) for every figure of ``doc``."""
    rows: list[tuple[str, str, str, str, str]] = []

    def add(name: str, fig: Any) -> None:
        if not isinstance(fig, dict) or "unit" not in fig:
            return
        unit = fig["unit"]
        if fig.get("value") is None:
            rows.append((name, "null", "", unit, fig.get("reason", "")))
            return
        spread = (f"{_fmt(fig['min'], unit)} - {_fmt(fig['max'], unit)} (x{fig['repeats']})"
                  if fig.get("repeats", 1) > 1 else "one run")
        note = fig.get("note", "")
        if "per_cpu_s" in fig:
            note = f"{note}; {_fmt(fig['per_cpu_s'], unit)} per CPU-second".lstrip("; ")
        rows.append((name, _fmt(fig["value"], unit), spread, unit, note))

    figs = doc["figures"]
    for key, model in (("simulator", "rigid-body"), ("simulator_point_mass", "point-mass")):
        for n, row in figs.get(key, {}).items():
            add(f"simulator {model}, batch {n}, with controllers", row.get("with_controllers"))
            add(f"simulator {model}, batch {n}, physics only", row.get("physics_only"))
    for model, row in figs.get("vehicle_step", {}).items():
        for n, fig in row.items():
            add(f"vehicle step {model}, batch {n} (Fleet.step alone)", fig)
    for n, fig in figs.get("gym_vector_env", {}).items():
        add(f"gym vector env, {n} envs", fig)
    for key, label in (("trial_1", "docking trial (1)"),
                       ("campaign_100", "docking campaign (100)")):
        add(label, figs.get("docking", {}).get(key))
    for rt in ("numpy", "onnx", "torch"):
        part = figs.get("predictor", {}).get(rt, {})
        if part.get("value", 0) is None:
            add(f"predictor {rt}", part)
            continue
        add(f"predictor {rt}, single call", part.get("single_call_us"))
        add(f"predictor {rt}, controller call", part.get("controller_call_us"))
        add(f"predictor {rt}, per sample in 1024", part.get("batch1024_per_sample_us"))
    add("training so2, 5 min of data", figs.get("training"))
    add("reproduce --quick", figs.get("reproduce_quick_s"))
    mem = figs.get("memory", {})
    add("peak memory, 1024-trial campaign (process)", mem.get("peak_rss_mib"))
    add("memory before the campaign (process)", mem.get("rss_after_imports_mib"))
    add("peak memory, 1024-trial campaign (its arrays)", mem.get("traced_peak_mib"))
    add("1024-trial campaign", mem.get("campaign_wall_s"))
    peer = figs.get("peer") or {}
    for key, fig in peer.items():
        if key.startswith(("aerodock_", "rotorpy_")):
            add(f"peer scenario: {key.replace('_', ' ')}", fig)
    for key, ratio in (peer.get("ratios") or {}).items():
        rows.append((f"ratio: {key.replace('_', ' ')}", f"{ratio:.1f}x", "", "", ""))
    return rows


def bench_command(
    quick: Annotated[bool, typer.Option(
        "--quick", help="Fewer, shorter repetitions; skips `reproduce --quick`.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print the numbers as JSON.")] = False,
    config: Annotated[Path | None, typer.Option(
        "--config", help="TOML file overriding aerodock's defaults.")] = None,
    only: Annotated[str | None, typer.Option(
        "--only", help=f"Measure one part alone: {', '.join(PARTS)}.")] = None,
) -> None:
    """Measure the speed of every hot path: simulator, docking, learnt model, training,
    `reproduce --quick`, memory, and RotorPy on the same scenario (if installed)."""
    from rich.console import Console
    from rich.table import Table

    from aerodock.config import load_config

    if only is not None and only not in PARTS:
        typer.echo(f"error: unknown --only {only!r}; choose one of {', '.join(PARTS)}", err=True)
        raise typer.Exit(2)

    err = Console(stderr=True)
    with err.status("benchmarking") as status:
        def progress(msg: str) -> None:
            if err.is_terminal:
                status.update(f"benchmarking: {msg}")
            else:
                err.print(f"bench: {msg}", highlight=False)

        doc = run_all(load_config(config), quick=quick, progress=progress, config_path=config,
                      only=only)
    if as_json:
        from aerodock.cli import print_json
        from aerodock.fileio import json_ready

        print_json(json_ready(doc))  # a figure that could not be computed is null
        return
    m = doc["machine"]
    load = m.get("load_average_1_5_15_min")
    table = Table(title=f"aerodock bench{' --quick' if quick else ''}: {m['cpu']}, "
                  f"{m['cores']} cores, Python {m['versions']['python']}"
                  + (f", load average {load[0]:g} / {load[1]:g} / {load[2]:g} (1/5/15 min, "
                     "at the end)" if load else ""))
    for col, justify in (("figure", "left"), ("median", "right"), ("spread (min - max)", "right"),
                         ("unit", "left"), ("note", "left")):
        table.add_column(col, justify=justify)  # type: ignore[arg-type]
    for row in table_rows(doc):
        table.add_row(*row)
    console = Console()
    console.print(table)
    for t in doc["targets"]:
        mark = {True: "met", False: "NOT met", None: "not measured"}[t["met"]]
        value = t["measured"]
        measured = ("-" if value is None else f"{value:,.0f}" if value >= 1000
                    else f"{value:.3g}")
        console.print(f"target {t['target']} {t['threshold']}: {measured} ({mark})")
