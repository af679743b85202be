"""Size limits: what one command may ask for before it would take minutes and gigabytes.

A run beyond a limit is refused up front with a one-line error that states the limit, rather than
hanging or exhausting memory. Measured on a 2-core machine (``aerodock dock --trials 500``:
5.3 s, 157 MB; ``field probe``: about 50 us per sample).
"""

from __future__ import annotations

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
MAX_FLIGHT_PHYSICS_STEPS = 100_000
"""Physics steps of one trial or flight (its simulated time x the physics rate). A batch's steps
run one after another whatever its size, about 0.5 ms each on two cores even for 2 trials, so
this is about a minute: 200 s of flight at the default 500 Hz (a default trial is 22.5 s)."""
MAX_SWEEP_CELLS = 10_000
"""Campaigns (points x seeds) of one ``sweep``."""
MAX_SWEEP_TRIALS = 200_000
"""Trials of one ``sweep`` in all: its tidy table holds one row (about 1 kB) per trial."""


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

    Every time of the mission counts (the settled start, the approach, the docking window and
    the back-off, :func:`campaign_duration_s`), at the configured rates: one trial's physics
    steps are limited (:data:`MAX_FLIGHT_PHYSICS_STEPS`) whatever the number of trials, and so
    are trials x control steps and trials x physics steps.

    Raises:
        LimitError: too many trials, a trial too long, or trials x steps beyond a limit (the
            message says which).
    """
    if trials > MAX_TRIALS:
        raise LimitError(f"--trials {trials} exceeds the limit of {MAX_TRIALS} per campaign; "
                         "run several campaigns with different --seed")
    duration_s = campaign_duration_s(cfg)
    check_flight_steps(cfg, duration_s, "trial")
    timing = cfg.timing
    control = trials * timing.control_periods(duration_s)
    physics = trials * timing.physics_steps(duration_s)
    limit = MAX_LOGGED_TRIAL_STEPS if keep_logs else MAX_TRIAL_STEPS
    what = "trials x control steps with --save-logs" if keep_logs else "trials x control steps"
    if control > limit:
        raise LimitError(f"{trials} trials of {duration_s:g} s at {timing.control_rate_hz:g} Hz "
                         f"are {control} {what}, over the limit of {limit}; use fewer trials "
                         "or shorter mission times")
    if physics > MAX_PHYSICS_TRIAL_STEPS:
        raise LimitError(f"{trials} trials of {duration_s:g} s at {timing.physics_rate_hz:g} Hz "
                         f"are {physics} trials x physics steps, over the limit of "
                         f"{MAX_PHYSICS_TRIAL_STEPS}; use fewer trials or a lower physics rate")


def check_probe_samples(samples: int) -> None:
    """Refuse a ``field probe`` beyond :data:`MAX_PROBE_SAMPLES` (or below 2)."""
    if not 2 <= samples <= MAX_PROBE_SAMPLES:
        raise LimitError(f"--samples must be between 2 and {MAX_PROBE_SAMPLES}, got {samples}")


def check_flight_steps(cfg: Config, duration_s: float, what: str = "trial") -> None:
    """Refuse one flight of ``duration_s`` simulated seconds beyond
    :data:`MAX_FLIGHT_PHYSICS_STEPS` at the configured physics rate.

    Raises:
        LimitError: the flight is too long; the message names the times and the rate to change.
    """
    timing = cfg.timing
    steps = timing.physics_steps(duration_s)
    if steps > MAX_FLIGHT_PHYSICS_STEPS:
        raise LimitError(
            f"one {what} of {duration_s:g} s at {timing.physics_rate_hz:g} Hz is {steps} physics "
            f"steps, over the limit of {MAX_FLIGHT_PHYSICS_STEPS}; shorten the mission's times "
            "(mission.settle_s, mission.dock_window_s, mission.backoff_s, the planner's horizons) "
            "or lower sim.physics_rate_hz")


def check_sweep_size(cells: int, trials: int) -> None:
    """Refuse a sweep of more than :data:`MAX_SWEEP_CELLS` campaigns or
    :data:`MAX_SWEEP_TRIALS` trials in all (``cells`` campaigns of ``trials`` each).

    Called with the counts before the cells are expanded, so a 3000 x 3000 grid is refused
    without building nine million cells.

    Raises:
        LimitError: the message states the limit.
    """
    if cells > MAX_SWEEP_CELLS:
        raise LimitError(f"the sweep has {cells} campaigns (points x seeds), over the limit of "
                         f"{MAX_SWEEP_CELLS}; split it into several sweeps")
    if cells * trials > MAX_SWEEP_TRIALS:
        raise LimitError(f"the sweep has {cells} campaigns x {trials} trials = {cells * trials} "
                         f"trials, over the limit of {MAX_SWEEP_TRIALS}; use fewer trials or "
                         "points, or split it into several sweeps")
