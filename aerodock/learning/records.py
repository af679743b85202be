"""Typed records of a training run (:func:`aerodock.learning.train.train_model`).

:class:`TrainingRecord` is what training returns beside the network; its
:meth:`~aerodock.records.Record.to_json` is the ``training`` object of ``model.json`` (the
same keys, in the same order, as before these records), and the CLI reads its attributes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from aerodock.records import Json, Record


@dataclass(frozen=True)
class Hyperparameters(Record):
    """The training's settings."""

    hidden: list[int]
    activation: str
    lr: float
    batch_size: int
    weight_decay: float
    max_epochs: int
    patience: int
    val_fraction: float
    split_rule: str  # the rule asked for ("auto", "flight", "time-blocks")
    optimizer: str
    loss: str


@dataclass(frozen=True)
class FitRecord(Record):
    """How well the trained network fits its training and validation samples.

    The torque fields are a wrench model's (``None``, and absent from the JSON, otherwise); the
    ``*_vs_true_*`` and ``*_true_torque_rms_nm`` ones only where the data hold the true wake
    torque."""

    train_rmse_mps2: float | None
    train_rmse_torque_nm: float | None = None
    train_torque_vs_true_rmse_nm: float | None = None
    train_true_torque_rms_nm: float | None = None
    val_rmse_mps2: float | None = None
    val_rmse_torque_nm: float | None = None
    val_torque_vs_true_rmse_nm: float | None = None
    val_true_torque_rms_nm: float | None = None
    _OMIT_NONE: ClassVar[tuple[str, ...]] = (
        "train_rmse_torque_nm", "train_torque_vs_true_rmse_nm", "train_true_torque_rms_nm",
        "val_rmse_torque_nm", "val_torque_vs_true_rmse_nm", "val_true_torque_rms_nm")

    @classmethod
    def from_parts(cls, parts: dict[str, float | None]) -> FitRecord:
        """From the ``{part}_...`` figures of the training and validation parts."""
        return cls(**parts)


@dataclass(frozen=True)
class TrainingOutcome(Record):
    """What the epoch loop did: the split used, the epochs, the losses and the fit."""

    split: str  # "flight", "time-blocks" or "none" (no validation)
    n_train: int
    n_val: int
    val_flights: list[str]
    epochs: int
    best_epoch: int
    stopped: str  # "max_epochs", "early stopping" or "time limit"
    train_loss: float
    val_loss: float | None
    fit: FitRecord
    _SPLICE: ClassVar[tuple[str, ...]] = ("fit",)


@dataclass(frozen=True)
class TrainingRecord(Record):
    """A training run: its settings and data, and (a kind with a network) what training did.

    ``outcome``, ``torch_version`` and ``history`` are ``None`` for a kind with nothing to
    train (``zero``)."""

    kind: str
    seed: int
    data: Json  # Dataset.summary()
    spectral_norm: bool
    hyperparameters: Hyperparameters
    wake_scales: Json | None  # a leader-aware kind's training_wake_scales()
    outcome: TrainingOutcome | None
    train_time_s: float
    torch_version: str | None = None
    history: Json | None = None  # learning_curve_record(): the per-epoch losses
    _OMIT_NONE: ClassVar[tuple[str, ...]] = ("wake_scales", "outcome", "torch_version",
                                             "history")
    _SPLICE: ClassVar[tuple[str, ...]] = ("outcome",)
