"""Feature maps and SO(2) equivariance of the so2, so2-ext, so2-leader and so2-pair models
(hypothesis)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from aerodock.geometry import euler_to_rotmat, rot_z, wrap_angle
from aerodock.learning.features import (
    EPS_POS_M,
    N_FEATURES,
    N_OUTPUTS,
    feature_map,
    feature_map_torch,
    phi_rad,
    so2_ext_features,
    so2_features,
)
from aerodock.learning.models import build_model
from aerodock.learning.runtime import Predictor

coord = st.floats(-2.0, 2.0, allow_nan=False)
vel = st.floats(-3.0, 3.0, allow_nan=False)
tilt = st.floats(-0.6, 0.6, allow_nan=False)
angle = st.floats(-np.pi, np.pi, allow_nan=False)
scene = st.tuples(
    st.lists(coord, min_size=3, max_size=3), st.lists(vel, min_size=6, max_size=6),
    tilt, tilt, angle,
)


def _random_model(kind: str, seed: int = 3) -> tuple[torch.nn.Module, Predictor]:
    """An untrained, randomly initialised model with non-trivial normalisation (float64)."""
    torch.manual_seed(seed)
    model = build_model(kind)
    rng = np.random.default_rng(seed)
    n_f = N_FEATURES[kind]
    n_out = N_OUTPUTS[kind]
    model.set_normalisation(rng.normal(0, 0.5, (50, n_f)), rng.normal(0, 2.0, (50, n_out)))
    model.eval()
    return model.double(), Predictor(model.spec(), model.weights())


MODELS = {kind: _random_model(kind) for kind in ("so2", "so2-ext", "so2-leader", "so2-pair", "mlp")}
# The leader-aware kinds' wake scales (a Crazyflie-like leader and follower): invariant inputs,
# the same before and after a rotation; so2-leader reads the first three, the other kinds none.
SCALES = np.array([[4.5, 0.045, 4.4, 0.05]])


def _scene(s) -> tuple[np.ndarray, np.ndarray]:
    dp, v, roll, pitch, yaw = s
    x = np.array([*dp, *v], dtype=float)[None, :]
    rot = euler_to_rotmat(np.array([roll]), np.array([pitch]), np.array([yaw]))
    return x, rot


def _about_axis(rot: np.ndarray, theta: float) -> np.ndarray:
    """World rotation by ``theta`` about the leader's axis a3: Q = R Rz(theta) R^T."""
    return rot[0] @ rot_z(np.array(theta)) @ rot[0].T


def _rotate_x(x: np.ndarray, q: np.ndarray) -> np.ndarray:
    return np.concatenate([x[:, 0:3] @ q.T, x[:, 3:6] @ q.T, x[:, 6:9] @ q.T], axis=1)


def _torch_predict(model: torch.nn.Module, x: np.ndarray, rot: np.ndarray) -> np.ndarray:
    with torch.no_grad():
        return model(torch.as_tensor(x), torch.as_tensor(rot), torch.as_tensor(SCALES)).numpy()


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "so2-leader", "so2-pair"])
@settings(max_examples=60, deadline=None)
@given(s=scene, theta=angle)
def test_rotating_whole_scene_about_leader_axis(kind, s, theta):
    """Positions, velocities and leader attitude rotated about a3: h fixed, prediction rotated."""
    x, rot = _scene(s)
    q = _about_axis(rot, theta)
    x2, rot2 = _rotate_x(x, q), (q @ rot[0])[None]
    z1, _ = feature_map(kind, x, rot, wake_scales=SCALES)
    z2, _ = feature_map(kind, x2, rot2, wake_scales=SCALES)
    np.testing.assert_allclose(z2, z1, atol=1e-9)
    model, pred = MODELS[kind]
    f1, f2 = pred.predict(x, rot, SCALES), pred.predict(x2, rot2, SCALES)
    np.testing.assert_allclose(f2, f1 @ q.T, atol=1e-9)
    np.testing.assert_allclose(_torch_predict(model, x2, rot2), f1 @ q.T, atol=1e-9)


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "so2-leader", "so2-pair"])
@settings(max_examples=60, deadline=None)
@given(s=scene, theta=angle)
def test_rotating_vectors_about_fixed_leader_axis(kind, s, theta):
    """The paper's SO(2) action: vectors rotated about a3, attitude fixed: h fixed, f rotated."""
    x, rot = _scene(s)
    q = _about_axis(rot, theta)
    x2 = _rotate_x(x, q)
    np.testing.assert_allclose(feature_map(kind, x2, rot, wake_scales=SCALES)[0],
                               feature_map(kind, x, rot, wake_scales=SCALES)[0],
                               atol=1e-9)
    _, pred = MODELS[kind]
    np.testing.assert_allclose(pred.predict(x2, rot, SCALES), pred.predict(x, rot, SCALES) @ q.T,
                               atol=1e-9)
    rho = np.hypot(*(rot[0].T @ x[0, :3])[:2])
    if rho > 1e-6:
        dphi = wrap_angle(phi_rad(x2, rot) - phi_rad(x, rot) - theta)
        assert abs(float(dphi[0])) < 1e-6


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "so2-leader", "so2-pair"])
@settings(max_examples=40, deadline=None)
@given(s=scene, theta=angle)
def test_leader_yaw_about_own_axis_changes_nothing(kind, s, theta):
    """Yawing the leader about its own axis (scene fixed) leaves h and the prediction unchanged."""
    x, rot = _scene(s)
    rot2 = rot @ rot_z(np.array(theta))
    np.testing.assert_allclose(feature_map(kind, x, rot2, wake_scales=SCALES)[0],
                               feature_map(kind, x, rot, wake_scales=SCALES)[0],
                               atol=1e-9)
    _, pred = MODELS[kind]
    np.testing.assert_allclose(pred.predict(x, rot2, SCALES), pred.predict(x, rot, SCALES),
                               atol=1e-9)


