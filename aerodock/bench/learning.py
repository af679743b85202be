"""The learnt model: wall time of training the SO(2) model on 5 minutes of data, and the
predictor's time per call (NumPy runtime, ONNX Runtime, PyTorch)."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.bench.timing import Progress, failure_reason, figure, measure, quiet, unavailable


def synthetic_dataset(cfg: Any, minutes: float = 5.0, flights: int = 10, rate_hz: float = 100.0,
                      seed: int = 0) -> Any:
    """``minutes`` of flight data below a hovering leader, labelled with the default field.

    Followers wander smoothly 0.45-1.9 m below a slightly tilted, yawed leader (``flights``
    flights of equal length at ``rate_hz``); labels are the field's turbulent acceleration plus
    accelerometer-like noise. Enough to time training on the paper's amount of data.
    """
    from aerodock.downwash import BodyState, build_field
    from aerodock.geometry import euler_to_rotmat
    from aerodock.learning.dataset import Dataset

    rng = np.random.default_rng(seed)
    field = build_field(cfg)
    n_t = int(round(minutes * 60.0 * rate_hz / flights))
    dt = 1.0 / rate_hz
    t = np.arange(n_t) * dt

    def smooth(amp: float) -> np.ndarray:
        out = np.zeros((flights, n_t))
        for _ in range(3):
            period = rng.uniform(6.0, 30.0, (flights, 1))
            phase = rng.uniform(0.0, 2.0 * np.pi, (flights, 1))
            out += amp / 3.0 * np.sin(2.0 * np.pi * t / period + phase)
        return out

    sep = rng.uniform(0.45, 1.6, (flights, 1)) + smooth(0.3)
    dp = np.stack([smooth(0.4), smooth(0.4), sep], axis=-1)  # (flights, T, 3)
    fol_v = np.gradient(dp, dt, axis=1)
    lead_R = euler_to_rotmat(smooth(0.05), smooth(0.05),
                             rng.uniform(-np.pi, np.pi, (flights, 1)) + smooth(0.3))
    lead_v = np.zeros_like(dp)
    mass = np.full(flights, cfg.vehicle.mass_kg)
    thrust = mass * cfg.sim.gravity_mps2
    eye = np.repeat(np.eye(3)[None], flights, 0)
    field.reset(flights, rng)
    y = np.empty_like(dp)
    for k in range(n_t):
        lead = BodyState(np.zeros((flights, 3)), lead_v[:, k], lead_R[:, k], thrust, mass)
        fol = BodyState(dp[:, k], fol_v[:, k], eye, thrust, mass)
        y[:, k] = field.acceleration(lead, fol, dt)
    y += cfg.vehicle.accel_noise_mps2 * rng.standard_normal(y.shape)
    meta = {"flights": [{"name": f"bench-synthetic-{i}", "n_samples": n_t, "dt_s": dt}
                        for i in range(flights)], "sources": ["aerodock-bench-synthetic"]}
    return Dataset(x=np.concatenate([dp, lead_v, fol_v], axis=-1).reshape(-1, 9),
                   leader_R=lead_R.reshape(-1, 3, 3), y=y.reshape(-1, 3),
                   flight_id=np.repeat(np.arange(flights), n_t), t_s=np.tile(t, flights),
                   meta=meta)


def predictor_inputs(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """``n`` model inputs ``x`` (n, 9) and leader attitudes (n, 3, 3) around and below a leader."""
    from aerodock.geometry import euler_to_rotmat

    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform([-0.5, -0.5, 0.2], [0.5, 0.5, 1.8], (n, 3)),
                        rng.normal(0.0, 0.3, (n, 6))], axis=1)
    rot = euler_to_rotmat(rng.normal(0.0, 0.1, n), rng.normal(0.0, 0.1, n),
                          rng.uniform(-np.pi, np.pi, n))
    return x, rot


def _per_call(fn: Callable[[], Any], calls: int, repeats: int, scale: float, unit: str,
              note: str | None = None) -> dict[str, Any]:
    """Figure of ``fn``'s time per call (x ``scale``), ``calls`` calls per repetition."""

    def loop() -> None:
        for _ in range(calls):
            fn()

    times = measure(loop, repeats, warmup=1)
    return figure([t / calls * scale for t in times], unit, note)


