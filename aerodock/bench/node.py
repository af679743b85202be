"""Latency of the learnt model next to a flight stack: the predictor alone, and ``aerodock node``
end to end over ROS 2 on this machine, per publish mode (``python -m aerodock.bench.node``).

- ``predictor``: one ``Predictor.predict_one`` call (the node's per-output work), µs: median
  and 99th percentile over many calls after a warm-up.
- ``node``: ``aerodock node --publish MODE`` in its own process (``--publish both``: one run
  per mode, one after the other), fed by a replay of a flight (both vehicles'
  nav_msgs/Odometry at 100 Hz, localhost, a ROS domain of its own): the output rate measured
  from the output stamps; how many outputs each trigger made (follower message, timer,
  watchdog) and how many follower messages were answered; ``node_ms`` (trigger to the output's
  stamp, from the node's diagnostics); ``end_to_end_ms``: the follower state's send stamp to
  the receipt of the output computed from it (paired by the diagnostics' ``follower_stamp``);
  in ``timer`` mode it includes the wait for the next tick, up to one period;
  ``state_to_prediction_ms``: each follower state sent to the receipt of the first output from
  it or a newer one (states skipped count too). ``path_ms``
  cuts it into consecutive pieces (:data:`PATH_SEGMENTS`; ``node_side_ms``: the node's share,
  :data:`NODE_SIDE`), and ``path_ms_in_the_worst_1pct`` says which pieces make the tail;
  ``cpu`` says, for the node's process and the replay's, how long they ran and how long they
  waited for a CPU while the replay sent (Linux scheduler statistics): whether a tail is work
  or the machine's load.

The model is a given model directory, or random weights in the default architecture (same cost
as a trained one). The numbers in docs/deploy.md's "Latency" section come from this module.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import dumps_json, json_ready
from aerodock.flightlog import FlightLog
from aerodock.geometry import euler_to_rotmat, rotmat_to_quat
from aerodock.learning.features import N_FEATURES, N_OUTPUTS
from aerodock.learning.kinds import get_kind
from aerodock.learning.modelfile import ModelSpec, save_model_dir
from aerodock.node.core import (
    DEFAULT_PUBLISH_MODE,
    TRIGGER_FOLLOWER,
    TRIGGER_TIMER,
    TRIGGER_WATCHDOG,
    PublishMode,
)


def random_model(path: Path, kind: str = "so2", seed: int = 3,
                 hidden: tuple[int, ...] = (64, 64)) -> Path:
    """A model directory with random weights (NumPy only), the default architecture (the
    kind's network layout: a deep-sets kind's ``rho`` also reads the ego features)."""
    rng = np.random.default_rng(seed)
    sizes = (N_FEATURES[kind], *hidden, N_OUTPUTS[kind])
    weights = [(rng.normal(0, 1 / np.sqrt(w_shape[1]), w_shape), rng.normal(0, 0.1, b_shape))
               for w_shape, b_shape in get_kind(kind).weight_shapes(sizes)]
    spec = ModelSpec(kind=kind, layer_sizes=sizes, activation="tanh",
                     in_mean=rng.normal(0, 0.2, sizes[0]), in_std=rng.uniform(0.5, 2, sizes[0]),
                     out_mean=rng.normal(0, 0.5, sizes[-1]),
                     out_std=rng.uniform(0.5, 2, sizes[-1]))
    vehicle = {"mass_kg": 0.7, "rotor_radius_m": 0.0635, "n_rotors": 4}
    return save_model_dir(path, spec, weights, vehicles={"leader": vehicle, "follower": vehicle})


def orbit_log(duration_s: float = 3.0, rate_hz: float = 100.0) -> FlightLog:
    """A follower circling 0.3 m off axis 0.6 m below a slowly moving, tilted leader (NED)."""
    t = np.arange(int(duration_s * rate_hz)) / rate_hz
    n = len(t)
    w = 2.0
    lp = np.stack([0.2 * t, 0.1 * np.sin(t), np.full(n, -2.0)], axis=1)
    lv = np.stack([np.full(n, 0.2), 0.1 * np.cos(t), np.zeros(n)], axis=1)
    fp = lp + np.stack([0.3 * np.cos(w * t), 0.3 * np.sin(w * t), 0.6 + 0.05 * np.sin(t)], 1)
    fv = lv + np.stack([-0.6 * np.sin(w * t), 0.6 * np.cos(w * t), 0.05 * np.cos(t)], 1)
    lq = rotmat_to_quat(euler_to_rotmat(0.05 * np.sin(t), 0.08 * np.cos(t), 0.4 * t))
    fq = rotmat_to_quat(euler_to_rotmat(0.1 * np.sin(w * t), -0.1 * np.cos(w * t), 0.2 * t))
    zeros = np.zeros((n, 3))
    return FlightLog(t_s=t, leader_pos_m=lp, leader_vel_mps=lv, leader_quat=lq,
                     follower_pos_m=fp, follower_vel_mps=fv, follower_quat=fq,
                     follower_cmd_accel_mps2=zeros, follower_thrust_n=np.full(n, 6.9),
                     follower_obs_accel_mps2=zeros, meta={"name": "orbit", "frame": "NED"})


def _stats(values: np.ndarray, digits: int = 3) -> dict[str, float | None]:
    """Median, p95, p99 and count of the known (finite) values; None without any."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return {"median": None, "p95": None, "p99": None, "n": 0}
    return {"median": round(float(np.median(v)), digits),
            "p95": round(float(np.percentile(v, 95)), digits),
            "p99": round(float(np.percentile(v, 99)), digits),
            "n": int(v.size)}


