"""Compile the world's kernels once, ahead of use: ``python -m aerodock.mission.warm``.

The compiled step (:mod:`aerodock.jit`) keeps its machine code on disk beside the sources
(numba's cache), so a process loads it in a fraction of a second; only the first process to
need a kernel pays for compiling it (two to three minutes for the whole world on a 2-core machine).
``make`` runs this module right after installing, so neither a user's first command nor a test
process pays that. It flies a few short campaigns that between them take every compiled path of
the default worlds (a batch large enough for the control period's blocks across the cores, the
rigid-body and point-mass vehicles, a hovering and a moving leader,
injected faults, the oracle's mean field), then one short trial on each other autopilot stack
(the generic loop and the Crazyflie firmware's two, as the Crazyflie worlds fly them) and under
each other controller profile (ours, with its accelerometer observer and the torque
feed-forward; the paper's, as Freyja publishes it); nothing is written.
"""

from __future__ import annotations

import sys
import time

from aerodock.config import load_config
from aerodock.config.schema import STACKS
from aerodock.control.profiles import controller_config
from aerodock.jit import compile_general_signatures
from aerodock.mission.batch import run_campaign
from aerodock.mission.faults import Fault
from aerodock.mission.spec import Compensation, MissionSpec
from aerodock.world.period import PARALLEL_MIN_TRIALS

_SHORT = {"mission": {"settle_s": 0.2, "post_dock_s": 0.1, "dock_window_s": 0.2,
                      "backoff_s": 0.2, "leader_ramp_s": 0.2},
          "planner": {"hold_s": 0.2}}


def warm(out=sys.stderr) -> float:
    """Fly the warm-up campaigns (compiling what is not cached yet); the seconds it took."""
    start = time.perf_counter()
    print("aerodock: compiling the world's kernels once (cached for later runs; two to three "
          "minutes the first time)", file=out, flush=True)
    cfg = load_config().with_overrides(_SHORT, source="warm-up")
    point_mass = cfg.with_overrides({"vehicle": {"model": "point-mass"}}, source="warm-up")
    for config, spec in (
            # enough trials for the period's blocks across the threads (world/period.py)
            (cfg, MissionSpec(trials=PARALLEL_MIN_TRIALS, compensation=Compensation.OBSERVER)),
            (cfg, MissionSpec(trials=2, compensation=Compensation.ORACLE,
                              leader_speed_mps=0.25)),
            (cfg, MissionSpec(trials=1, compensation=Compensation.NONE,
                              faults=(Fault("rotor", "rotor_thrust_loss", magnitude=0.1),))),
            (point_mass, MissionSpec(trials=2, compensation=Compensation.OBSERVER,
                                     leader_fixed=True))):
        run_campaign(config, spec)
    one = MissionSpec(trials=1, compensation=Compensation.OBSERVER)
    for stack in STACKS:  # the default stack was flown above; a repeat loads from the cache
        run_campaign(cfg.with_overrides({"autopilot": {"stack": stack}}, source="warm-up"), one)
    ours = controller_config(cfg, "ours")
    for config in (ours, ours.with_overrides({"control": {"torque_feedforward": True}},
                                             source="warm-up"), controller_config(cfg, "paper")):
        run_campaign(config, one)
    compile_general_signatures()  # what a kernel runs for arrays of other layouts (aerodock.jit)
    return time.perf_counter() - start


if __name__ == "__main__":
    took = warm()
    print(f"aerodock: kernels ready ({took:.0f} s)", file=sys.stderr)