def test_mlp_baseline_is_not_equivariant():
    """Sanity check of the property tests: the plain MLP does change under the rotation."""
    x, rot = _scene(([0.2, 0.1, 0.6], [0.3, 0, 0, 0.1, -0.2, 0], 0.1, 0.0, 0.3))
    q = _about_axis(rot, 1.0)
    _, pred = MODELS["mlp"]
    diff = pred.predict(_rotate_x(x, q), rot) - pred.predict(x, rot) @ q.T
    assert np.abs(diff).max() > 1e-3


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "mlp"])
def test_degenerate_inputs_give_finite_outputs(kind):
    """Follower exactly on the leader's axis, zero velocities, all-zero input: finite."""
    rot = euler_to_rotmat(np.array([0.2, 0.0, 0.0]), np.array([-0.1, 0.0, 0.0]),
                          np.array([1.0, 0.0, 0.0]))
    x = np.zeros((3, 9))
    x[0, 0:3] = 0.5 * rot[0, :, 2]  # exactly below along a3, velocities zero
    x[1, 0:3] = [0.0, 0.0, 0.4]
    # x[2] is all zeros: dp = 0
    z, out_map = feature_map(kind, x, rot)
    assert np.all(np.isfinite(z)) and np.all(np.isfinite(out_map))
    model, pred = MODELS[kind]
    f = pred.predict(x, rot)
    assert np.all(np.isfinite(f))
    assert np.all(np.isfinite(_torch_predict(model, x, rot)))
    assert np.all(np.isfinite(pred.predict_one(x[0], rot[0])))
    if kind != "mlp":
        # on the axis the planar part vanishes: the force is along a3
        planar = f[0] - (f[0] @ rot[0, :, 2]) * rot[0, :, 2]
        np.testing.assert_allclose(planar, 0.0, atol=1e-12)
        assert z[0, 0] == 0.0  # the cosine is defined as 0 when proj(dp) = 0


def test_paper_feature_map_matches_the_equation():
    """Away from degenerate inputs, h equals Eq. featuremap computed directly."""
    rng = np.random.default_rng(0)
    n = 200
    rot = euler_to_rotmat(rng.normal(0, 0.2, n), rng.normal(0, 0.2, n), rng.uniform(-3, 3, n))
    x = rng.normal(0, 1.0, (n, 9))
    h, phi = so2_features(x, rot)
    a1, a2, a3 = rot[:, :, 0], rot[:, :, 1], rot[:, :, 2]

    def proj(w):
        return w - np.sum(w * a3, axis=1, keepdims=True) * a3

    dp, va, vb = x[:, 0:3], x[:, 3:6], x[:, 6:9]
    pd, pa, pb = proj(dp), proj(va), proj(vb)
    nd, na, nb = (np.linalg.norm(p, axis=1) for p in (pd, pa, pb))
    ok = (nd > 0.1) & (nb > 0.3)
    cos = np.sum(pd * pb, axis=1) / (nd * nb)
    expected = np.stack([cos, nd, nb, np.sum(dp * a3, 1), np.sum(vb * a3, 1), na], axis=1)
    np.testing.assert_allclose(h[:, 1:], expected[:, 1:], atol=1e-12)
    np.testing.assert_allclose(h[ok, 0], expected[ok, 0], atol=2e-3)
    np.testing.assert_allclose(phi, np.arctan2(np.sum(dp * a2, 1), np.sum(dp * a1, 1)),
                               atol=1e-12)
    ext = so2_ext_features(x, rot)
    sin = np.sum(np.cross(pd, pb) * a3, axis=1) / (nd * nb)
    np.testing.assert_allclose(ext[ok, 1], sin[ok], atol=2e-3)
    np.testing.assert_allclose(ext[ok, 0] ** 2 + ext[ok, 1] ** 2, 1.0, atol=5e-3)
    assert EPS_POS_M < 0.01


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "mlp"])
def test_numpy_and_torch_features_agree(kind):
    rng = np.random.default_rng(1)
    n = 100
    rot = euler_to_rotmat(rng.normal(0, 0.3, n), rng.normal(0, 0.3, n), rng.uniform(-3, 3, n))
    x = rng.normal(0, 1.0, (n, 9))
    x[:5, 0:2] = 0.0
    x[5:10, 6:9] = 0.0
    z, m = feature_map(kind, x, rot)
    zt, mt = feature_map_torch(kind, torch.as_tensor(x), torch.as_tensor(rot))
    np.testing.assert_allclose(zt.numpy(), z, atol=1e-12)
    np.testing.assert_allclose(mt.numpy(), m, atol=1e-12)