def predictor_latency(model: Path, calls: int = 20000) -> dict[str, Any]:
    """Time per ``predict_one`` call, µs (median, p95, p99), on this machine."""
    from aerodock.learning.runtime import Predictor
    from aerodock.node.core import VehicleState, model_inputs

    pred = Predictor.load(model)
    log = orbit_log(2.0)
    rot = euler_to_rotmat(0.05, 0.02, 0.3)
    samples = [model_inputs(VehicleState(log.leader_pos_m[i], log.leader_vel_mps[i], rot, 0.0),
                            VehicleState(log.follower_pos_m[i], log.follower_vel_mps[i], rot,
                                         0.0)) for i in range(log.n_samples)]
    for x, r in samples[:500]:
        pred.predict_one(x, r)
    times = np.empty(calls)
    clock = time.perf_counter
    for k in range(calls):
        x, r = samples[k % len(samples)]
        t0 = clock()
        pred.predict_one(x, r)
        times[k] = clock() - t0
    return {"kind": pred.kind, "per_call_us": _stats(times * 1e6, 2)}


PATH_SEGMENTS = {
    "replay_send": "the replay publishes the leader's, then the follower's message (the "
                   "follower's stamp to its publish call returning)",
    "to_trigger": "DDS into the node and the node's wait for its callback (on-follower), or for "
                  "the next tick (timer)",
    "node_queue": "of to_trigger: the follower message's wait in the node, from its DDS reception "
                  "to its callback (on-follower only)",
    "node": "the node's trigger (callback or tick) to the output's stamp: conversion, checks, "
            "predictor",
    "node_publish": "the node's publish call, to its DDS write (output stamp to the DDS source "
                    "time)",
    "dds_out": "DDS to the replay's DDS layer (source time to reception time; includes the "
               "wake-up of the replay's DDS receive thread)",
    "replay_wait": "the replay's executor: the f_ext's DDS reception to its callback",
}
"""The end-to-end path cut in consecutive pieces (they sum to ``end_to_end_ms``), ms, all on the
wall clock of this machine (the stamps, the node's ROS clock and DDS's source and reception
times are all system time)."""


