"""Named worlds the tests fly where the default's choice is not what they test.

:data:`EARLIER_WORLD` is the paper-scale world before issue 39: the generic attitude loop with
chosen gains and inertia, and the wake fitted to the real flights' force alone. Every controller
docks there; in today's world (ArduCopter's default loops under the wake fitted with the logged
torque) the torque tilts the follower and most trials abort (docs/results/headline.md). Tests of
the mission's machinery (a trial that docks, a gate that closes, a batch equal to its trials)
fly it; tests of what today's world does fly the defaults.
"""

from __future__ import annotations

from typing import Any

EARLIER_WAKE = {"width0_ratio": 1.008, "spread_rate": 0.02309, "ingest_coeff": 0.4989,
                "ingest_exponent": 0.5573, "planar_ratio": -0.004125, "body_area_ratio": 0.2,
                "turb_vertical": 0.2478, "turb_lateral": 0.05196, "turb_length_ratio": 0.4736,
                "turb_time_ratio": 3.829}
"""The wake fitted to the force alone (examples/crazyflie_wake_fitted.toml before issue 39)."""

UNSETTLED_WAKE = {"width0_ratio": 0.7353, "spread_rate": 1.105e-05, "ingest_coeff": 0.8051,
                  "ingest_exponent": 0.561, "planar_ratio": 0.003171, "body_area_ratio": 2.158e-14,
                  "turb_vertical": 0.1845, "turb_lateral": 0.0484, "turb_length_ratio": 1.585,
                  "turb_time_ratio": 9.386}
"""The wake fitted to force and torque before the fit settled its least squares
(``wake_fit.settled_least_squares``): defaults.toml's and the Crazyflie worlds' until 7 December
2026, what the goldens written before then flew."""

EARLIER_WORLD: dict[str, Any] = {
    "autopilot": {"stack": "generic"},
    "vehicle": {"inertia_kgm2": [0.0023, 0.0023, 0.004]},
    "downwash": {"params": EARLIER_WAKE},
}


def merged(*overrides: dict[str, Any]) -> dict[str, Any]:
    """The overrides' sections merged key by key (later ones win)."""
    out: dict[str, Any] = {}
    for o in overrides:
        for section, keys in o.items():
            if isinstance(keys, dict) and isinstance(out.get(section), dict):
                out[section] = merged(out[section], keys)
            else:
                out[section] = keys
    return out
