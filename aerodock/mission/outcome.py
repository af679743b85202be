"""A campaign's outcome: per-trial results and metrics, their summary, Wilson intervals."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.mission.spec import AbortReason, MissionSpec

DEPRECATED_KEYS = {
    "err_down_int_0p5s_ms": "err_down_int_0p5s_m_s",
    "err_3d_int_0p5s_ms": "err_3d_int_0p5s_m_s",
}
"""Summary keys kept one more release under their old names (old: new): the integrals of the
tracking error are metre-seconds, which ``_ms`` misread as milliseconds."""


@dataclass
class CampaignResult:
    """Outcomes of one campaign: per-trial arrays, a summary, and optional traces / logs."""

    spec: MissionSpec
    success: np.ndarray
    slipped: np.ndarray
    missed: np.ndarray  # the gate closed without the bar (the truth)
    sensed_missed: np.ndarray  # the follower found itself not held after closing, backed off
    aborted: np.ndarray
    abort_reason: np.ndarray
    clearance_violation: np.ndarray
    rotor_strike: np.ndarray  # the bar or a cable went through a rotor disk (a crash)
    nan_state: np.ndarray  # a non-finite state or metric (a numerical failure)
    fault_hit: np.ndarray  # an injected fault struck the trial (every trial when none is set)
    ground_contact: np.ndarray
    post_dock_sink_m: np.ndarray  # the leader's altitude loss when a docked trial ends (nan: not)
    min_clearance_m: np.ndarray
    capture_time_s: np.ndarray
    err_down_m: np.ndarray  # mean |vertical tracking error| over the terminal window
    err_3d_m: np.ndarray
    err_down_int_ms: np.ndarray  # integral of |vertical error| over the final 0.5 s (paper's table)
    err_3d_int_ms: np.ndarray
    ff_down_int_mps: np.ndarray  # integral of the predicted vertical force over the final 0.5 s
    tilt_rms_deg: np.ndarray  # RMS tilt of the follower over the terminal window
    saturated_frac: np.ndarray  # fraction of the terminal window with the control saturated
    arrival_s: float
    trace: dict[str, np.ndarray] = field(default_factory=dict)
    logs: list[FlightLog] = field(default_factory=list)

    def take(self, index: np.ndarray) -> CampaignResult:
        """The campaign of the trials at batch positions ``index`` alone: outcomes, metrics,
        traces (their trial axis) and logs; per-trial trigger flags of the spec likewise."""
        index = np.asarray(index)
        n = self.success.size
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray) and value.ndim and value.shape[0] == n:
                value = value[index]
            out[f.name] = value
        out["trace"] = {k: (v[:, index] if v.ndim >= 2 else v) for k, v in self.trace.items()}
        out["logs"] = [self.logs[i] for i in index] if self.logs else []
        flags = {k: tuple(bool(b) for b in np.asarray(getattr(self.spec, k))[index])
                 for k in ("passive_trigger", "active_trigger")
                 if np.ndim(getattr(self.spec, k))}
        out["spec"] = replace(self.spec, trials=int(index.size), **flags)
        return CampaignResult(**out)

    def summary(self) -> dict[str, Any]:
        """Success rate with a Wilson 95 % interval and error statistics (JSON-ready)."""
        n = int(self.success.size)
        k = int(self.success.sum())
        lo, hi = wilson_interval(k, n)
        return {
            "trials": n,
            "docked": k,
            "success_rate": k / n,
            "success_wilson95": [lo, hi],
            "slip_throughs": int(self.slipped.sum()),
            "missed": int(self.missed.sum()),
            "sensed_misses": int(self.sensed_missed.sum()),
            "aborts": int(self.aborted.sum()),
            "abort_reasons": {r.name.lower(): int((self.abort_reason == r).sum())
                              for r in AbortReason if r != AbortReason.NONE},
            "clearance_violations": int(self.clearance_violation.sum()),
            "rotor_strikes": int(self.rotor_strike.sum()),
            "nan_trials": int(self.nan_state.sum()),
            "safe_aborts": int((self.aborted & ~self.clearance_violation & ~self.rotor_strike
                                & ~self.ground_contact & ~self.nan_state).sum()),
            "ground_contacts": int(self.ground_contact.sum()),
            "post_dock_sink_median_m": _nan_stat(np.nanmedian, self.post_dock_sink_m),
            "post_dock_sink_max_m": _nan_stat(np.nanmax, self.post_dock_sink_m),
            "min_clearance_m": float(np.min(self.min_clearance_m)),
            "terminal_err_down_median_m": float(np.median(self.err_down_m)),
            "terminal_err_down_mean_m": float(np.mean(self.err_down_m)),
            "terminal_err_3d_median_m": float(np.median(self.err_3d_m)),
            "terminal_err_3d_mean_m": float(np.mean(self.err_3d_m)),
            "err_down_int_0p5s_m_s": float(np.mean(self.err_down_int_ms)),  # m·s
            "err_3d_int_0p5s_m_s": float(np.mean(self.err_3d_int_ms)),
            # deprecated: the same figures under their old names (DEPRECATED_KEYS)
            "err_down_int_0p5s_ms": float(np.mean(self.err_down_int_ms)),
            "err_3d_int_0p5s_ms": float(np.mean(self.err_3d_int_ms)),
            "ff_down_int_0p5s_mps": float(np.mean(self.ff_down_int_mps)),
            "terminal_tilt_rms_deg_median": float(np.median(self.tilt_rms_deg)),
            "terminal_saturated_frac_mean": float(np.mean(self.saturated_frac)),
        }


def _nan_stat(stat: Callable[[np.ndarray], Any], values: np.ndarray) -> float | None:
    """``stat`` over the finite values, or None when there are none (JSON-ready)."""
    finite = values[np.isfinite(values)]
    return float(stat(finite)) if finite.size else None


def wilson_interval(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score interval ``(low, high)`` for a binomial proportion ``k / n`` (95 % by default).

    Always ``0 <= low <= k / n <= high <= 1``: the exact interval holds ``k / n``, and rounding
    (``high`` = 0.9999999999999999 at ``k = n`` = 4, 10, 14, ...) is clamped, so an error bar
    ``high - k / n`` is never negative. ``n = 0`` gives ``(0, 1)``.
    """
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    denom = 1 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    low = min(max(0.0, float(centre - half)), p)
    high = max(min(1.0, float(centre + half)), p)
    return (low, high)
