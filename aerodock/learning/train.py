"""Training: Adam on the mean squared error, a validation split, early stopping.

::

    trained = train_model("so2", ds, seed=0)
    trained.save("models/so2")           # weights.npz + model.json
    predictor = trained.predictor()      # NumPy runtime, same numbers

Validation (``split``, the same rule for every model kind). ``"flight"`` holds out whole flights
(no flight in both parts), so that the validation loss measures generalisation to a new flight
rather than to the turbulence of neighbouring samples; when there is a single flight, or when
whole flights cannot approach the requested fraction (two flights of equal length would hold out
half of the data), it falls back to ``"time-blocks"``: whole contiguous time blocks of 5 s (far
longer than the wake's ~0.1 s turbulence correlation) of every flight. ``"auto"`` (the default)
splits by flight only when there are at least :data:`MIN_FLIGHTS_FOR_FLIGHT_SPLIT` flights, and
otherwise by time blocks: with a few flights the held-out ones are one or two particular flights,
and a flight whose geometry no other flight covers takes that geometry out of training and turns
early stopping into a test of extrapolation. On the shared swap_ss logs (10 flights) the flight
split held out, for every seed, the only flight whose passes run north-south; a model in world
coordinates (``mlp``) had never seen such a pass, its validation loss rose from the second epoch
and early stopping kept an almost untrained network (best epoch 1-3 of 21). ``info["split"]``
(``TrainedModel.record.outcome.split``) records the split used. Features are computed once;
the loop then only runs the small MLP, so a 30 000-sample data set (5 minutes at 100 Hz)
trains in well under a minute on two CPU cores.

The per-epoch losses are kept (``TrainedModel.history``) and recorded, rounded, in
``info["history"]`` (so in ``model.json`` -> ``training.history``): the learning curves.

A ``so2-wrench`` model (:mod:`aerodock.learning.models`) learns the force and the torque labels
(``Dataset.y_torque``) together, on their standardised errors
(:func:`~aerodock.learning.models.standardised_wrench_loss`); its record adds the held-out torque
RMSE and, with simulated data, the RMSE against the true wake torque and that torque's RMS.

Randomness: ``seed`` fixes the split, the initial weights (``torch.manual_seed`` under a forked
RNG, so the caller's global torch RNG is untouched) and the mini-batch order (a NumPy Generator).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from aerodock.learning.dataset import Dataset
from aerodock.learning.features import (
    WAKE_SCALE_NAMES,
    check_wake_scales,
    feature_map,
    invariant_components,
)
from aerodock.learning.kinds import get_kind
from aerodock.learning.modelfile import save_model_dir
from aerodock.learning.models import (
    DEFAULT_ACTIVATION,
    DEFAULT_HIDDEN,
    build_model,
    standardised_wrench_loss,
)
from aerodock.learning.records import (
    FitRecord,
    Hyperparameters,
    TrainingOutcome,
    TrainingRecord,
)
from aerodock.learning.runtime import Predictor, ZeroPredictor
from aerodock.learning.splits import flight_split_ids, time_block_split_mask
from aerodock.learning.training_vehicles import normalise_vehicles

ProgressFn = Callable[[int, int, float, float | None], None]
"""``progress(epoch, max_epochs, train_loss, val_loss)``, called after every epoch."""


@dataclass
class TrainedModel:
    """A trained model with its training record.

    Attributes:
        kind: model kind.
        model: the torch module (eval mode).
        info: JSON-ready training summary, written to ``model.json`` (``record.to_json()``
            for a model :func:`train_model` trained).
        history: per-epoch ``train_loss`` and ``val_loss`` (MSE, m²/s⁴; for a wrench model the
            standardised loss, dimensionless).
        record: the typed training record (``None`` for a model not made by
            :func:`train_model`).
    """

    kind: str
    model: nn.Module
    info: dict[str, Any] = field(default_factory=dict)
    history: dict[str, list[float]] = field(default_factory=dict)
    record: TrainingRecord | None = None

    def save(self, path: str | Path) -> Path:
        """Write a model directory (``weights.npz`` + ``model.json``)."""
        self.model.eval()
        return save_model_dir(path, self.model.spec(), self.model.weights(), training=self.info)

    def predictor(self) -> Predictor:
        """The NumPy runtime for this model (no file round trip)."""
        self.model.eval()
        if not get_kind(self.kind).has_network:
            return ZeroPredictor(meta={"kind": self.kind, "training": self.info})
        data = self.info.get("data")
        vehicles = data.get("vehicles") if isinstance(data, dict) else None
        # the same document a saved model's file holds (its training vehicles included)
        return Predictor(self.model.spec(), self.model.weights(),
                         {"kind": self.kind, "training": self.info,
                          "vehicles": normalise_vehicles(vehicles)})

    @torch.no_grad()
    def predict(self, x: np.ndarray, leader_R: np.ndarray,
                wake_scales: np.ndarray | None = None) -> np.ndarray:
        """Torch prediction (n, 3), m/s², NED, as float64 NumPy (``wake_scales`` (n, k): the
        leader-aware kinds' third input, :func:`~aerodock.learning.features.check_wake_scales`)."""
        self.model.eval()
        xt = torch.as_tensor(np.asarray(x), dtype=torch.float32)
        rt = torch.as_tensor(np.asarray(leader_R), dtype=torch.float32)
        st = None if wake_scales is None else torch.as_tensor(
            np.array(check_wake_scales(wake_scales, xt.shape[0], self.kind)),
            dtype=torch.float32)
        return self.model(xt, rt, st).double().numpy()


SPLITS = ("auto", "flight", "time-blocks")
"""Validation split rules (see the module docstring)."""
MIN_FLIGHTS_FOR_FLIGHT_SPLIT = 20
"""Fewest flights ``split="auto"`` splits by flight (20 % of them: at least 4 held out)."""


# Largest |value| of a model input (m, m/s) or label (m/s²) training accepts: far beyond any
# flight, and small enough that float32 squares and sums stay finite.
MAX_ABS_INPUT = 1e6


def check_trainable(ds: Dataset, min_samples: int = 20, kind: str | None = None) -> None:
    """Refuse data no model can be trained on: too few samples, non-finite or absurd values,
    or (for a wrench ``kind``) samples without torque labels.

    Raises:
        ValueError: one line saying what is wrong with the data.
    """
    if ds.n < min_samples:
        raise ValueError(f"too few samples to train on ({ds.n} < {min_samples})")
    arrays = [("inputs x", ds.x), ("labels y", ds.y), ("leader_R", ds.leader_R)]
    record = None if kind is None else get_kind(kind)
    if record is not None and record.torque:
        arrays.append(("torque labels", ds.torque_labels()))
    for name, arr in arrays:
        arr = np.asarray(arr, dtype=float)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"degenerate data: {name} contain NaN or infinite values")
        if arr.size and np.max(np.abs(arr)) > MAX_ABS_INPUT:
            raise ValueError(f"degenerate data: {name} reach {np.max(np.abs(arr)):.3g}, beyond "
                             f"{MAX_ABS_INPUT:g} (not SI units?)")
    if record is not None and record.n_wake_scales:
        ds.wake_scales()  # raises DataError (a ValueError) naming a flight without vehicles
    rot = np.asarray(ds.leader_R, dtype=float)
    gram = np.einsum("nji,njk->nik", rot, rot)
    if rot.size and np.max(np.abs(gram - np.eye(3))) > 1e-2:
        raise ValueError("degenerate data: leader_R holds matrices that are not rotations")


