"""The RotorPy peer: the same vehicle and scenario flown by RotorPy and by aerodock, both timed
in one run (the rigid-body vehicle, as the world flies it)."""

from __future__ import annotations

import contextlib
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from aerodock.bench.timing import Progress, failure_reason, figure, quiet, unavailable

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
    """aerodock's side: ``n`` rigid-body quadrotors as the world flies them (the autopilot on the
    gyro, rotors with motor lag, rigid-body dynamics: :func:`rigid_targets` once per control
    period, :func:`step_with_autopilot` at 500 Hz) under the LQR position controller at 100 Hz
    (no observer, true state, no noise), flying ``ref``; the command is clipped once per control
    period and held, as :meth:`aerodock.world.world.World.advance` does.

    Returns the final position error of the first vehicle (m: a check that it tracked) and the
    time spent in the vehicle step alone (s).
    """
    from aerodock.control.controller import PositionController, Reference
    from aerodock.world.vehicles.rigid_body import (
        RigidBodyParams,
        hover_rigid_state,
        step_with_autopilot,
    )
    from aerodock.world.vehicles.targets import rigid_targets

    params = RigidBodyParams.from_config(cfg)
    dt = 1.0 / PEER_PHYSICS_HZ
    every = int(round(PEER_PHYSICS_HZ / PEER_CONTROL_HZ))
    ctl = PositionController(cfg, n, use_observer=False)
    state = hover_rigid_state(params, np.zeros((n, 3)), 0.0, np.ones(n))
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
            targets = rigid_targets(cmd, state, params, n)
            physics_s += clock() - t0
        t0 = clock()
        state, _ = step_with_autopilot(state, targets, zero3, zero3, params, dt)
        physics_s += clock() - t0
    return float(np.linalg.norm(state.p[0] - ref["x"][steps - 1])), physics_s


_NED_TO_ZUP = np.array([1.0, -1.0, -1.0])  # RotorPy's world is z-up: (x, y, z) -> (x, -y, -z)
_FLAT_KEYS = ("x", "x_dot", "x_ddot", "x_dddot", "x_ddddot")


def _rotorpy_params(cfg: Any) -> dict[str, Any]:
    """aerodock's rigid-body vehicle of ``cfg`` as RotorPy's ``quad_params`` (the mapping of
    :func:`aerodock.validation.peer.rotorpy_quad_params`): both simulators fly one vehicle."""
    from aerodock.validation.peer import rigid_params, rotorpy_quad_params

    return rotorpy_quad_params(rigid_params(cfg))


def _hover_rotor_speed(quad: dict[str, Any]) -> float:
    return float(np.sqrt(quad["mass"] * 9.81 / (quad["num_rotors"] * quad["k_eta"])))


def peer_rotorpy(cfg: Any, steps: int, ref: dict[str, np.ndarray]) -> tuple[float, float]:
    """RotorPy's side: one ``Multirotor`` (aerodock's vehicle, :func:`_rotorpy_params`; its
    default RK45 integrator and motor-speed commands) stepped sequentially at 500 Hz under
    ``SE3Control``, which runs at every step as in RotorPy's own ``simulate`` loop.

    Returns the final position error (m) and the time spent in ``Multirotor.step`` alone (s).
    """
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.vehicles.multirotor import Multirotor

    quad = _rotorpy_params(cfg)
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


