"""Peers in one run: crazyflow (utiasDSL's JAX + MuJoCo drone simulator) and aerodock on the
peer scenario of :mod:`aerodock.bench.peer` at batches of 1, 256 and 1,024, with aerodock's
full world beside them (``aerodock bench --only peer``; crazyflow is the optional extra
``aerodock[peer]``, and the comparison is skipped with a one-line reason without it)."""

from __future__ import annotations

import contextlib
import json
import statistics
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.bench.peer import (
    PEER_CONTROL_HZ,
    PEER_PHYSICS_HZ,
    _peer_steps,
    peer_aerodock,
    peer_reference,
)
from aerodock.bench.timing import Progress, figure, quiet, unavailable

PEER_BATCHES = (1, 256, 1024)
CRAZYFLOW_START_ZUP_M = (0.0, 0.0, 1.0)  # crazyflow's world is z-up, its floor at z = 0
_NED_TO_ZUP = np.array([1.0, -1.0, -1.0])


def crazyflow_missing() -> str | None:
    """Why crazyflow cannot run here, as one line (None: it seems installed; it is imported in
    its own process, :class:`CrazyflowWorker`, which reports its own failures)."""
    from importlib.util import find_spec

    for module in ("crazyflow", "jax"):
        if find_spec(module) is None:
            return f"{module} not installed: pip install 'aerodock[peer]' to fly crazyflow"
    return None


def crazyflow_commands(ref: dict[str, np.ndarray], every: int) -> np.ndarray:
    """crazyflow's state commands for ``ref`` (NED, from :func:`peer_reference`), one per control
    period: ``(periods, 16)`` float32 rows ``[x, y, z, vx, vy, vz, ax, ay, az, qx, qy, qz, qw,
    wx, wy, wz]`` in its z-up world, from :data:`CRAZYFLOW_START_ZUP_M`, yaw zero."""
    rows = np.arange(0, len(ref["x"]), every)
    cmds = np.zeros((len(rows), 16), np.float32)
    cmds[:, 0:3] = ref["x"][rows] * _NED_TO_ZUP + np.array(CRAZYFLOW_START_ZUP_M)
    cmds[:, 3:6] = ref["x_dot"][rows] * _NED_TO_ZUP
    cmds[:, 6:9] = ref["x_ddot"][rows] * _NED_TO_ZUP
    cmds[:, 12] = 1.0  # the identity quaternion (x, y, z, w)
    return cmds


class CrazyflowUnavailable(RuntimeError):
    """crazyflow could not fly here; the message is the one-line reason."""


