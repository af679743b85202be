"""The one helper for a field's mean (aerodock.downwash.mean): exact where the field has
``mean_acceleration``, otherwise an estimate that never disturbs the simulated field."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from protocol_fields import MinimalField, NoWakeField, OutwardThrustAxisField

from aerodock.control.compensation import OraclePredictor
from aerodock.downwash import build_field
from aerodock.downwash.base import BodyState
from aerodock.downwash.mean import EstimatedMean, mean_acceleration_fn, mean_source
from aerodock.downwash.probe import probe_bodies

MASS, G = 0.7, 9.81


def _points():
    sep = np.array([0.2, 0.36, 0.5, 0.9, 1.4, 0.36])
    rad = np.array([0.0, 0.05, 0.15, 0.3, 0.1, 0.6])
    return probe_bodies(sep, rad, 0.4, MASS, G, azimuth_rad=0.7)


def _minimal_mean(follower: BodyState, field: MinimalField) -> np.ndarray:
    r = np.hypot(follower.p[:, 0], follower.p[:, 1])
    out = np.zeros_like(follower.p)
    out[:, 2] = field.accel_mps2 * np.exp(-((r / field.radius_m) ** 4))
    return out


def test_field_with_a_mean_is_used_as_is(cfg):
    jet = build_field(cfg)
    fn = mean_acceleration_fn(jet)
    assert fn == jet.mean_acceleration
    assert mean_source(fn) == "the field's mean_acceleration()"


def test_estimate_recovers_the_jet_mean(cfg):
    """Turbulence enters the jet linearly: antithetic samples average it out exactly."""
    jet = build_field(cfg)
    leader, follower = _points()
    est = EstimatedMean(jet, samples=16)
    assert np.allclose(est(leader, follower), jet.mean_acceleration(leader, follower),
                       rtol=1e-9, atol=1e-12)
    assert "estimated" in mean_source(est)


def test_estimate_recovers_a_minimal_plugin_mean():
    field = MinimalField()
    leader, follower = _points()
    est = mean_acceleration_fn(field)
    assert isinstance(est, EstimatedMean)
    assert np.allclose(est(leader, follower), _minimal_mean(follower, field), atol=1e-12)


def test_estimate_leaves_the_simulated_field_untouched(cfg):
    """The trial's turbulence stream is the same with or without estimates in between."""
    leader, follower = _points()
    used, twin = build_field(cfg), build_field(cfg)
    used.reset(follower.n, np.random.default_rng(8))
    twin.reset(follower.n, np.random.default_rng(8))
    est = EstimatedMean(used)
    for _ in range(3):
        est(leader, follower)
        assert np.array_equal(used.acceleration(leader, follower, 0.002),
                              twin.acceleration(leader, follower, 0.002))


class _SquaredNoiseField:
    """Turbulence entering non-linearly (mean of z² is 1): the estimate is approximate."""

    def reset(self, n, rng):
        self.rng = rng

    def acceleration(self, leader, follower, dt):
        z = self.rng.standard_normal(follower.p.shape)
        return follower.p + 0.3 * z * z


def test_estimate_of_one_point_does_not_depend_on_the_batch():
    leader, follower = _points()
    est = EstimatedMean(_SquaredNoiseField(), samples=400)
    batch = est(leader, follower)
    for i in range(follower.n):
        one = est(*(BodyState(*(a[i:i + 1] for a in (b.p, b.v, b.R, b.thrust_n, b.mass_kg)))
                    for b in (leader, follower)))
        assert np.array_equal(one[0], batch[i])
    assert np.array_equal(est(leader, follower), batch)  # same on every call
    # and it is an estimate of the right thing: E[p + 0.3 z²] = p + 0.3, within 5 standard
    # errors (sd of 0.3 z² is 0.3 sqrt 2; antithetic pairs share z², so 200 independent draws)
    assert np.allclose(batch, follower.p + 0.3, atol=5 * 0.3 * np.sqrt(2) / np.sqrt(200))


def test_uncopyable_field_gets_one_clear_error_or_a_factory():
    class Uncopyable(MinimalField):
        def __init__(self):
            super().__init__()
            self.lock = threading.Lock()  # cannot be deep-copied

    with pytest.raises(ValueError, match="cannot be copied"):
        EstimatedMean(Uncopyable())
    leader, follower = _points()
    est = EstimatedMean(Uncopyable(), make_field=MinimalField)
    assert np.allclose(est(leader, follower), _minimal_mean(follower, MinimalField()), atol=1e-12)


@pytest.mark.parametrize("field", [MinimalField(), NoWakeField(), OutwardThrustAxisField()],
                         ids=lambda f: type(f).__name__)
def test_oracle_works_with_every_field(field):
    leader, follower = _points()
    oracle = OraclePredictor(field)
    pred = oracle.predict_bodies(leader, follower)
    assert pred.shape == (follower.n, 3) and np.all(np.isfinite(pred))
    if isinstance(field, MinimalField):
        assert np.allclose(pred, _minimal_mean(follower, field), atol=1e-12)
    elif isinstance(field, NoWakeField):
        assert np.array_equal(pred, np.zeros_like(pred))
    else:
        assert np.array_equal(pred, field.mean_acceleration(leader, follower))
