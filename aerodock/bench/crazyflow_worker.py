"""crazyflow's side of the batched peer comparison, in a process of its own.

crazyflow needs SciPy in its array-API mode (``SCIPY_ARRAY_API=1``, set before SciPy is
imported), which aerodock's process has long imported; so :mod:`aerodock.bench.peer_batches`
runs this file as a script (``python -P crazyflow_worker.py N COMMANDS.npz``), which imports
crazyflow before anything else and nothing of aerodock.

The protocol, one line each way: the worker builds and compiles the flight, then prints
``@peer {"ready": ...}`` (or ``@peer {"error": "Type: message"}`` and exits); each ``fly`` line
on its stdin flies the scenario once and answers ``@peer {"wall_s", "cpu_s", "error_m"}``;
end of input ends it. Any other output (JAX's and MuJoCo's notes) is not part of the protocol.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from typing import Any

PREFIX = "@peer "


def _say(message: dict[str, Any]) -> None:
    print(PREFIX + json.dumps(message), flush=True)


class CrazyflowRun:
    """``n`` crazyflow worlds of one drone each (its default Crazyflie, first-principles
    dynamics, Euler integration, float32: crazyflow's defaults), 500 Hz physics, its Mellinger
    state controller at 100 Hz, flying ``commands`` (``(periods, 16)`` state commands, one per
    control period, z-up): the whole flight is one jitted ``jax.lax.scan`` over control periods
    (stage the period's command, then ``Sim``'s own jitted step of 5 physics steps), crazyflow's
    fastest way to fly it.

    Building it compiles the flight and settles the drones in hover at the first command's
    position (one untimed flight, so that every timed flight starts from hover with spun-up
    rotors); :meth:`fly` is what is timed.
    """

    def __init__(self, n: int, commands: Any, target_m: Any, physics_hz: int = 500,
                 control_hz: int = 100):
        import crazyflow  # noqa: F401 - first: it sets SciPy's array-API mode
        import jax
        import jax.numpy as jnp
        import numpy as np
        from crazyflow.control import Control
        from crazyflow.sim import Sim, functional

        self._jax, self._np = jax, np
        every = physics_hz // control_hz
        with warnings.catch_warnings():  # MuJoCo's notes on building the scene
            warnings.simplefilter("ignore")
            sim = Sim(n_worlds=n, n_drones=1, control=Control.state, freq=physics_hz,
                      state_freq=control_hz, attitude_freq=physics_hz, device="cpu")
        step = sim.build_step_fn()

        @jax.jit
        def fly(data: Any, cmds: Any) -> Any:
            def period(d: Any, cmd: Any) -> tuple[Any, None]:
                d = functional.state_control(d, jnp.broadcast_to(cmd, (n, 1, 16)))
                return step(d, n_steps=every), None

            return jax.lax.scan(period, data, cmds)[0]

        self._fly = fly
        self.commands = jnp.asarray(commands, jnp.float32)
        hover = np.repeat(np.asarray(commands[:1], np.float32), len(commands), 0)
        hover[:, 3:9] = 0.0
        start = jnp.broadcast_to(jnp.asarray(commands[0, 0:3], jnp.float32), (n, 1, 3))
        data = sim.data.replace(states=sim.data.states.replace(pos=start))
        self.start = jax.block_until_ready(fly(data, jnp.asarray(hover)))
        self.target_m = np.asarray(target_m, float)
        self.fly()  # the settled state's types differ from the built one's: compiled again

    def fly(self) -> float:
        """Fly the commands from the settled hover; the first drone's final position error (m)."""
        end = self._jax.block_until_ready(self._fly(self.start, self.commands))
        return float(self._np.linalg.norm(self._np.asarray(end.states.pos[0, 0]) - self.target_m))


def main(argv: list[str]) -> int:
    """Build the flight for ``argv = [n, commands.npz]``, then fly it once per ``fly`` line."""
    try:
        from importlib.metadata import version

        import crazyflow  # noqa: F401 - before NumPy's and SciPy's users
        import numpy as np

        t0 = time.perf_counter()
        with np.load(argv[1]) as npz:
            run = CrazyflowRun(int(argv[0]), npz["commands"], npz["target_m"])
        _say({"ready": True, "build_s": time.perf_counter() - t0,
              "version": version("crazyflow")})
    except Exception as err:  # noqa: BLE001 - the parent reports it as one line
        text = str(err).strip().splitlines()
        _say({"error": f"{type(err).__name__}: {text[0]}" if text else type(err).__name__})
        return 0
    for line in sys.stdin:
        if line.strip() != "fly":
            continue
        c0, t0 = time.process_time(), time.perf_counter()
        error_m = run.fly()
        _say({"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0,
              "error_m": error_m})
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
