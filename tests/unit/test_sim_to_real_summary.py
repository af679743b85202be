"""The sim-to-real study's summaries (aerodock/experiments/sim_to_real.py): how the two vehicles'
velocities line up, and the mean over seeds with the issue's two targets."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.experiments.sim_to_real import mean_over_seeds, velocity_alignment


def _inputs(va: list[list[float]], vb: list[list[float]]) -> np.ndarray:
    n = len(va)
    x = np.zeros((n, 9))
    x[:, 3:5], x[:, 6:8] = va, vb
    return x


def test_velocity_alignment_counts_moving_pairs_and_their_directions():
    x = _inputs([[0.3, 0.0], [0.3, 0.0], [0.0, 0.3], [0.01, 0.0], [0.3, 0.0]],
                [[0.3, 0.0], [-0.2, 0.0], [0.3, 0.0], [0.3, 0.0], [0.0, 0.0]])
    out = velocity_alignment(x, np.ones(5, dtype=bool))
    assert out["both_moving"] == pytest.approx(3 / 5)  # the last two: one vehicle still
    assert out["median_cos"] == pytest.approx(0.0)  # alike, opposite, crossing
    assert out["opposite"] == pytest.approx(1 / 3)
    # the mask selects; nothing moving gives no direction at all
    still = velocity_alignment(x, np.array([False, False, False, True, True]))
    assert still == {"both_moving": 0.0, "median_cos": None, "opposite": None}


def _result(**pairs: tuple[float, float, float]) -> dict:
    return {"pairs": {key: {"reduction_vs_zero": dict(zip(("sim", "real", "field"), v,
                                                          strict=True))}
                      for key, v in pairs.items()}}


def test_mean_over_seeds_judges_the_mean_against_both_targets():
    results = [_result(a=(0.66, 0.72, 0.57), b=(0.48, 0.74, 0.69)),
               _result(a=(0.70, 0.72, 0.57), b=(0.56, 0.74, 0.69)),
               _result(a=(0.68, 0.72, 0.57))]
    out = mean_over_seeds(results)
    assert out["a"]["seeds"] == 3 and out["b"]["seeds"] == 2
    assert out["a"]["reduction_vs_zero"]["sim"] == pytest.approx(0.68)
    assert out["a"]["met"] and out["a"]["close_to_real"]  # 4 points short, above the field
    assert out["b"]["reduction_vs_zero"]["sim"] == pytest.approx(0.52)
    assert out["b"]["met"] and not out["b"]["close_to_real"]  # 22 points short
    # within 5 points but under the world's own mean wake: not close enough
    assert not mean_over_seeds([_result(c=(0.70, 0.74, 0.71))])["c"]["close_to_real"]
    with pytest.raises(ValueError, match="no results"):
        mean_over_seeds([])
