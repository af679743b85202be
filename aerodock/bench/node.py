"""Latency of the learnt model next to a flight stack: the predictor alone, and ``aerodock node``
at its rate, end to end over ROS 2 on this machine (``python -m aerodock.bench.node``).

- ``predictor``: one ``Predictor.predict_one`` call (the node's per-tick work), µs: median and
  99th percentile over many calls after a warm-up.
- ``node``: ``aerodock node`` in its own process at ``rate_hz`` (100 Hz), fed by a replay of a
  flight (both vehicles' nav_msgs/Odometry at 100 Hz, localhost, a ROS domain of its own):
  ``rate_hz`` measured from the output stamps; ``tick_ms`` (tick start to publish, from the
  node's diagnostics); ``end_to_end_ms`` (state stamped and sent -> f_ext received: both
  transports plus the wait for the next tick, up to one period); the share of stale ticks.

The model is a given model directory, or random weights in the default architecture (same cost
as a trained one). The numbers in the README's "Deploy" section come from this module.
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
from aerodock.learning.modelfile import ModelSpec, save_model_dir


def random_model(path: Path, kind: str = "so2", seed: int = 3,
                 hidden: tuple[int, ...] = (64, 64)) -> Path:
    """A model directory with random weights (NumPy only), the default architecture."""
    rng = np.random.default_rng(seed)
    sizes = (N_FEATURES[kind], *hidden, N_OUTPUTS[kind])
    weights = [(rng.normal(0, 1 / np.sqrt(sizes[i]), (sizes[i + 1], sizes[i])),
                rng.normal(0, 0.1, sizes[i + 1])) for i in range(len(sizes) - 1)]
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


def _stats(values: np.ndarray, digits: int = 3) -> dict[str, float]:
    v = np.asarray(values, dtype=float)
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


def node_latency(model: Path, *, seconds: float = 10.0, rate_hz: float = 100.0) -> dict[str, Any]:
    """``aerodock node`` at ``rate_hz`` fed by a 100 Hz replay (see the module docstring)."""
    from aerodock.node.replay import free_domain_id, replay, start_node, write_mapping

    with tempfile.TemporaryDirectory() as tmp:
        mapping = write_mapping(Path(tmp) / "mapping.toml", "/alpha/odom", "/bravo/odom")
        domain = free_domain_id()
        proc = start_node(model, mapping, domain, rate_hz=rate_hz, duration_s=seconds + 60)
        try:
            rec = replay(orbit_log(seconds), domain, leader_topic="/alpha/odom",
                         follower_topic="/bravo/odom")
        finally:
            proc.kill()
            proc.communicate(timeout=30)
    outputs = {row[1]: row for row in rec.outputs}
    t0, t1 = rec.send_times_s[0], rec.send_times_s[-1]
    during = [(outputs[s], v) for _, s, v in rec.diagnostics
              if s in outputs and t0 <= s <= t1]
    fresh = [(row, v) for row, v in during if v["stale"] == "false"]
    stamps = np.array(sorted(row[1] for row, _ in during))
    return {
        "rate_hz_set": rate_hz,
        "rate_hz": round(float((len(stamps) - 1) / (stamps[-1] - stamps[0])), 2),
        "ticks": len(during),
        "stale_fraction": round(1 - len(fresh) / max(len(during), 1), 4),
        "tick_ms": _stats([float(v["latency_ms"]) for _, v in fresh]),
        "predictor_in_node_ms": _stats([float(v["compute_ms"]) for _, v in fresh], 4),
        "end_to_end_ms": _stats([(row[0] - float(v["follower_stamp"])) * 1e3
                                 for row, v in fresh]),
        "seconds": seconds,
    }


def run(model: Path | None = None, *, seconds: float = 10.0, rate_hz: float = 100.0,
        node: bool = True) -> dict[str, Any]:
    """Both measurements as one JSON-ready document."""
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
            doc["node"] = node_latency(path, seconds=seconds, rate_hz=rate_hz)
    return doc


def main(argv: list[str] | None = None) -> None:
    """``python -m aerodock.bench.node [--model DIR] [--seconds S] [--rate HZ] [--json]``."""
    parser = argparse.ArgumentParser(prog="python -m aerodock.bench.node",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", type=Path, default=None, help="model directory")
    parser.add_argument("--seconds", type=float, default=10.0, help="replay length, s")
    parser.add_argument("--rate", type=float, default=100.0, help="node rate, Hz")
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args(argv)
    doc = run(args.model, seconds=args.seconds, rate_hz=args.rate)
    if args.json:
        print(dumps_json(json_ready(doc)))  # a statistic of no sample is null
        return
    p, n = doc["predictor"]["per_call_us"], doc["node"]
    print(f"predictor ({doc['predictor']['kind']}): {p['median']} us per call (p99 {p['p99']})")
    print(f"node at {n['rate_hz_set']:g} Hz: measured {n['rate_hz']} Hz, tick "
          f"{n['tick_ms']['median']} ms (p99 {n['tick_ms']['p99']}), end to end "
          f"{n['end_to_end_ms']['median']} ms (p95 {n['end_to_end_ms']['p95']}, p99 "
          f"{n['end_to_end_ms']['p99']}), stale {100 * n['stale_fraction']:.1f}%")


if __name__ == "__main__":
    main()