NODE_SIDE = ("to_trigger", "node", "node_publish")
"""The pieces in the node's process (and DDS into it): the follower message leaving the replay
(its publish call returned) to the f_ext leaving the node (its DDS write). ``node_side_ms`` is
their sum: end to end without the measuring client's own send, receive thread and executor."""


def node_latency(model: Path, *, seconds: float = 10.0, rate_hz: float = 100.0,
                 publish: str = DEFAULT_PUBLISH_MODE.value) -> dict[str, Any]:
    """``aerodock node --publish publish`` fed by a 100 Hz replay (see the module docstring)."""
    from aerodock.node.replay import free_domain_id, replay, start_node, write_mapping

    with tempfile.TemporaryDirectory() as tmp:
        mapping = write_mapping(Path(tmp) / "mapping.toml", "/alpha/odom", "/bravo/odom")
        domain = free_domain_id()
        proc = start_node(model, mapping, domain, rate_hz=rate_hz, publish=publish,
                          duration_s=seconds + 60)
        pids = {"node": proc.pid, "replay": os.getpid()}
        marks: dict[str, dict[str, np.ndarray | None]] = {}

        def on_send(when: str) -> None:
            marks[when] = {name: scheduler_s(pid) for name, pid in pids.items()}

        try:
            rec = replay(orbit_log(seconds), domain, leader_topic="/alpha/odom",
                         follower_topic="/bravo/odom", on_send=on_send)
        finally:
            proc.kill()
            _, stderr = proc.communicate(timeout=30)
    if len(rec.outputs) < 2:
        last = (stderr.strip().splitlines() or ["nothing on stderr"])[-1]
        raise RuntimeError(f"aerodock node --publish {publish} published {len(rec.outputs)} "
                           f"outputs during the replay; its last words: {last}")
    return {"publish": publish, "rate_hz_set": rate_hz, **replay_figures(rec, publish),
            "cpu": {name: cpu_figures(marks["start"][name], marks["end"][name])
                    for name in pids},
            "seconds": seconds}


