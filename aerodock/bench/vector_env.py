"""Throughput of the native vector environment (``aerodock bench``: ``gym_vector_env``; on its
own: ``python -m aerodock.bench.vector_env [--quick]``). Needs ``aerodock[gym]``."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from aerodock.bench.timing import figure, measure
from aerodock.envs import DockingVectorEnv  # gymnasium: ImportError without aerodock[gym]

ENV_BATCHES = (1, 128, 256)  # 128: issue 38's target for the vector env


def bench_vector_env(cfg: Any, batches: tuple[int, ...] = ENV_BATCHES, quick: bool = False,
                     progress: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Env-steps per second (environments x steps / wall time) of ``DockingVectorEnv`` stepped
    with random residual actions, per batch size: the whole world at 500 Hz physics, both
    controllers, the planner and the mission logic, one control period (10 ms) per step."""
    out: dict[str, Any] = {}
    repeats = 3 if quick else 5
    for n in batches:
        progress(f"gym vector env: {n} envs")
        env = DockingVectorEnv(num_envs=n, config=cfg)
        steps = max(10, int((200 if n <= 64 else 60) * (0.5 if quick else 1)))
        actions = np.random.default_rng(0).uniform(-1, 1, (steps, n, 3)).astype(np.float32)

        def run(env: Any = env, actions: np.ndarray = actions) -> None:
            for a in actions:
                env.step(a)

        times = measure(run, repeats, warmup=1, setup=lambda env=env: env.reset(seed=0))
        out[str(n)] = figure([n * steps / t for t in times], "env-steps/s",
                             f"{n} envs, {steps} steps of 10 ms, random residual actions")
    return out


if __name__ == "__main__":  # python -m aerodock.bench.vector_env [--quick]: the figures as JSON
    import sys

    from aerodock.config import load_config
    from aerodock.fileio import dumps_json, json_ready

    print(dumps_json(json_ready(bench_vector_env(load_config(), quick="--quick" in sys.argv))))