def training_wake_scales(ds: Dataset, kind: str = "so2-leader") -> dict[str, Any]:
    """What a leader-aware model records of its training data's wake scales (the ones ``kind``
    reads): the median of each (:data:`~aerodock.learning.features.WAKE_SCALE_NAMES`, m/s and
    m), the default the runtime uses when it is given no leader (``default``), and each one's
    range (``min``, ``max``)."""
    k = get_kind(kind).n_wake_scales
    scales = ds.wake_scales()[:, :k]
    return {
        "names": list(WAKE_SCALE_NAMES[:k]),
        "default": [float(f"{v:.6g}") for v in np.median(scales, axis=0)],
        "min": [float(f"{v:.6g}") for v in scales.min(axis=0)],
        "max": [float(f"{v:.6g}") for v in scales.max(axis=0)],
    }


def _check_trained(model: nn.Module, train_mse: float) -> None:
    """Refuse a model whose training diverged (nothing is written then)."""
    finite = math.isfinite(train_mse) and all(
        bool(torch.all(torch.isfinite(t))) for t in model.state_dict().values()
        if torch.is_floating_point(t)
    )
    if not finite:
        raise ValueError("training diverged: the model has non-finite weights or loss "
                         "(degenerate data?); no model written")


def validation_split(
    ds: Dataset, val_fraction: float, rng: np.random.Generator, split: str = "auto"
) -> tuple[np.ndarray, np.ndarray, str]:
    """Train and validation indices and the split method used (``"flight"`` or
    ``"time-blocks"``).

    ``split="flight"``: by flight when whole flights can hold out between half and twice
    ``val_fraction`` (and at most half of the data), otherwise by contiguous time blocks within
    the flights. ``"time-blocks"``: always by time blocks. ``"auto"``: as ``"flight"`` when the
    data hold at least :data:`MIN_FLIGHTS_FOR_FLIGHT_SPLIT` flights, otherwise by time blocks.

    Raises:
        ValueError: unknown ``split``.
    """
    if split not in SPLITS:
        raise ValueError(f"unknown split {split!r} (expected one of {', '.join(SPLITS)})")
    if split == "auto":
        split = "flight" if ds.n_flights >= MIN_FLIGHTS_FOR_FLIGHT_SPLIT else "time-blocks"
    val_ids = flight_split_ids(ds, val_fraction, rng) if split == "flight" else None
    if val_ids is not None:
        in_val = np.isin(ds.flight_id, val_ids)
        frac = in_val.mean()
        if 0.5 * val_fraction <= frac <= min(2.0 * val_fraction, 0.5):
            return np.flatnonzero(~in_val), np.flatnonzero(in_val), "flight"
    in_val = time_block_split_mask(ds, val_fraction, rng)
    return np.flatnonzero(~in_val), np.flatnonzero(in_val), "time-blocks"


