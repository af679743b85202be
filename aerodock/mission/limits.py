"""Size limits: what one command may ask for before it would take minutes and gigabytes.

A run beyond a limit is refused up front with a one-line error that states the limit, rather than
hanging or exhausting memory. Measured on a 2-core machine (``aerodock dock --trials 500``:
5.3 s, 157 MB; ``field probe``: about 50 us per sample).
"""

from __future__ import annotations

import math

from aerodock.config import Config

MAX_TRIALS = 10_000
"""Trials in one ``dock`` campaign (one batch); run several seeds for more."""
MAX_TRIAL_STEPS = 10_000_000
"""Trials x control steps of a campaign (per-step metrics take 24 bytes each: 240 MB)."""
MAX_LOGGED_TRIAL_STEPS = 500_000
"""Trials x control steps when every FlightLog is kept (about 600 bytes each: 300 MB)."""
MAX_PHYSICS_TRIAL_STEPS = 50_000_000
"""Trials x physics steps of a campaign (about 2 minutes on two cores)."""
MAX_PROBE_SAMPLES = 200_000
"""Turbulence samples of ``field probe`` (about 10 s; 400 s of flight at 500 Hz)."""


class LimitError(ValueError):
    """A request exceeds a size limit; the message states the limit."""


def campaign_duration_s(cfg: Config) -> float:
    """Upper bound on the flight time of one docking trial, s (settled start, approach, hold,
    window, back-off)."""
    p, m = cfg.planner, cfg.mission
    from aerodock.mission.settle import CRUISE_BEFORE_S  # (settle imports the simulator)

    preroll_s = m.settle_s + m.leader_ramp_s + CRUISE_BEFORE_S  # a moving leader's, the longest
    return (preroll_s + max(p.horizon_hover_s, p.horizon_moving_s + p.hold_s) + m.dock_window_s
            + m.backoff_s)


def check_campaign_size(cfg: Config, trials: int, keep_logs: bool = False) -> None:
    """Refuse a campaign whose memory or time would exceed the limits above.

    Raises:
        LimitError: too many trials, or trials x steps beyond a limit (the message says which).
    """
    if trials > MAX_TRIALS:
        raise LimitError(f"--trials {trials} exceeds the limit of {MAX_TRIALS} per campaign; "
                         "run several campaigns with different --seed")
    duration_s = campaign_duration_s(cfg)
    control = trials * math.ceil(duration_s * cfg.sim.control_rate_hz)
    physics = trials * math.ceil(duration_s * cfg.sim.physics_rate_hz)
    limit = MAX_LOGGED_TRIAL_STEPS if keep_logs else MAX_TRIAL_STEPS
    what = "trials x control steps with --save-logs" if keep_logs else "trials x control steps"
    if control > limit:
        raise LimitError(f"{trials} trials of {duration_s:g} s at {cfg.sim.control_rate_hz:g} Hz "
                         f"are {control} {what}, over the limit of {limit}; use fewer trials "
                         "or shorter mission times")
    if physics > MAX_PHYSICS_TRIAL_STEPS:
        raise LimitError(f"{trials} trials of {duration_s:g} s at {cfg.sim.physics_rate_hz:g} Hz "
                         f"are {physics} trials x physics steps, over the limit of "
                         f"{MAX_PHYSICS_TRIAL_STEPS}; use fewer trials or a lower physics rate")


def check_probe_samples(samples: int) -> None:
    """Refuse a ``field probe`` beyond :data:`MAX_PROBE_SAMPLES` (or below 2)."""
    if not 2 <= samples <= MAX_PROBE_SAMPLES:
        raise LimitError(f"--samples must be between 2 and {MAX_PROBE_SAMPLES}, got {samples}")
