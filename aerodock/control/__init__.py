"""Follower/leader control: LQR on the linearised model, inversion map, bias observer."""

from aerodock.control.inversion import accel_to_attitude_thrust, attitude_thrust_to_accel
from aerodock.control.lqr import lin_model, lqr_command, lqr_gain
from aerodock.control.observer import BiasObserver

__all__ = [
    "BiasObserver",
    "accel_to_attitude_thrust",
    "attitude_thrust_to_accel",
    "lin_model",
    "lqr_command",
    "lqr_gain",
]