def learning_curve_record(history: dict[str, list[float]], wrench: bool = False
                          ) -> dict[str, Any]:
    """The per-epoch losses as a JSON-ready record (4 significant digits).

    Args:
        history: ``train_loss`` and ``val_loss`` lists (``val_loss`` empty without validation).
        wrench: the losses are a wrench model's standardised loss (dimensionless) rather than
            the force's MSE.

    Returns:
        ``{"loss": what the numbers are, "train_loss": [...], "val_loss": [...]}``, one entry
        per epoch (``val_loss`` empty without validation). ``train_loss`` is the mean over the
        epoch's mini-batches while the weights change; ``val_loss`` is computed after the epoch.
    """
    return {
        "loss": ("standardised MSE (dimensionless)" if wrench
                 else "MSE of the force, m^2/s^4 (sqrt: RMSE, m/s^2)"),
        "train_loss": [float(f"{v:.4g}") for v in history.get("train_loss", [])],
        "val_loss": [float(f"{v:.4g}") for v in history.get("val_loss", [])],
    }


def _features_tensors(
    kind: str, ds: Dataset, idx: np.ndarray
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor | None]:
    """Features, output map, force labels and (wrench kinds) torque labels of samples ``idx``."""
    record = get_kind(kind)
    scales = ds.wake_scales()[idx] if record.n_wake_scales else None
    z, out_map = feature_map(kind, ds.x[idx], ds.leader_R[idx], wake_scales=scales)
    torque = (torch.as_tensor(ds.torque_labels()[idx], dtype=torch.float32)
              if record.torque else None)
    return (torch.as_tensor(z, dtype=torch.float32),
            torch.as_tensor(np.ascontiguousarray(out_map), dtype=torch.float32),
            torch.as_tensor(ds.y[idx], dtype=torch.float32), torque)


LossFn = Callable[[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor | None], torch.Tensor]


