"""The label's noise floor (aerodock.experiments.label_floor) on synthetic samples of known
parts."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.experiments.label_floor import label_floor
from aerodock.learning.dataset import Dataset
from aerodock.learning.evaluate import evaluate


def _wake_z(dp: np.ndarray) -> np.ndarray:
    """A jet: 3 m/s² down on the axis, Gaussian of 0.08 m radius, nothing beyond 0.25 m."""
    r = np.hypot(dp[:, 0], dp[:, 1])
    return np.where((dp[:, 2] > 0) & (r < 0.25), 3.0 * np.exp(-(r / 0.08) ** 2), 0.0)


def _dataset(noise_sd: float, offset: float, n: int = 40_000, seed: int = 0) -> Dataset:
    """Followers below a level leader, 0-0.6 m off axis; label = wake + offset + noise (z)."""
    rng = np.random.default_rng(seed)
    r = 0.6 * np.sqrt(rng.uniform(size=n))
    phi = rng.uniform(0, 2 * np.pi, n)
    dp = np.stack([r * np.cos(phi), r * np.sin(phi), rng.uniform(0.2, 0.6, n)], axis=1)
    y = np.zeros((n, 3))
    y[:, 2] = _wake_z(dp) + offset + noise_sd * rng.normal(size=n)
    return Dataset(x=np.concatenate([dp, np.zeros((n, 6))], axis=1),
                   leader_R=np.broadcast_to(np.eye(3), (n, 3, 3)), y=y,
                   flight_id=np.zeros(n, dtype=np.int64), t_s=0.01 * np.arange(n))


class _WakeOnly:
    """Predicts the wake exactly and nothing else."""

    def predict(self, x: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
        out = np.zeros((len(x), 3))
        out[:, 2] = _wake_z(x[:, 0:3])
        return out


@pytest.mark.parametrize(("noise_sd", "offset"), [(0.15, 0.0), (0.15, -0.35), (0.5, 0.0)])
def test_ceiling_is_what_a_perfect_wake_model_reaches(noise_sd, offset):
    ds = _dataset(noise_sd, offset)
    floor = label_floor(ds)
    # the non-wake part's mean square and offset, as built
    assert floor.ms_out == pytest.approx(noise_sd ** 2 + offset ** 2, rel=0.05)
    assert floor.out_mean == pytest.approx(offset, abs=0.02)
    # a model that knows the wake exactly cuts the zero model's RMSE by the ceiling, not more
    ev = evaluate(_WakeOnly(), ds)["interaction"]
    reached = 1.0 - ev["model"]["rmse_mps2"]["z"] / ev["zero"]["rmse_mps2"]["z"]
    assert floor.ceiling == pytest.approx(reached, abs=0.015)
    assert np.sqrt(floor.ms_wake) == pytest.approx(ev["zero"]["rmse_mps2"]["z"], rel=1e-9)


def test_a_wrong_offset_lowers_the_ceiling_and_a_mask_selects_samples():
    clean, biased = label_floor(_dataset(0.15, 0.0)), label_floor(_dataset(0.15, -0.35))
    assert biased.ceiling < clean.ceiling - 0.1
    ds = _dataset(0.15, 0.0)
    half = np.arange(ds.n) % 2 == 0
    assert label_floor(ds, half).n_wake == pytest.approx(clean.n_wake / 2, rel=0.05)
    none = label_floor(ds, np.zeros(ds.n, dtype=bool))
    assert none.ceiling is None and none.n_wake == 0 and none.n_out == 0


def test_bad_arguments_are_refused():
    ds = _dataset(0.1, 0.0, n=100)
    with pytest.raises(ValueError, match="out_radius_m"):
        label_floor(ds, out_radius_m=0.1)
    with pytest.raises(ValueError, match="axis"):
        label_floor(ds, axis=3)
    with pytest.raises(ValueError, match="shape"):
        label_floor(ds, np.ones(5, dtype=bool))