def peer_rotorpy_batched(cfg: Any, n: int, steps: int,
                         ref: dict[str, np.ndarray]) -> tuple[float, float]:
    """RotorPy's batched simulator (PyTorch): ``BatchedMultirotor`` with ``BatchedSE3Control``
    at 500 Hz, ``n`` of aerodock's vehicles on the CPU, fixed-step RK4 (its faster integrator
    option).

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
    quad = _rotorpy_params(cfg)
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
        return failure_reason(err)
    return None


_Runner = Callable[[int], tuple[float, float]]
"""A timed side of the peer: ``runner(steps) -> (final error m, physics s)``."""
_Run = tuple[float, float, float]
"""One timed run: ``(wall s, physics s, final error m)``."""


def _alternating_runs(ours: _Runner, theirs: _Runner | None, steps: int, reps: int,
                      warm_theirs: int) -> tuple[list[_Run], list[_Run]]:
    """Alternating timed runs of ``ours`` and ``theirs`` (aerodock, peer, aerodock, ...).

    Args:
        ours: aerodock's side.
        theirs: the peer's side (None: ours only).
        steps: physics steps per run.
        reps: timed runs of each side.
        warm_theirs: the peer's warm-up run's steps (ours warms up on ``steps``).

    Returns:
        ``(ours, theirs)`` runs, ``(wall s, physics s, final error m)`` each.
    """
    ours(steps)
    if theirs is not None:
        theirs(warm_theirs)
    a: list[_Run] = []
    b: list[_Run] = []
    for _ in range(reps):
        for runner, runs in ((ours, a), (theirs, b)):
            if runner is None:
                continue
            t0 = time.perf_counter()
            err, physics = runner(steps)
            runs.append((time.perf_counter() - t0, physics, err))
    return a, b


def _run_figure(runs: list[_Run], vehicles: int, steps: int, note: str) -> dict[str, Any]:
    """A side's figure: its wall times (:func:`aerodock.bench.timing.figure`), and the median
    run's wall time (``value``), physics time, vehicle steps per second of each, and error."""
    wall, physics, err = sorted(runs)[len(runs) // 2]  # the median run (odd counts)
    out_fig = figure([r[0] for r in runs], "s", note)
    out_fig.update({"value": wall, "physics_s": physics,
                    "vehicle_steps_per_s": vehicles * steps / wall,
                    "physics_vehicle_steps_per_s": vehicles * steps / physics,
                    "final_error_m": err})
    return out_fig


def _pair_ratio(theirs: list[_Run], ours: list[_Run], index: int) -> float:
    """The median over alternating pairs of their run's ``index`` figure over ours."""
    return float(statistics.median(t[index] / o[index] for t, o in zip(theirs, ours)))


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
                    progress: Progress = quiet, repeats: int | None = None) -> dict[str, Any]:
    """Time the peer scenario with RotorPy and with aerodock in one run; times and ratios.

    Scenario: one quadrotor, aerodock's rigid-body vehicle of ``cfg`` in both simulators
    (:func:`aerodock.validation.peer.rotorpy_quad_params`), hovers for 1 s, then flies a 4 s
    minimum-jerk move (1 m north, 0.5 m east, 0.3 m up) under its position controller, 500 Hz
    physics; ``quick`` flies the first half of it. RotorPy: ``Multirotor`` stepped sequentially
    (one trial), and its batched simulator when importable (PyTorch, ``torchdiffeq``, ``roma``).
    aerodock: the rigid body with its autopilot as the world steps it, under the LQR position
    controller, batch of 1 and of ``batch``.

    Each run's figure is its whole wall time (``value``, median over repetitions after a
    warm-up) and the part of it spent in the physics step (``physics_s``, of the median run).
    The two simulators' runs alternate (aerodock, RotorPy, aerodock, ...), so that a change of
    load on the machine hits both; a ratio is the median of the ratios of these pairs.
    ``repeats`` sets every side's number of timed runs (None: three to five; 1 for a smoke run,
    which checks that each side runs, not its time).
    """
    if repeats is not None and repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
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

    reps = repeats or ((3 if quick else 5) if not have_rotorpy else 3)
    progress("peer: aerodock batch of 1" + (" and RotorPy Multirotor, alternating"
                                            if have_rotorpy else ""))
    one, seq = _alternating_runs(
        lambda k: peer_aerodock(cfg, 1, k, ref),
        (lambda k: peer_rotorpy(cfg, k, ref)) if have_rotorpy else None, steps, reps, 50)
    out["aerodock_1"] = _run_figure(one, 1, steps, "rigid body + autopilot (step_with_autopilot) "
                                    "500 Hz + LQR PositionController 100 Hz")
    ratios: dict[str, float] = {}
    if have_rotorpy:
        out["rotorpy_sequential"] = _run_figure(
            seq, 1, steps, "Multirotor.step (RK45) 500 Hz + SE3Control at every step, aerodock's "
            "vehicle")
        ratios["single_trial"] = _pair_ratio(seq, one, 0)
        ratios["single_trial_physics_step"] = _pair_ratio(seq, one, 1)

    batched: _Runner | None = None
    if have_rotorpy:
        missing = _rotorpy_batched_missing()
        if missing is None:
            batched = lambda k: peer_rotorpy_batched(cfg, batch, k, ref)  # noqa: E731
        else:
            out["rotorpy_batched"] = unavailable(
                f"RotorPy's batched simulator not available ({missing})", "s")
    progress(f"peer: aerodock batch of {batch}"
             + (" and RotorPy batched, alternating" if batched else ""))
    ours = lambda k: peer_aerodock(cfg, batch, k, ref)  # noqa: E731
    try:
        with _torch_threads(1):
            many, bat = _alternating_runs(ours, batched, steps,
                                          repeats or (1 if (quick and batched) else 3), 20)
    except Exception as err:  # noqa: BLE001 - RotorPy's batched simulator failed: go on
        if batched is None:
            raise
        out["rotorpy_batched"] = unavailable(
            f"RotorPy's batched simulator failed ({failure_reason(err)})", "s")
        batched = None
        many, bat = _alternating_runs(ours, None, steps, repeats or 3, 20)
    out[f"aerodock_{batch}"] = _run_figure(many, batch, steps,
                                           f"the same, {batch} vehicles at once")
    if have_rotorpy:
        ratios[f"aerodock_batch_{batch}_vs_rotorpy_sequential"] = (
            out[f"aerodock_{batch}"]["vehicle_steps_per_s"]
            / out["rotorpy_sequential"]["vehicle_steps_per_s"])
    if batched is not None:
        out["rotorpy_batched"] = _run_figure(
            bat, batch, steps, f"BatchedMultirotor (RK4) + BatchedSE3Control 500 Hz, {batch} "
            "vehicles, CPU, 1 torch thread")
        ratios[f"batched_{batch}"] = _pair_ratio(bat, many, 0)
        ratios[f"batched_{batch}_physics_step"] = _pair_ratio(bat, many, 1)
    if not have_rotorpy:
        reason = "rotorpy not installed (pip install --no-deps rotorpy)"
        out["rotorpy_sequential"] = unavailable(reason, "s")
        out["rotorpy_batched"] = unavailable(reason, "s")
    out["ratios"] = ratios or None
    return out