QUICK_TRAIN_EPOCHS = 10
"""``bench --quick`` trains for at most this many epochs (a check that training runs and a
model to time; the full bench trains with the defaults, early stopping after up to 200)."""


def bench_training(cfg: Any, quick: bool = False,
                   progress: Progress = quiet) -> tuple[dict[str, Any], Any]:
    """Wall time to train the SO(2) model on 5 minutes of data; also returns the trained model."""
    try:
        from aerodock.learning.train import train_model
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"training not available ({failure_reason(err)})", "s"), None
    max_epochs = QUICK_TRAIN_EPOCHS if quick else 200  # (200: train_model's own default)
    progress("training: building 5 minutes of data")
    try:
        data = synthetic_dataset(cfg)
        progress("training: warm-up")
        train_model("so2", data, seed=0, max_epochs=2)
        trained: list[Any] = []

        def train() -> None:
            trained.append(train_model("so2", data, seed=0, max_epochs=max_epochs))

        progress("training: the SO(2) model on 5 minutes")
        times = measure(train, 1 if quick else 3, warmup=0)
    except Exception as err:  # noqa: BLE001 - optional part, never crash the benchmark
        return unavailable(f"training failed ({failure_reason(err)})", "s"), None
    info = trained[-1].info
    limit = (f"quick: at most {QUICK_TRAIN_EPOCHS} epochs, {info.get('epochs')} run" if quick
             else f"early stopping: {info.get('epochs')} epochs")
    note = (f"so2, {data.n} samples ({data.minutes:g} min at 100 Hz), defaults "
            f"({limit}), 1 torch thread")
    return figure(times, "s", note), trained[-1]


def _numpy_predictor(trained: Any) -> Any:
    """The NumPy runtime of ``trained``, or of an untrained default SO(2) network."""
    if trained is not None:
        return trained.predictor()
    from aerodock.learning.features import N_FEATURES, N_OUTPUTS
    from aerodock.learning.modelfile import ModelSpec
    from aerodock.learning.runtime import Predictor

    sizes = (N_FEATURES["so2"], 64, 64, N_OUTPUTS["so2"])
    rng = np.random.default_rng(0)
    weights = [(rng.normal(0, 0.3, (b, a)), rng.normal(0, 0.1, b))
               for a, b in zip(sizes[:-1], sizes[1:])]
    spec = ModelSpec(kind="so2", layer_sizes=sizes, in_mean=np.zeros(sizes[0]),
                     in_std=np.ones(sizes[0]), out_mean=np.zeros(sizes[-1]),
                     out_std=np.ones(sizes[-1]))
    return Predictor(spec, weights)


