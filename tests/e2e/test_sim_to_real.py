"""The sim-to-real check on the shared real flights (small under small): in the suite at its
smallest (one simulated flight in each of three depth bands, 8 epochs); ``AERODOCK_E2E=quick``
(``make test-e2e``) at its quick size, checking that a model of real flights halves the zero
model's error."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from aerodock.config import load_config
from aerodock.experiments.sim_to_real import PAIRS, sim_to_real_study

WORLD = Path(__file__).resolve().parents[2] / "examples" / "crazyflie.toml"


QUICK = os.environ.get("AERODOCK_E2E", "smoke") == "quick"


@pytest.mark.slow
def test_sim_to_real(shared_data):
    data = shared_data("neural-swarm")
    out = sim_to_real_study({"small_under_small": load_config(WORLD)}, data, quick=QUICK,
                            smoke=not QUICK)
    r = out["pairs"]["small_under_small"]
    pair = PAIRS["small_under_small"]
    # judged on the held-out real flights only, both vehicles following
    assert {name.split("_")[-2] for name in r["real_test_flights"]} == set(pair.test_flights)
    assert not set(r["real_train_flights"]) & set(r["real_test_flights"])
    assert r["interaction_samples"] > 500
    assert r["sim"]["flights"] >= (2 if QUICK else 1) and r["sim"]["label_basis"] == "thrust"
    rmse = r["rmse_vertical_mps2"]
    assert all(math.isfinite(v) and v > 0 for v in rmse.values())
    if QUICK:  # a model of real flights of the pair cuts the zero model's error by half (~70 %)
        assert r["reduction_vs_zero"]["real"] > 0.5
    # conventions: in the real logs (converted to NED) and in the simulated flights alike the
    # leader's wake pushes the follower down, a positive vertical label
    means = r["mean_vertical_mps2"]
    assert means["label"] > 0 and means["sim"] > 0 and means["real"] > 0
    assert r["met"] == (r["reduction_vs_zero"]["sim"] >= out["target_reduction"])
