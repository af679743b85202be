"""A follower's rotor footprint (issue 39, item 6): a model trained on one follower carried to a
larger one by averaging its prediction over the ring the wider diagonal adds."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.learning.dataset import Dataset
from aerodock.learning.evaluate import evaluate
from aerodock.learning.footprint import RING_POINTS, footprint_average, footprint_radius_m
from aerodock.learning.train import train_model

SMALL_M, LARGE_M, THIRD_M = 0.092, 0.120, 0.20  # motor-to-motor diagonals
JET_SIGMA_M = 0.07  # the wake's Gaussian width, about the Crazyflies' at their separations


def point_wake(dp: np.ndarray) -> np.ndarray:
    """A downward Gaussian wake (n, 3), m/s², NED, at points ``dp`` below the leader."""
    r2 = dp[:, 0] ** 2 + dp[:, 1] ** 2
    out = np.zeros_like(dp)
    out[:, 2] = 3.0 * np.exp(-0.5 * r2 / JET_SIGMA_M**2)
    return out


def on_disks(dp: np.ndarray, diagonal_m: float, yaw_rad: np.ndarray | float = np.pi / 4
             ) -> np.ndarray:
    """What a quadrotor of ``diagonal_m`` feels: the point wake at its four rotors, averaged."""
    out = np.zeros_like(dp)
    for k in range(4):
        angle = yaw_rad + k * np.pi / 2
        moved = dp.copy()
        moved[:, 0] += diagonal_m / 2 * np.cos(angle)
        moved[:, 1] += diagonal_m / 2 * np.sin(angle)
        out += point_wake(moved)
    return out / 4


def test_the_extra_ring_is_the_difference_of_the_squared_arms():
    assert footprint_radius_m(SMALL_M, LARGE_M) == pytest.approx(
        np.sqrt(0.060**2 - 0.046**2))
    assert footprint_radius_m(SMALL_M, LARGE_M) == pytest.approx(0.0385, abs=1e-4)
    # no ring for a follower as large or smaller, nor for an unknown diagonal
    radii = footprint_radius_m(LARGE_M, np.array([LARGE_M, SMALL_M, np.nan, -1.0]))
    assert radii.tolist() == [0.0, 0.0, 0.0, 0.0]
    assert footprint_radius_m(None, LARGE_M) == 0.0
    assert footprint_radius_m(SMALL_M, None).shape == ()


def test_a_zero_ring_is_the_prediction_bit_for_bit():
    rng = np.random.default_rng(1)
    x = rng.normal(0, 0.1, (20, 9))
    rot = np.broadcast_to(np.eye(3), (20, 3, 3))

    def predict(xs, rs):
        return point_wake(xs[:, :3]) + xs[:, 3:6] * 0.1

    radius = np.where(np.arange(20) % 2 == 0, 0.0, 0.05)
    out = footprint_average(predict, x, rot, radius)
    np.testing.assert_array_equal(out[::2], predict(x, rot)[::2])
    assert not np.allclose(out[1::2], predict(x, rot)[1::2])


def test_the_small_followers_force_over_the_footprint_is_the_large_followers():
    """On the analytic wake: the small quadrotor's force, averaged over the extra ring, is the
    large one's, far closer than the small one's force itself (any yaw of the large one)."""
    rng = np.random.default_rng(2)
    n = 2000
    dp = np.column_stack([rng.uniform(-0.15, 0.15, (n, 2)), rng.uniform(0.2, 0.5, n)])
    x = np.concatenate([dp, np.zeros((n, 6))], axis=1)
    rot = np.broadcast_to(np.eye(3), (n, 3, 3))
    yaw = rng.uniform(0, np.pi / 2, n)
    for diagonal in (LARGE_M, THIRD_M):
        truth = on_disks(dp, diagonal, yaw)[:, 2]
        small = on_disks(dp, SMALL_M)[:, 2]
        carried = footprint_average(lambda xs, rs: on_disks(xs[:, :3], SMALL_M), x, rot,
                                    footprint_radius_m(SMALL_M, diagonal))[:, 2]
        before = np.sqrt(np.mean((small - truth) ** 2))
        after = np.sqrt(np.mean((carried - truth) ** 2))
        assert after < 0.25 * before, (diagonal, before, after)


def _flights(rng: np.random.Generator, diagonal_m: float, n_flights: int, n: int) -> Dataset:
    """Synthetic hover-and-cross flights of a follower of ``diagonal_m`` under a small leader:
    labels its four disks' wake plus noise; metadata as ``aerodock ingest`` writes it."""
    m = n_flights * n
    dp = np.column_stack([rng.uniform(-0.25, 0.25, (m, 2)), rng.uniform(0.2, 0.5, m)])
    x = np.concatenate([dp, np.zeros((m, 3)), rng.normal(0, 0.2, (m, 3))], axis=1)
    y = on_disks(dp, diagonal_m, rng.uniform(0, np.pi / 2, m)) + 0.05 * rng.normal(size=(m, 3))
    fid = np.repeat(np.arange(n_flights), n)
    flights = [{"name": f"d{diagonal_m:g}_{i}", "dt_s": 0.01, "leader_diagonal_m": SMALL_M,
                "follower_diagonal_m": diagonal_m} for i in range(n_flights)]
    return Dataset(x=x, leader_R=np.broadcast_to(np.eye(3), (m, 3, 3)).copy(), y=y,
                   flight_id=fid, t_s=np.tile(np.arange(n) * 0.01, n_flights),
                   meta={"flights": flights})