class CrazyflowWorker:
    """crazyflow's ``n`` worlds flying ``commands`` in a process of its own
    (:mod:`aerodock.bench.crazyflow_worker`: crazyflow needs SciPy's array-API mode, set before
    SciPy is imported). Starting it builds and compiles the flight; :meth:`fly` flies it once
    and returns ``(wall s, CPU s of the worker, first drone's final error m)``, timed in the
    worker, while this process waits. A use as a context manager ends the worker.

    Raises :class:`CrazyflowUnavailable` with a one-line reason if the worker cannot build the
    flight or stops answering.
    """

    def __init__(self, n: int, commands: np.ndarray, target_m: np.ndarray):
        import os
        import subprocess
        import sys
        import tempfile

        from aerodock.bench import crazyflow_worker

        self._tmp = tempfile.TemporaryDirectory(prefix="aerodock-crazyflow-")
        path = Path(self._tmp.name) / "commands.npz"
        np.savez(path, commands=np.asarray(commands, np.float32),
                 target_m=np.asarray(target_m, float))
        self._stderr = open(Path(self._tmp.name) / "stderr.txt", "w+")  # noqa: SIM115
        # -P: the script's folder (aerodock/bench) is not put on sys.path
        self._proc = subprocess.Popen(
            [sys.executable, "-P", crazyflow_worker.__file__, str(n), str(path)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr, text=True,
            env=dict(os.environ, SCIPY_ARRAY_API="1"))
        try:
            ready = self._answer()
            if "error" in ready:
                raise CrazyflowUnavailable(ready["error"])
        except BaseException:
            self.close()
            raise
        self.version: str = ready.get("version", "")
        self.build_s: float = ready.get("build_s", float("nan"))

    def _answer(self) -> dict[str, Any]:
        from aerodock.bench.crazyflow_worker import PREFIX

        assert self._proc.stdout is not None
        for line in self._proc.stdout:
            if line.startswith(PREFIX):
                return json.loads(line[len(PREFIX):])
        code = self._proc.wait()
        self._stderr.seek(0)
        last = [ln.strip() for ln in self._stderr.read().splitlines() if ln.strip()]
        raise CrazyflowUnavailable(f"its process ended (exit code {code})"
                                   + (f": {last[-1]}" if last else ""))

    def fly(self) -> tuple[float, float, float]:
        """One flight: ``(wall s, worker CPU s, final error m)``."""
        assert self._proc.stdin is not None
        self._proc.stdin.write("fly\n")
        self._proc.stdin.flush()
        got = self._answer()
        return got["wall_s"], got["cpu_s"], got["error_m"]

    def close(self) -> None:
        """End the worker (its input closed, then killed if it lingers) and remove its files."""
        if self._proc.poll() is None:
            with contextlib.suppress(OSError):
                self._proc.stdin.close()  # type: ignore[union-attr]
            try:
                self._proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._stderr.close()
        self._tmp.cleanup()

    def __enter__(self) -> CrazyflowWorker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


Run = tuple[float, float, float]  # wall s, CPU s, final error m


def _timed(fn: Callable[[], float]) -> Run:
    """``(wall s, process CPU s, fn's result)`` of one call of ``fn``."""
    c0, t0 = time.process_time(), time.perf_counter()
    result = fn()
    return time.perf_counter() - t0, time.process_time() - c0, result


def _fig(runs: list[Run], vehicle_steps: int, note: str, error: bool = True) -> dict[str, Any]:
    """Vehicle-steps/s of the runs (median, spread), per CPU-second, and the final error."""
    out = figure([vehicle_steps / wall for wall, _, _ in runs], "vehicle-steps/s", note)
    out["per_cpu_s"] = float(statistics.median(vehicle_steps / max(cpu, 1e-9)
                                               for _, cpu, _ in runs))
    out["vehicle_steps"] = vehicle_steps
    if error:
        out["final_error_m"] = float(statistics.median(err for _, _, err in runs))
    return out


_NOTES = {
    "crazyflow": "{n} worlds x 1 drone (its Crazyflie), Mellinger state control at 100 Hz, "
                 "500 Hz, one jitted scan, float32, in its own process",
    "aerodock_rigid_body": "{n} rigid-body vehicles + autopilot at 500 Hz, LQR at 100 Hz",
    "aerodock_world": "the full world, {n} trials x 2 vehicles, LQR + observer at 100 Hz, "
                      "holding the docking formation",
}


def compare_crazyflow(cfg: Any, quick: bool = False, batches: tuple[int, ...] = PEER_BATCHES,
                      progress: Progress = quiet) -> dict[str, Any]:
    """crazyflow, aerodock's rigid body and aerodock's full world, timed alternately per batch.

    At each batch ``n``: crazyflow's ``n`` worlds of one drone (:class:`CrazyflowWorker`) and
    aerodock's ``n`` rigid-body vehicles (:func:`peer_aerodock`: autopilot, rotors, rigid body
    at 500 Hz, LQR at 100 Hz) fly the peer scenario (hover 1 s, then the 4 s minimum-jerk move;
    ``quick``: the first half); aerodock's full world
    (:class:`aerodock.bench.simulator.SimLoop`: ``n`` trials of two vehicles each, the wake on
    rotor disks and bar, IMU chain and attitude estimate, bar on cables, gripper, both LQR +
    observer controllers at 100 Hz) flies as many control periods, holding its docking
    formation. A figure is vehicle-steps per second of wall time (the median of the runs, the
    three run in turn, one run each at a time) and per CPU-second of the process that flew it;
    a ratio is the median over the turns of crazyflow's wall time per vehicle-step over
    aerodock's (above 1: aerodock is faster).

    Without crazyflow, nothing is flown: ``crazyflow`` is an unavailable figure with its
    one-line reason (so too if its worker fails), and ``ratios`` is None.
    """
    from aerodock.bench.simulator import SimLoop

    steps = _peer_steps(quick)
    dt = 1.0 / PEER_PHYSICS_HZ
    every = int(round(PEER_PHYSICS_HZ / PEER_CONTROL_HZ))
    out: dict[str, Any] = {"scenario": {
        "physics_hz": PEER_PHYSICS_HZ, "control_hz": PEER_CONTROL_HZ, "steps": steps,
        "simulated_s": steps * dt, "batches": list(batches)}}
    missing = crazyflow_missing()
    if missing is not None:
        out["crazyflow"] = unavailable(missing, "vehicle-steps/s")
        out["ratios"] = None
        return out
    ref = peer_reference(steps, dt)
    commands = crazyflow_commands(ref, every)
    target_m = ref["x"][-1] * _NED_TO_ZUP + np.array(CRAZYFLOW_START_ZUP_M)
    periods = steps // every
    reps = 1 if quick else 3
    figs: dict[str, dict[str, Any]] = {key: {} for key in _NOTES}
    ratios: dict[str, dict[str, float]] = {}
    for n in batches:
        progress(f"peer: crazyflow {n} worlds (building, compiling), aerodock's rigid body "
                 f"and full world at {n}")
        try:
            worker = CrazyflowWorker(n, commands, target_m)
        except CrazyflowUnavailable as err:
            out["crazyflow"] = unavailable(f"crazyflow failed at {n} worlds: {err}",
                                           "vehicle-steps/s")
            out["ratios"] = None
            return out
        out["scenario"]["crazyflow_version"] = worker.version
        loop = SimLoop(cfg, n)

        def world(loop: SimLoop = loop) -> Run:
            loop.reset()
            return _timed(lambda: (loop.run(periods), float("nan"))[1])

        runners: dict[str, Callable[[], Run]] = {
            "crazyflow": worker.fly,
            "aerodock_rigid_body": lambda n=n: _timed(
                lambda: peer_aerodock(cfg, n, steps, ref)[0]),
            "aerodock_world": world,
        }
        peer_aerodock(cfg, n, 2 * every, ref)  # warm-ups (crazyflow's is in its build)
        loop.run(2)
        runs: dict[str, list[Run]] = {key: [] for key in runners}
        with worker:
            for _ in range(reps):
                for key, run in runners.items():
                    runs[key].append(run())
        vehicles = {"crazyflow": n, "aerodock_rigid_body": n, "aerodock_world": 2 * n}
        for key, note in _NOTES.items():
            figs[key][str(n)] = _fig(runs[key], vehicles[key] * steps, note.format(n=n),
                                     error=key != "aerodock_world")
        per_step = {key: [wall / (vehicles[key] * steps) for wall, _, _ in runs[key]]
                    for key in runners}
        ratios[str(n)] = {
            f"{key.removeprefix('aerodock_')}_vs_crazyflow": float(statistics.median(
                c / a for c, a in zip(per_step["crazyflow"], per_step[key])))
            for key in ("aerodock_rigid_body", "aerodock_world")}
    out.update(figs)
    out["ratios"] = ratios
    return out
