"""Compile the world's kernels once, ahead of use: ``python -m aerodock.mission.warm``.

The compiled step (:mod:`aerodock.jit`) keeps its machine code on disk (numba's cache, in a
folder named by the kernels' sources and shared by every copy of them), so a process loads it in
a fraction of a second; only the first process to need a kernel pays for compiling it (about ten
minutes for the whole world on a 2-core machine). ``make`` runs this module right after
installing, so neither a user's first command nor a test process pays that. It flies a few short
campaigns that between them take every compiled path of the default worlds (a batch large enough
for the control period's blocks across the cores, the rigid-body and point-mass vehicles, a
hovering, a moving and a held leader, injected faults, the oracle's mean field, and a field
written in Python, which the world flies step by step between the compiled terms), then one
short trial on each other autopilot stack (the generic loop and the Crazyflie firmware's two, as
the Crazyflie worlds fly them) and under each other controller profile (ours, with its
accelerometer observer and the torque feed-forward; the paper's, as Freyja publishes it), then
the paths no campaign takes (the world stepped from Python, as ``bench`` and the studies step
it; the vehicles under rotor commands and under their autopilots alone, as the peer comparisons
fly them); nothing is written. One line per part on stderr.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

import numpy as np

from aerodock.config import Config, load_config
from aerodock.config.schema import STACKS
from aerodock.control.controller import PositionController, Reference
from aerodock.control.profiles import controller_config
from aerodock.jit import compile_general_signatures
from aerodock.mission.batch import run_campaign
from aerodock.mission.faults import Fault
from aerodock.mission.spec import Compensation, MissionSpec
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command
from aerodock.world.period import PARALLEL_MIN_TRIALS
from aerodock.world.vehicles.rigid_body import (
    RigidBodyParams,
    hover_rigid_state,
    step_rigid_body,
    step_with_autopilot,
)
from aerodock.world.vehicles.targets import rigid_targets

_SHORT = {"mission": {"settle_s": 0.2, "post_dock_s": 0.1, "dock_window_s": 0.2,
                      "backoff_s": 0.2, "leader_ramp_s": 0.2},
          "planner": {"hold_s": 0.2}}
# A field written in Python (the plug-in template's): the world flies it step by step
_PYTHON_FIELD = {"downwash": {"field": "aerodock.downwash.template:UniformColumnField"}}


def _step_the_world(cfg: Config) -> None:
    """The world stepped from Python, one physics step a call (``bench``'s, the studies')."""
    n = 2
    world = World(cfg, n, TrialRNG(0, n))
    lead = np.tile([0.0, 0.0, -2.5], (n, 1))
    world.reset(lead, lead + [0.05, 0.0, 0.6])
    cmd = hover_command(world.vehicle, n)
    for _ in range(3):
        world.step(cmd, cmd)


def _fly_the_vehicles_alone(cfg: Config) -> None:
    """The vehicles without the world: under rotor-speed commands, and flown by their
    autopilots under the position controller (the peer comparisons' paths)."""
    params = RigidBodyParams.from_config(cfg)
    n, dt = 1, 0.002
    state = hover_rigid_state(params, np.zeros((n, 3)), 0.0, np.ones(n))
    zero3, zero = np.zeros((n, 3)), np.zeros(n)
    step_rigid_body(state, state.rotor_speed.copy(), zero3, None, params, dt)
    step_rigid_body(state, state.rotor_speed.copy(), zero3, zero3, params, dt)
    ctl = PositionController(cfg, n, use_observer=False)
    ref = Reference(np.zeros((n, 3)), zero3, zero3, zero, zero)
    cmd = ctl.step(state.p, state.v, state.rpy, ref).command
    targets = rigid_targets(cmd, state, params, n)
    for _ in range(2):
        state, _ = step_with_autopilot(state, targets, zero3, zero3, params, dt)


def warm(out: TextIO = sys.stderr) -> float:
    """Fly the warm-up's parts (compiling what is not cached yet); the seconds it took."""
    start = time.perf_counter()
    print("aerodock: compiling the world's kernels once (cached for later runs; about ten "
          "minutes the first time, seconds after)", file=out, flush=True)
    cfg = load_config().with_overrides(_SHORT, source="warm-up")
    point_mass = cfg.with_overrides({"vehicle": {"model": "point-mass"}}, source="warm-up")
    one = MissionSpec(trials=1, compensation=Compensation.OBSERVER)
    ours = controller_config(cfg, "ours")
    parts: list[tuple[str, Callable[[], object]]] = [
        # enough trials for the period's blocks across the threads (world/period.py)
        ("rigid-body world, trials in blocks across the cores", lambda: run_campaign(
            cfg, MissionSpec(trials=PARALLEL_MIN_TRIALS, compensation=Compensation.OBSERVER))),
        ("the oracle's mean field, a moving leader", lambda: run_campaign(
            cfg, MissionSpec(trials=2, compensation=Compensation.ORACLE,
                             leader_speed_mps=0.25))),
        ("a rotor fault", lambda: run_campaign(
            cfg, MissionSpec(trials=1, compensation=Compensation.NONE,
                             faults=(Fault("rotor", "rotor_thrust_loss", magnitude=0.1),)))),
        ("point-mass world, a held leader", lambda: run_campaign(
            point_mass, MissionSpec(trials=2, compensation=Compensation.OBSERVER,
                                    leader_fixed=True))),
        ("point-mass world", lambda: run_campaign(
            point_mass, MissionSpec(trials=2, compensation=Compensation.OBSERVER))),
        ("a field written in Python", lambda: run_campaign(
            cfg.with_overrides(_PYTHON_FIELD, source="warm-up"), one)),
    ]
    # the default stack was flown above; a repeat loads from the cache
    parts += [(f"the {stack} autopilot", lambda stack=stack: run_campaign(
        cfg.with_overrides({"autopilot": {"stack": stack}}, source="warm-up"), one))
        for stack in STACKS]
    parts += [
        ("our controller", lambda: run_campaign(ours, one)),
        ("our controller with the torque feed-forward", lambda: run_campaign(
            ours.with_overrides({"control": {"torque_feedforward": True}}, source="warm-up"),
            one)),
        ("the paper's controller", lambda: run_campaign(controller_config(cfg, "paper"), one)),
        ("the world stepped from Python", lambda: _step_the_world(cfg)),
        ("the vehicles alone", lambda: _fly_the_vehicles_alone(cfg)),
        # what a kernel runs for arrays of other layouts (aerodock.jit)
        ("every layout's signature", compile_general_signatures),
    ]
    for k, (label, part) in enumerate(parts, 1):
        began = time.perf_counter()
        part()
        print(f"aerodock: [{k}/{len(parts)}] {label} ({time.perf_counter() - began:.0f} s)",
              file=out, flush=True)
    return time.perf_counter() - start


if __name__ == "__main__":
    took = warm()
    print(f"aerodock: kernels ready ({took:.0f} s)", file=sys.stderr)
