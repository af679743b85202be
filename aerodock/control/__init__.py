"""Follower/leader control: LQR on the linearised model, inversion map, bias observer.

The names below load their modules on first use (the compiled kernels behind them import numba,
which a command that never flies a controller, or ``aerodock --help``, should not wait for)."""

from __future__ import annotations

from aerodock.lazy import lazy_names

_HOMES = {
    "BiasObserver": "aerodock.control.observer",
    "accel_to_attitude_thrust": "aerodock.control.inversion",
    "attitude_thrust_to_accel": "aerodock.control.inversion",
    "lin_model": "aerodock.control.lqr",
    "lqr_command": "aerodock.control.lqr",
    "lqr_gain": "aerodock.control.lqr",
}

__all__ = sorted(_HOMES)

__getattr__ = lazy_names(__name__, _HOMES)
