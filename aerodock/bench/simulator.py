"""The simulator's speed: vehicle-steps per second of the whole world (with and without the
position controllers) and of the vehicles' own step, per batch size."""

from __future__ import annotations

import statistics
from typing import Any

import numpy as np

from aerodock.bench.timing import Progress, figure, measure, quiet

SIM_BATCHES = (1, 64, 256, 1024)


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
                    progress: Progress = quiet, model: str | None = None) -> dict[str, Any]:
    """Vehicle-steps per second, with controllers and physics only, per batch size.

    ``model`` (``"rigid-body"`` or ``"point-mass"``) overrides ``cfg``'s ``[vehicle] model``.
    """
    from aerodock.world import period
    from aerodock.world.block_choice import block_choice

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
        # the control period's blocks of trials across numba's threads (world/period.py): the
        # CPU time then counts every thread's, so per_cpu_s is below the wall figure when
        # they ran; whether the blocks' home was across them at the end (the faster way, with
        # a few probe periods of the other: world/block_choice.py)
        row["threads"] = period.kernel_blocks(n)
        row["in_blocks"] = row["threads"] > 1 and (not period.CHOOSE_BLOCKS
                                                   or block_choice(n, row["threads"]).home)
        out[str(n)] = row
    return out


def bench_vehicle_step(cfg: Any, batches: tuple[int, ...] = (1, 256, 1024), quick: bool = False,
                       progress: Progress = quiet) -> dict[str, Any]:
    """Vehicle-steps per second of the vehicles' own step (``Fleet.step``: for rigid bodies the
    autopilot, rotor wrench and attitude step) on 2n vehicles, without the rest of the world:
    per model and batch, wall and per CPU-second."""
    from aerodock.world.vehicles.fleet import build_fleet
    from aerodock.world.vehicles.point_mass import AttitudeCommand

    out: dict[str, Any] = {}
    repeats = 3 if quick else 5
    dt = cfg.timing.physics_dt_s
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


PYTHON_FIELD = {"downwash": {"field": "aerodock.downwash.template:UniformColumnField",
                             "params": {"accel_mps2": 3.0, "radius_m": 0.15}}}
"""A plug-in field written in Python (the template's uniform column), for
:func:`bench_python_field`."""


def bench_python_field(cfg: Any, batches: tuple[int, ...] = (1, 256), quick: bool = False,
                       progress: Progress = quiet) -> dict[str, Any]:
    """:func:`bench_simulator` with a plug-in field written in Python instead of the compiled
    jet: the world's other terms stay compiled, the field's own NumPy calls run between them
    (rigid-body vehicles)."""
    progress("simulator with a Python plug-in field")
    return bench_simulator(cfg.with_overrides(PYTHON_FIELD, source="bench"), batches, quick,
                           progress, model="rigid-body")


_FIRST_STEPS = """
import time
t0 = time.perf_counter()
from aerodock.bench.simulator import SimLoop
from aerodock.config import load_config
loop = SimLoop(load_config(None), 1)
loop.run(2)
print(time.perf_counter() - t0)
"""


def bench_kernels(cold: bool = True, progress: Progress = quiet) -> dict[str, Any]:
    """What the compiled kernels cost before the first step: a fresh process importing aerodock
    and flying two control periods of the default world, with the kernels already cached
    (``cached_s``), and (``cold``) with an empty cache, every kernel compiled (``cold_s``;
    about a minute: ``make`` pays it once, at install)."""
    import os
    import subprocess
    import sys
    import tempfile

    def run(env: dict[str, str]) -> float:
        done = subprocess.run([sys.executable, "-c", _FIRST_STEPS], env=env, check=True,
                              capture_output=True, text=True)
        return float(done.stdout.strip().splitlines()[-1])

    progress("kernels: a fresh process's first steps (cached)")
    out: dict[str, Any] = {"cached_s": figure([run(dict(os.environ)) for _ in range(3)], "s",
                                              "import + first 2 control periods, kernels "
                                              "cached")}
    if cold:
        progress("kernels: a fresh process's first steps (compiling, about a minute)")
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, AERODOCK_CACHE_DIR=tmp)
            env.pop("NUMBA_CACHE_DIR", None)
            out["cold_s"] = figure([run(env)], "s", "the same with an empty cache: every "
                                   "kernel the default world flies compiled")
    return out