def _loss_fn(model: nn.Module) -> LossFn:
    """``loss(z, out_map, y, torque)``: the force's MSE (m²/s⁴), or for a wrench model the
    standardised loss of force and torque."""
    if not getattr(model, "has_torque", False):
        return lambda z, m, y, tau: torch.mean((model.head(z, m) - y) ** 2)
    scales = model.output_scales()

    def wrench_loss(z, m, y, tau):
        force, torque = model.wrench_head(z, m)
        return standardised_wrench_loss(force, y, torque, tau, scales)

    return wrench_loss


@torch.no_grad()
def _fit_record(model: nn.Module, ds: Dataset, idx: np.ndarray, part: str,
                tensors: tuple) -> dict[str, float | None]:
    """``{part}_rmse_mps2`` of the force and, for a wrench model, ``{part}_rmse_torque_nm`` and
    (where the data hold the true wake torque) ``{part}_torque_vs_true_rmse_nm`` and
    ``{part}_true_torque_rms_nm`` (RMS of one component, over samples ``idx``)."""
    if not len(idx):
        return {f"{part}_rmse_mps2": None}
    z, out_map, y, tau = tensors
    force, torque = model.wrench_head(z, out_map)
    out: dict[str, float | None] = {
        f"{part}_rmse_mps2": math.sqrt(float(torch.mean((force - y) ** 2)))}
    if torque is None:
        return out
    out[f"{part}_rmse_torque_nm"] = math.sqrt(float(torch.mean((torque - tau) ** 2)))
    true = None if ds.y_torque_true is None else ds.y_torque_true[idx]
    if true is not None and np.isfinite(true).all(axis=1).any():
        ok = np.isfinite(true).all(axis=1)
        pred = torque.double().numpy()[ok]
        out[f"{part}_torque_vs_true_rmse_nm"] = float(np.sqrt(np.mean((pred - true[ok]) ** 2)))
        out[f"{part}_true_torque_rms_nm"] = float(np.sqrt(np.mean(true[ok] ** 2)))
    return out