def test_trained_on_one_size_judged_on_a_third():
    """A model trained on the small follower's synthetic flights records its diagonal and,
    judged on a follower of a third size (0.2 m), cuts more of the error with its footprint."""
    rng = np.random.default_rng(3)
    train = _flights(rng, SMALL_M, 4, 1500)
    third = _flights(rng, THIRD_M, 1, 1500)
    predictor = train_model("so2", train, seed=0, max_epochs=60).predictor()
    assert predictor.trained_follower_diagonal_m == SMALL_M
    cut = {}
    for footprint in (False, True):
        ev = evaluate(predictor, third, footprint=footprint)["interaction"]
        cut[footprint] = 1 - ev["model"]["rmse_mps2"]["z"] / ev["zero"]["rmse_mps2"]["z"]
    assert cut[True] > cut[False] + 0.1, cut
    # the training size itself: the footprint changes nothing
    same = evaluate(predictor, train.subset(train.flight_id == 0), footprint=True)
    plain = evaluate(predictor, train.subset(train.flight_id == 0))
    assert same["all"]["model"] == plain["all"]["model"]
    assert RING_POINTS >= 4
    # the controller's call: the follower set from a config, over its footprint once larger
    from aerodock.downwash.base import BodyState
    from aerodock.learning.runtime import bodies_to_inputs

    k = 5
    leader = BodyState(np.zeros((k, 3)), np.zeros((k, 3)), np.broadcast_to(np.eye(3), (k, 3, 3)),
                       np.full(k, 0.32), np.full(k, 0.032))
    follower = BodyState(third.x[:k, :3], third.x[:k, 6:9], leader.R, np.full(k, 0.32),
                         np.full(k, 0.032))
    x, rot = bodies_to_inputs(leader, follower)
    as_trained = predictor.predict_bodies(leader, follower)
    predictor.set_follower_diagonal(SMALL_M)
    np.testing.assert_array_equal(predictor.predict_bodies(leader, follower), as_trained)
    predictor.set_follower_diagonal(THIRD_M)
    np.testing.assert_array_equal(predictor.predict_bodies(leader, follower),
                                  predictor.predict(x, rot, follower_diagonal_m=THIRD_M))
    assert not np.allclose(predictor.predict_bodies(leader, follower), as_trained)
    with pytest.raises(ValueError, match="diagonal"):
        predictor.set_follower_diagonal(float("nan"))
    with pytest.raises(ValueError, match="diagonal"):
        predictor.set_follower_diagonal(True)
    predictor.set_follower_diagonal(None)  # as trained again
    np.testing.assert_array_equal(predictor.predict_bodies(leader, follower), as_trained)
    # a campaign leaves it alone (a Crazyflie's model on the paper's vehicle is no small ring)
    from aerodock.config import load_config
    from aerodock.mission.params import fly_on_configured_rotors

    fly_on_configured_rotors(predictor, load_config())
    assert predictor.follower_diagonal_m is None
    # a footprint that cannot apply says so rather than scoring the plain model under its name
    bare = _flights(rng, SMALL_M, 1, 50)
    for flight in bare.meta["flights"]:
        del flight["follower_diagonal_m"]
    with pytest.raises(ValueError, match="follower_diagonal_m"):
        evaluate(predictor, bare, footprint=True)
    assert evaluate(predictor, third, footprint=True)["footprint_radius_m"] == pytest.approx(
        footprint_radius_m(SMALL_M, THIRD_M))
    with pytest.raises(ValueError, match="one per sample"):
        predictor.predict(x, rot, follower_diagonal_m=np.full(k + 1, THIRD_M))
