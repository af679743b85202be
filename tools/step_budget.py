"""Where one Gymnasium environment's step goes, part by part, in microseconds of wall time.

::

    python tools/step_budget.py [--envs 1] [--steps 300]
    python tools/step_budget.py --sim [--envs 1] [--steps 2000] [--physics-only]

Wraps the parts of a step with timers (the env's ``step``, the mission's ``fly`` and ``decide``,
the world's ``advance`` and its compiled period kernel, both position controllers, the mission's
phases and the motion capture), flies a warm-up, resets, then ``--steps`` steps with random
residual actions, and prints each part's time per environment step and its calls per step. The
parts nest (``fly`` holds ``advance`` and ``decide``; ``advance`` holds the kernel), so the
figures do not add up; what a part costs beyond those it holds is its figure less theirs. The
timers cost about 0.2 µs a call.

``--sim``: the same for the bench's ``SimLoop`` instead of an environment (``--envs`` trials,
``--steps`` control periods; with both controllers, or held hover commands with
``--physics-only``): the period, ``advance``, the kernel, the autopilots' targets, the per-step
path, the motion capture and the controllers, µs per period.
"""

from __future__ import annotations

import argparse
import collections
import time
from collections.abc import Callable
from typing import Any

import numpy as np

TIMES: collections.Counter = collections.Counter()
CALLS: collections.Counter = collections.Counter()


def timed(owner: Any, name: str, label: str) -> None:
    """Replace ``owner.name`` by the same callable timed under ``label``."""
    inner: Callable[..., Any] = getattr(owner, name)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            TIMES[label] += time.perf_counter() - start
            CALLS[label] += 1

    setattr(owner, name, wrapper)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=1)
    parser.add_argument("--steps", type=int, default=None)
    parser.add_argument("--sim", action="store_true", help="the bench's SimLoop, not an env")
    parser.add_argument("--physics-only", action="store_true", help="with --sim: no controllers")
    args = parser.parse_args()
    if args.sim:
        return sim_budget(args.envs, args.steps or 2000, not args.physics_only)
    args.steps = args.steps or 300

    import aerodock.control.controller as controller
    import aerodock.envs.vector as vector
    import aerodock.mission.batch as batch
    import aerodock.mission.phases.approach as approach
    import aerodock.mission.phases.leader as leader
    import aerodock.world.period as period
    import aerodock.world.world as world
    from aerodock.config import load_config

    labels = time_parts([
        (vector.DockingVectorEnv, "step", "env step"),
        (batch.MissionBatch, "fly", "  mission fly"),
        (world.World, "advance", "    world advance"),
        (period, "period_kernel", "      period kernel (serial)"),
        (period, "period_kernel_parallel", "      period kernel (blocks)"),
        (batch.MissionBatch, "decide", "    mission decide"),
        (leader, "leader_command", "      leader's command (its controller)"),
        (approach, "replan", "      approach replan"),
        (world.World, "observe", "      motion capture"),
        (controller.PositionController, "step", "  position controllers (both)")])

    env = vector.DockingVectorEnv(num_envs=args.envs, config=load_config())
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (args.steps, args.envs, 3))
    env.reset(seed=0)
    for a in actions[:min(100, args.steps)]:
        env.step(a.astype(np.float32))
    env.reset(seed=1)  # its settled start flies many periods: not counted
    TIMES.clear()
    CALLS.clear()
    for a in actions:
        env.step(a.astype(np.float32))
    print(f"{args.envs} environment(s), {args.steps} steps: µs per step (calls per step)")
    report(labels, args.steps)
    return 0


def time_parts(parts: list[tuple[Any, str, str]]) -> list[str]:
    """:func:`timed` on each (owner, name, label); the labels, in order."""
    for owner, name, label in parts:
        timed(owner, name, label)
    return [label for _, _, label in parts]


def report(labels: list[str], count: int) -> None:
    """Each timed part that ran: µs and calls per step (or period) over ``count`` of them."""
    for label in labels:
        if CALLS[label]:
            print(f"{label:42s} {1e6 * TIMES[label] / count:8.1f}  ({CALLS[label] / count:.2f})")


def sim_budget(n: int, periods: int, controllers: bool) -> int:
    """The ``--sim`` budget: SimLoop's parts, µs of wall time per control period."""
    import aerodock.control.controller as controller
    import aerodock.world.period as period
    import aerodock.world.world as world
    from aerodock.bench.simulator import SimLoop
    from aerodock.config import load_config

    labels = time_parts([
        (world.World, "advance", "  world advance"),
        (period, "period_kernel", "    period kernel (serial)"),
        (period, "period_kernel_parallel", "    period kernel (blocks)"),
        (world.World, "_targets", "    autopilots' targets"),
        (world, "step_world", "    per-step path"),
        (world.World, "observe", "  motion capture"),
        (controller.PositionController, "step", "  position controllers (both)")])
    loop = SimLoop(load_config(), n)
    loop.run(200, controllers)
    loop.reset()
    loop.run(200, controllers)
    TIMES.clear()
    CALLS.clear()
    start = time.perf_counter()
    loop.run(periods, controllers)
    whole = time.perf_counter() - start
    what = "with both controllers" if controllers else "physics only"
    print(f"SimLoop, {n} trial(s), {periods} periods, {what}: µs per period (calls per period)")
    print(f"{'period':42s} {1e6 * whole / periods:8.1f}")
    report(labels, periods)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