def train_model(
    kind: str,
    train: Dataset,
    *,
    val_fraction: float = 0.2,
    seed: int = 0,
    max_epochs: int = 200,
    patience: int = 20,
    spectral_norm: bool = False,
    hidden: Sequence[int] = DEFAULT_HIDDEN,
    activation: str = DEFAULT_ACTIVATION,
    lr: float = 3e-3,
    batch_size: int = 256,
    weight_decay: float = 0.0,
    split: str = "auto",
    max_time_s: float | None = None,
    num_threads: int | None = 1,
    progress: ProgressFn | None = None,
) -> TrainedModel:
    """Train a downwash model on ``train``.

    Args:
        kind: ``"so2"``, ``"so2-ext"``, ``"so2-wrench"`` (needs torque labels), ``"mlp"`` or
            ``"zero"`` (nothing to train).
        train: the data (a validation part is split off it).
        val_fraction: fraction held out for validation and early stopping; 0 trains for
            ``max_epochs`` without validation.
        seed: fixes split, initial weights and batch order.
        max_epochs: epoch limit.
        patience: epochs without validation improvement before stopping (best weights kept).
        spectral_norm: spectrally normalise the linear layers.
        hidden: hidden layer widths.
        activation: ``"tanh"`` or ``"silu"``.
        lr: Adam learning rate (halved when the validation loss plateaus).
        batch_size: mini-batch size.
        weight_decay: Adam weight decay.
        split: validation split rule, ``"auto"``, ``"flight"`` or ``"time-blocks"`` (see
            :func:`validation_split`; ``"flight"`` was the only rule before ``"auto"``).
        max_time_s: wall-clock limit on the epoch loop (None: none).
        num_threads: torch intra-op threads during training (restored afterwards); None leaves
            the setting alone. The default, 1, is as fast as 2 for these small networks on a
            2-core CPU (about 90 ms per epoch of 24 000 samples) and cannot oversubscribe the
            CPU when other work runs beside it (measured: 2 threads under load spiked to 5x).
        progress: called after every epoch (see :data:`ProgressFn`).

    Returns:
        The trained model (best validation epoch) and its record.

    Raises:
        ValueError: unknown kind, bad options, too few samples, degenerate data
            (:func:`check_trainable`), or a training that diverged to non-finite weights.
    """
    kind_record = get_kind(kind)
    _check_options(val_fraction, max_epochs, patience, batch_size, split)
    check_trainable(train, kind=kind)
    wrench = kind_record.torque
    given = {
        "kind": kind, "seed": seed, "data": train.summary(), "spectral_norm": spectral_norm,
        "hyperparameters": Hyperparameters(
            hidden=list(hidden), activation=activation, lr=lr, batch_size=batch_size,
            weight_decay=weight_decay, max_epochs=max_epochs, patience=patience,
            val_fraction=val_fraction, split_rule=split, optimizer="Adam",
            loss=("standardised MSE: mean of force and torque MSE, each over its label "
                  "scale squared" if wrench else "MSE (m^2/s^4, world NED)")),
        "wake_scales": (training_wake_scales(train, kind) if kind_record.n_wake_scales
                        else None),
    }
    if not kind_record.has_network:
        untrained = TrainingRecord(**given, outcome=None, train_time_s=0.0)
        return TrainedModel(kind, build_model(kind), untrained.to_json(), {}, record=untrained)
    t_start = time.perf_counter()
    rng = np.random.default_rng(seed)
    if val_fraction > 0:
        tr_idx, va_idx, split_used = validation_split(train, val_fraction, rng, split)
    else:
        tr_idx, va_idx, split_used = np.arange(train.n), np.zeros(0, dtype=np.int64), "none"
    with _torch_threads(num_threads):
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            model = build_model(kind, hidden=hidden, activation=activation,
                                spectral_norm=spectral_norm)
        tr_tensors = _features_tensors(kind, train, tr_idx)
        _normalise(model, kind, train, tr_idx, tr_tensors)
        va_tensors = _features_tensors(kind, train, va_idx) if len(va_idx) else None
        loss_fn = _loss_fn(model)
        loop = _epoch_loop(model, loss_fn, tr_tensors, va_tensors, rng, _LoopSettings(
            max_epochs=max_epochs, patience=patience, lr=lr, batch_size=batch_size,
            weight_decay=weight_decay, max_time_s=max_time_s, t_start=t_start,
            progress=progress))
        outcome = _outcome(model, loss_fn, train, (tr_idx, tr_tensors), (va_idx, va_tensors),
                           split_used, loop)
    _check_trained(model, outcome.train_loss)
    trained = TrainingRecord(**given, outcome=outcome,
                             train_time_s=round(time.perf_counter() - t_start, 3),
                             torch_version=torch.__version__,
                             history=learning_curve_record(loop.history, wrench))
    return TrainedModel(kind, model, trained.to_json(), loop.history, record=trained)


def _check_options(val_fraction: float, max_epochs: int, patience: int, batch_size: int,
                   split: str) -> None:
    """Refuse training options out of range (ValueError, one line)."""
    if not 0.0 <= val_fraction < 1.0:
        raise ValueError(f"val_fraction must be in [0, 1), got {val_fraction}")
    if max_epochs < 1 or patience < 1 or batch_size < 1:
        raise ValueError("max_epochs, patience and batch_size must be positive")
    if split not in SPLITS:
        raise ValueError(f"unknown split {split!r} (expected one of {', '.join(SPLITS)})")


@torch.no_grad()
def _outcome(model: nn.Module, loss_fn: LossFn, train: Dataset, tr: tuple, va: tuple,
             split_used: str, loop: _LoopResult) -> TrainingOutcome:
    """The trained model's losses and fit on its training part ``tr`` and validation part
    ``va`` (each ``(indices, tensors)``; no validation: no indices, tensors ``None``)."""
    (tr_idx, tr_tensors), (va_idx, va_tensors) = tr, va
    train_mse = float(loss_fn(*tr_tensors))
    val_mse = None if va_tensors is None else float(loss_fn(*va_tensors))
    fit = _fit_record(model, train, tr_idx, "train", tr_tensors)
    if va_tensors is not None:
        fit.update(_fit_record(model, train, va_idx, "val", va_tensors))
    else:
        fit["val_rmse_mps2"] = None
    return TrainingOutcome(
        split=split_used, n_train=int(len(tr_idx)), n_val=int(len(va_idx)),
        val_flights=(sorted({train.flight_names[k] for k in np.unique(train.flight_id[va_idx])})
                     if split_used == "flight" else []),
        epochs=len(loop.history["train_loss"]), best_epoch=int(loop.best_epoch),
        stopped=loop.stopped, train_loss=train_mse, val_loss=val_mse,
        fit=FitRecord.from_parts(fit))