def scheduler_s(pid: int) -> np.ndarray | None:
    """``(on CPU s, waiting for a CPU s, times scheduled)`` summed over the threads of process
    ``pid`` (Linux ``/proc/PID/task/*/schedstat``); None where there is no such file."""
    total = np.zeros(3)
    try:
        tasks = list(Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return None
    for task in tasks:
        try:
            total += [float(x) for x in (task / "schedstat").read_text().split()[:3]]
        except (OSError, ValueError):  # a thread that ended meanwhile
            continue
    return total * (1e-9, 1e-9, 1.0)


def cpu_figures(start: np.ndarray | None, end: np.ndarray | None) -> dict[str, float] | None:
    """Over the replay, one process: CPU time, time runnable but waiting for a CPU (the run
    queue: the machine's load, not the process's work), and that wait per time scheduled."""
    if start is None or end is None:
        return None
    run_s, wait_s, slices = end - start
    return {"on_cpu_s": round(float(run_s), 3), "waiting_for_cpu_s": round(float(wait_s), 3),
            "wait_per_wakeup_ms": round(float(wait_s / max(slices, 1) * 1e3), 3)}


def replay_figures(rec: Any, publish: str) -> dict[str, Any]:
    """The figures of one replay (a :class:`aerodock.node.replay.ReplayRecord`) against a node
    publishing in mode ``publish``.

    Each output is paired with its diagnostics by stamp, and with the follower state it was
    computed from by the diagnostics' ``follower_stamp``: ``end_to_end_ms`` is that state's send
    stamp to the output's receipt, over the fresh outputs of the mode's own trigger (follower
    messages in ``on-follower``, ticks in ``timer``; watchdog outputs are counted, not timed).
    """
    outputs = {row[1]: row for row in rec.outputs}
    paired = [(outputs[s], v) for _, s, v in rec.diagnostics if s in outputs]
    sent = set(rec.send_times_s)
    t0, t1 = rec.send_times_s[0], rec.send_times_s[-1]
    # the outputs while the replay sends, and every answer to one of its follower messages
    # (the answer to the last one is stamped after it)
    during = [(row, v) for row, v in paired if t0 <= row[1] <= t1 or (
        v["trigger"] == TRIGGER_FOLLOWER and _stamp_or_nan(v["follower_stamp"]) in sent)]
    own = TRIGGER_FOLLOWER if publish == PublishMode.ON_FOLLOWER else TRIGGER_TIMER
    timed = [(row, v) for row, v in during if v["stale"] == "false" and v["trigger"] == own
             and _stamp_or_nan(v["follower_stamp"]) in sent]
    stamps = np.array(sorted(row[1] for row, _ in during))
    triggers = {t: sum(v["trigger"] == t for _, v in during)
                for t in (TRIGGER_FOLLOWER, TRIGGER_TIMER, TRIGGER_WATCHDOG)}
    answered = [float(v["follower_stamp"]) for _, v in during
                if v["trigger"] == TRIGGER_FOLLOWER]
    e2e, pieces = path_ms(rec, timed)
    tail = e2e >= np.percentile(e2e, 99) if e2e.size else np.zeros(0, bool)
    return {
        "rate_hz": round(float((len(stamps) - 1) / (stamps[-1] - stamps[0])), 2),
        "outputs": len(during),
        "outputs_by_trigger": triggers,
        "follower_messages": len(sent),
        "follower_messages_answered": len(set(answered) & sent),
        "follower_messages_answered_twice": len(answered) - len(set(answered)),
        "stale_fraction": round(1 - sum(v["stale"] == "false" for _, v in during)
                                / max(len(during), 1), 4),
        "node_ms": _stats([float(v["latency_ms"]) for _, v in timed]),
        "predictor_in_node_ms": _stats([float(v["compute_ms"]) for _, v in timed], 4),
        "end_to_end_ms": _stats(e2e),
        "state_to_prediction_ms": _stats(state_to_prediction_ms(rec, paired)),
        "node_side_ms": _stats(sum(pieces[k] for k in NODE_SIDE) if e2e.size else e2e),
        "path_ms": {name: _stats(values) for name, values in pieces.items()},
        "path_ms_in_the_worst_1pct": {name: (round(float(np.nanmean(values[tail])), 3)
                                             if np.isfinite(values[tail]).any() else None)
                                      for name, values in pieces.items()},
    }


def state_to_prediction_ms(rec: Any, paired: list[tuple[Any, dict[str, str]]]) -> np.ndarray:
    """Per follower state sent: until a fresh output computed from it *or a newer one* was
    received, ms (NaN: none ever was).

    ``end_to_end_ms`` times each output from its own state; this times each state until the
    consumer holds a prediction at least as new, whatever the trigger: a state the node skipped
    (superseded while it waited for a CPU, or between two ticks) counts, with the wait until a
    newer one was answered. The figure that cannot improve by answering fewer states.
    """
    rows = np.array([(_stamp_or_nan(v["follower_stamp"]), row[0]) for row, v in paired
                     if v["stale"] == "false"], dtype=float).reshape(-1, 2)
    rows = rows[np.isfinite(rows[:, 0])]
    sent = np.asarray(rec.send_times_s, dtype=float)
    if not rows.size:
        return np.full(sent.shape, np.nan)
    rows = rows[np.argsort(rows[:, 0])]
    earliest = np.minimum.accumulate(rows[::-1, 1])[::-1]  # over outputs from this state on
    first = np.searchsorted(rows[:, 0], sent)  # the first output from a state >= each sent one
    covered = first < len(rows)
    out = np.full(sent.shape, np.nan)
    out[covered] = (earliest[first[covered]] - sent[covered]) * 1e3
    return out


def _stamp_or_nan(text: str) -> float:
    """A diagnostics stamp (``repr`` of a float, ``"None"`` before any state) as a number."""
    return float("nan") if text == "None" else float(text)


def path_ms(rec: Any, timed: list[tuple[Any, dict[str, str]]]
            ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """End to end and its :data:`PATH_SEGMENTS`, ms, one value per timed output (NaN: unknown)."""
    rows = []
    for row, v in timed:
        received, stamp = row[0], row[1]
        follower = float(v["follower_stamp"])
        published = rec.published_s.get(follower, np.nan)
        node_s = float(v["latency_ms"]) * 1e-3
        trigger_s = stamp - node_s
        dds_source, dds_received = rec.output_dds_s.get(stamp, (np.nan, np.nan))
        rows.append((received - follower, published - follower, trigger_s - published,
                     float(v["queue_ms"]) * 1e-3, node_s, dds_source - stamp,
                     dds_received - dds_source, received - dds_received))
    values = np.asarray(rows, dtype=float).reshape(-1, 1 + len(PATH_SEGMENTS)) * 1e3
    return values[:, 0], dict(zip(PATH_SEGMENTS, values[:, 1:].T, strict=True))


def run(model: Path | None = None, *, seconds: float = 10.0, rate_hz: float = 100.0,
        node: bool = True, publish: tuple[str, ...] = (DEFAULT_PUBLISH_MODE.value,)
        ) -> dict[str, Any]:
    """Both measurements as one JSON-ready document (the node once per ``publish`` mode)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = model or random_model(Path(tmp) / "model")
        doc: dict[str, Any] = {
            "machine": {"cpu": platform.processor() or platform.machine(),
                        "cores": os.cpu_count(), "python": platform.python_version(),
                        "load_average_1min_before": round(os.getloadavg()[0], 2)},
            "model": str(model) if model else "random weights, so2, layers 6-64-64-2",
            "predictor": predictor_latency(path),
        }
        if node:
            doc["node"] = {}
            for mode in publish:
                doc["node"][mode] = node_latency(path, seconds=seconds, rate_hz=rate_hz,
                                                 publish=mode)
                doc["node"][mode]["load_average_1min_after"] = round(os.getloadavg()[0], 2)
    return doc


def main(argv: list[str] | None = None) -> None:
    """``python -m aerodock.bench.node [--model DIR] [--seconds S] [--rate HZ] [--publish MODE]
    [--json]``."""
    parser = argparse.ArgumentParser(prog="python -m aerodock.bench.node",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", type=Path, default=None, help="model directory")
    parser.add_argument("--seconds", type=float, default=10.0, help="replay length, s")
    parser.add_argument("--rate", type=float, default=100.0, help="node rate, Hz")
    parser.add_argument("--publish", default=DEFAULT_PUBLISH_MODE.value,
                        choices=[*(m.value for m in PublishMode), "both"],
                        help="the node's publish mode(s) to measure")
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args(argv)
    modes = (tuple(m.value for m in PublishMode) if args.publish == "both"
             else (args.publish,))
    doc = run(args.model, seconds=args.seconds, rate_hz=args.rate, publish=modes)
    if args.json:
        print(dumps_json(json_ready(doc)))  # a statistic of no sample is null
        return
    p = doc["predictor"]["per_call_us"]
    print(f"predictor ({doc['predictor']['kind']}): {p['median']} us per call (p99 {p['p99']})")
    for mode, n in doc["node"].items():
        e2e = n["end_to_end_ms"]
        print(f"node --publish {mode} ({n['rate_hz_set']:g} Hz): {n['rate_hz']} Hz out, "
              f"{n['outputs_by_trigger']}, node {n['node_ms']['median']} ms "
              f"(p99 {n['node_ms']['p99']}), end to end {e2e['median']} ms (p95 {e2e['p95']}, "
              f"p99 {e2e['p99']}), stale {100 * n['stale_fraction']:.1f}%")


if __name__ == "__main__":
    main()