def bench_predictor(trained: Any, quick: bool = False,
                    progress: Progress = quiet) -> dict[str, Any]:
    """Single-call and per-sample batch-of-1024 times: NumPy runtime, ONNX Runtime, PyTorch."""
    repeats = 5 if quick else 7
    single_calls = 500 if quick else 2000
    batch_calls = 10 if quick else 30
    x1, r1 = predictor_inputs(1)
    xb, rb = predictor_inputs(1024)
    out: dict[str, Any] = {}
    untrained = " (untrained network: no trained model available)" if trained is None else ""

    progress("predictor: NumPy runtime")
    try:
        from aerodock.downwash import BodyState

        pred = _numpy_predictor(trained)
        x0, rot0 = x1[0], r1[0]
        mass = np.ones(1)
        lead = BodyState(np.zeros((1, 3)), x1[:, 3:6], r1, mass * 9.81, mass)
        fol = BodyState(x1[:, 0:3], x1[:, 6:9], r1, mass * 9.81, mass)
        out["numpy"] = {
            "single_call_us": _per_call(lambda: pred.predict_one(x0, rot0), single_calls,
                                        repeats, 1e6, "us",
                                        f"Predictor.predict_one{untrained}"),
            "controller_call_us": _per_call(lambda: pred.predict_bodies(lead, fol),
                                            single_calls, repeats, 1e6, "us",
                                            "Predictor.predict_bodies, batch of 1 (the "
                                            "controller's call)"),
            "batch1024_per_sample_us": _per_call(lambda: pred.predict(xb, rb), batch_calls,
                                                 repeats, 1e6 / 1024, "us",
                                                 "Predictor.predict on 1024 samples"),
        }
    except Exception as err:  # noqa: BLE001 - optional part
        out["numpy"] = unavailable(f"NumPy runtime not available ({failure_reason(err)})", "us")

    progress("predictor: ONNX Runtime")
    out["onnx"] = _bench_onnx(trained, x1, r1, xb, rb, repeats, single_calls, batch_calls)
    progress("predictor: PyTorch")
    out["torch"] = _bench_torch(trained, x1, r1, xb, rb, repeats, single_calls, batch_calls)
    return out


def _bench_onnx(trained: Any, x1: np.ndarray, r1: np.ndarray, xb: np.ndarray, rb: np.ndarray,
                repeats: int, single_calls: int, batch_calls: int) -> dict[str, Any]:
    if trained is None:
        return unavailable("no trained model to export (training not available)", "us")
    try:
        import onnxruntime as ort

        from aerodock.deploy.export import export_onnx
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"ONNX export/runtime not available ({failure_reason(err)})", "us")
    try:
        with tempfile.TemporaryDirectory(prefix="aerodock-bench-") as tmp:
            path = export_onnx(trained, Path(tmp) / "model.onnx")
            opts = ort.SessionOptions()
            opts.intra_op_num_threads = 1
            opts.inter_op_num_threads = 1
            sess = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
        one = {"x": x1.astype(np.float32), "leader_R": r1.astype(np.float32)}
        many = {"x": xb.astype(np.float32), "leader_R": rb.astype(np.float32)}
        return {
            "single_call_us": _per_call(lambda: sess.run(None, one), single_calls, repeats, 1e6,
                                        "us", "InferenceSession.run, float32, 1 thread"),
            "batch1024_per_sample_us": _per_call(lambda: sess.run(None, many), batch_calls,
                                                 repeats, 1e6 / 1024, "us"),
        }
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"ONNX benchmark failed ({failure_reason(err)})", "us")


def _bench_torch(trained: Any, x1: np.ndarray, r1: np.ndarray, xb: np.ndarray, rb: np.ndarray,
                 repeats: int, single_calls: int, batch_calls: int) -> dict[str, Any]:
    if trained is None:
        return unavailable("no trained model (training not available)", "us")
    try:
        import torch
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"PyTorch not available ({failure_reason(err)})", "us")
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        model = trained.model.eval()
        t1 = (torch.as_tensor(x1, dtype=torch.float32), torch.as_tensor(r1, dtype=torch.float32))
        tb = (torch.as_tensor(xb, dtype=torch.float32), torch.as_tensor(rb, dtype=torch.float32))

        def call(args: tuple[Any, Any]) -> Any:
            with torch.inference_mode():
                return model(*args)

        return {
            "single_call_us": _per_call(lambda: call(t1), single_calls, repeats, 1e6, "us",
                                        "module call under inference_mode, float32, 1 thread"),
            "batch1024_per_sample_us": _per_call(lambda: call(tb), batch_calls, repeats,
                                                 1e6 / 1024, "us"),
        }
    except Exception as err:  # noqa: BLE001 - optional part
        return unavailable(f"PyTorch benchmark failed ({failure_reason(err)})", "us")
    finally:
        torch.set_num_threads(threads)