@contextmanager
def _torch_threads(num_threads: int | None) -> Iterator[None]:
    """Torch's intra-op threads set to ``num_threads`` (None: left alone), restored after."""
    old_threads = torch.get_num_threads()
    if num_threads:
        torch.set_num_threads(num_threads)
    try:
        yield
    finally:
        if num_threads:
            torch.set_num_threads(old_threads)


def _normalise(model: nn.Module, kind: str, train: Dataset, idx: np.ndarray,
               tensors: tuple) -> None:
    """Set the model's input and output normalisation from the training samples ``idx``."""
    z_tr, _, _, tau_tr = tensors
    wake = train.wake_scales()[idx] if get_kind(kind).n_wake_scales else None
    model.set_normalisation(
        z_tr.double().numpy(),
        invariant_components(kind, train.x[idx], train.leader_R[idx], train.y[idx],
                             None if tau_tr is None else tau_tr.double().numpy(), wake),
    )


@dataclass(frozen=True)
class _LoopSettings:
    """The epoch loop's settings (see :func:`train_model`'s arguments)."""

    max_epochs: int
    patience: int
    lr: float
    batch_size: int
    weight_decay: float
    max_time_s: float | None
    t_start: float  # time.perf_counter() when training started (for max_time_s)
    progress: ProgressFn | None


@dataclass
class _LoopResult:
    """What the epoch loop did: per-epoch losses, the epoch kept and why it stopped."""

    history: dict[str, list[float]]
    best_epoch: int
    stopped: str


def _epoch_loop(model: nn.Module, loss_fn: LossFn, tr: tuple, va: tuple | None,
                rng: np.random.Generator, s: _LoopSettings) -> _LoopResult:
    """Adam over shuffled mini-batches of ``tr``, the learning rate halved on a validation
    plateau, early stopping on ``va``; the model is left in eval mode with its best weights
    (the last epoch's when it trained for ``max_epochs`` without validation)."""
    z_tr, m_tr, y_tr, tau_tr = tr
    opt = torch.optim.Adam(model.parameters(), lr=s.lr, weight_decay=s.weight_decay)
    sched = torch.optim.lr_scheduler.ReduceLROnPlateau(
        opt, factor=0.5, patience=max(3, s.patience // 3)
    )
    history: dict[str, list[float]] = {"train_loss": [], "val_loss": []}
    best_loss, best_epoch, best_state = math.inf, 0, copy.deepcopy(model.state_dict())
    stopped = "max_epochs"
    n_tr = len(y_tr)
    for epoch in range(1, s.max_epochs + 1):
        model.train()
        perm = torch.from_numpy(rng.permutation(n_tr))
        total = 0.0
        for start in range(0, n_tr, s.batch_size):
            b = perm[start:start + s.batch_size]
            loss = loss_fn(z_tr[b], m_tr[b], y_tr[b], None if tau_tr is None else tau_tr[b])
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(b)
        train_loss = total / n_tr
        model.eval()
        val_loss = None
        if va is not None:
            with torch.no_grad():
                val_loss = float(loss_fn(*va))
            sched.step(val_loss)
        history["train_loss"].append(train_loss)
        if val_loss is not None:
            history["val_loss"].append(val_loss)
        monitor = val_loss if val_loss is not None else train_loss
        if monitor < best_loss * (1.0 - 1e-4):
            best_loss, best_epoch = monitor, epoch
            best_state = copy.deepcopy(model.state_dict())
        if s.progress is not None:
            s.progress(epoch, s.max_epochs, train_loss, val_loss)
        if va is not None and epoch - best_epoch >= s.patience:
            stopped = "early stopping"
            break
        if s.max_time_s is not None and time.perf_counter() - s.t_start > s.max_time_s:
            stopped = "time limit"
            break
    if va is not None or stopped != "max_epochs":
        model.load_state_dict(best_state)
    else:
        best_epoch = len(history["train_loss"])
    model.eval()
    return _LoopResult(history, best_epoch, stopped)
