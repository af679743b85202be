"""Follower/leader control: LQR on the linearised model, inversion map, bias observer.

The names below load their modules on first use (the compiled kernels behind them import numba,
which a command that never flies a controller, or ``aerodock --help``, should not wait for)."""

from __future__ import annotations

import importlib
from typing import Any

_HOMES = {
    "BiasObserver": "aerodock.control.observer",
    "accel_to_attitude_thrust": "aerodock.control.inversion",
    "attitude_thrust_to_accel": "aerodock.control.inversion",
    "lin_model": "aerodock.control.lqr",
    "lqr_command": "aerodock.control.lqr",
    "lqr_gain": "aerodock.control.lqr",
}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module 'aerodock.control' has no attribute {name!r}")
    return getattr(importlib.import_module(_HOMES[name]), name)
