"""How fast a controller's bias observer answers a disturbance: its step response, measured on the
controller itself.

The observer's bandwidth is what the paper leaves unstated and what decides its baseline, so it
is measured the same way for every observer (the time-constant Kalman filter, Freyja's
estimator at any rate and noise setting): the controller holds a vehicle modelled as a double
integrator at the state-message rate; at ``step_at_s`` a constant downward disturbance
acceleration starts; the published estimate's rise is read off. The state message, the
controller's own rate, its state filter and its estimator are exactly those the configuration
flies (:class:`aerodock.control.controller.PositionController`); only the vehicle is ideal, so
the figure is the observer's and the position loop's, not the airframe's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.config import Config
from aerodock.control.controller import PositionController, Reference


@dataclass(frozen=True)
class StepResponse:
    """The bias estimate's answer to a disturbance step.

    Attributes:
        t_s: time since the step, s (one sample per state message).
        bias_down_mps2: the published vertical estimate over ``t_s``, m/s².
        final_mps2: the settled estimate (the mean of the last second), m/s².
        rise_63_s: time to 63 % of the settled estimate, s.
        rise_98_s: time to 98 % of it, s (``inf`` if never reached).
    """

    t_s: np.ndarray
    bias_down_mps2: np.ndarray
    final_mps2: float
    rise_63_s: float
    rise_98_s: float


def _first_crossing_s(t_s: np.ndarray, x: np.ndarray, level: float) -> float:
    above = np.flatnonzero(x >= level)
    return float(t_s[above[0]]) if above.size else float("inf")


def bias_step_response(cfg: Config, step_mps2: float = 1.0, step_at_s: float = 3.0,
                       seconds: float = 20.0) -> StepResponse:
    """The step response of the bias observer ``cfg`` flies (see the module docstring).

    Args:
        cfg: the configuration (``[control]``: estimator, rates, state filter).
        step_mps2: the disturbance, downward, m/s².
        step_at_s: when it starts after the observer is enabled, s (after any ramp-in).
        seconds: how long to follow it after the step, s (long enough to settle).
    """
    ctl = PositionController(cfg, 1, use_observer=True)
    if ctl.observer is None:
        raise ValueError("the configuration flies no bias observer")
    dt = ctl.dt_s
    zero = np.zeros((1, 3))
    ref = Reference(zero, zero, zero, np.zeros(1), np.zeros(1))
    p, v = zero.copy(), zero.copy()
    ctl.reset(p, v)
    steps_before = int(round(step_at_s / dt))
    steps = steps_before + int(round(seconds / dt))
    bias = np.empty(steps)
    for k in range(steps):
        out = ctl.step(p, v, zero, ref)
        a = out.applied_accel_mps2.copy()
        if k >= steps_before:
            a[0, 2] += step_mps2
        p = p + v * dt + 0.5 * a * dt * dt
        v = v + a * dt
        bias[k] = out.bias_mps2[0, 2]
    t_s = (np.arange(steps) - steps_before + 1) * dt
    t_s, bias = t_s[steps_before:], bias[steps_before:]
    final = float(np.mean(bias[t_s > seconds - 1.0]))
    return StepResponse(t_s, bias, final, _first_crossing_s(t_s, bias, 0.63 * final),
                        _first_crossing_s(t_s, bias, 0.98 * final))
