"""The node's input judgement under random message streams (issue 25: stale stamps).

Each vehicle's stream is a seeded random mix of good messages and the faults a real link shows:
stamps of zero, going backwards or frozen, a relay repeating a message, positions beyond the
plausible range, non-finite values. Every message goes through the node's own path
(:class:`aerodock.node.core.InputMonitor`, then :func:`aerodock.node.core.prediction_step`), and
the output must be the predictor's when both newest messages are good, and zero with the injected
fault named in the reason otherwise; never a NumPy warning.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
from fuzz_helpers import count, n_cases

from aerodock.bench.node import random_model
from aerodock.learning.runtime import Predictor
from aerodock.node.core import InputMonitor, VehicleState, prediction_step

FAULTS = ("zero", "backwards", "frozen", "repeat", "far", "nan", "inf")
# What the reason must contain for each fault (the stream generator is the oracle).
KEYWORD = {"zero": "stamp is zero", "backwards": "went backwards", "frozen": "stamp frozen",
           "repeat": "repeated message", "far": "beyond", "nan": "not finite",
           "inf": "not finite"}


def _good(rng: np.random.Generator, stamp_s: float, centre: np.ndarray) -> VehicleState:
    return VehicleState(centre + rng.normal(0, 0.1, 3), rng.normal(0, 0.3, 3), np.eye(3),
                        received_s=0.0, stamp_s=stamp_s)


def _message(rng: np.random.Generator, prev: VehicleState | None, newest_s: float,
             centre: np.ndarray) -> tuple[VehicleState, str | None, float]:
    """The next message of a stream: (state, the fault injected or None, newest stamp so far)."""
    good_stamp = newest_s + 0.01
    kind = None if prev is None or rng.random() < 0.6 else str(rng.choice(FAULTS))
    if kind is None:
        return _good(rng, good_stamp, centre), None, good_stamp
    assert prev is not None
    prev_stamp = prev.stamp_s or 0.0
    if kind == "zero" or (kind in ("backwards", "frozen") and prev_stamp == 0.0):
        # (a stamp derived from a zero stamp is zero: that is what is wrong with it)
        return _good(rng, 0.0, centre), "zero", newest_s
    if kind == "repeat" and prev_stamp == 0.0:
        return replace(prev), "zero", newest_s
    if kind == "backwards":
        return _good(rng, prev_stamp * rng.uniform(0.5, 0.999), centre), kind, newest_s
    if kind == "frozen":
        return _good(rng, prev_stamp, centre), kind, newest_s
    if kind == "repeat":
        return replace(prev), kind, newest_s
    state = _good(rng, good_stamp, centre)
    if kind == "far":
        p = state.p_m.copy()
        p[rng.integers(3)] = rng.choice([2e4, -1e300, 1e300])
        return replace(state, p_m=p), kind, good_stamp
    bad = np.nan if kind == "nan" else np.inf * rng.choice([-1.0, 1.0])
    if rng.random() < 0.5:
        p = state.p_m.copy()
        p[rng.integers(3)] = bad
        return replace(state, p_m=p), kind, good_stamp
    v = state.v_mps.copy()
    v[rng.integers(3)] = bad
    return replace(state, v_mps=v), kind, good_stamp


@pytest.mark.parametrize("seed", [0, 1])
def test_random_streams_are_judged_by_their_data(seed, tmp_path):
    rng = np.random.default_rng(seed)
    predictor = Predictor.load(random_model(tmp_path / "model"))
    centres = {"leader": np.array([0.0, 0.0, -2.0]), "follower": np.array([0.1, -0.1, -1.5])}
    monitors = {role: InputMonitor() for role in centres}
    newest = {role: None for role in centres}
    injected: dict[str, str | None] = {role: None for role in centres}
    newest_stamp = {role: 1.0 for role in centres}
    seen = set()
    for k in range(n_cases(300)):
        role = "leader" if rng.random() < 0.5 else "follower"
        state, fault, newest_stamp[role] = _message(rng, newest[role], newest_stamp[role],
                                                    centres[role])
        now = 10.0 + 0.005 * k
        state = replace(state, received_s=now)
        newest[role], injected[role] = state, fault
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            monitors[role].receive(state)
            out = prediction_step(predictor, newest["leader"], newest["follower"], now,
                                  max_age_s=1e3,
                                  faults={r: m.verdict for r, m in monitors.items()})
        count("node-stamps")
        if newest["leader"] is None or newest["follower"] is None:
            assert out.stale and "missing" in out.reason
            continue
        bad = {r: f for r, f in injected.items() if f is not None}
        seen |= set(bad.values())
        if not bad:
            assert not out.stale, (k, out.reason)
            assert np.all(np.isfinite(out.f_ext_mps2)) and np.any(out.f_ext_mps2 != 0)
            continue
        assert out.stale, (k, bad)
        np.testing.assert_array_equal(out.f_ext_mps2, np.zeros(3))
        for r, f in bad.items():
            assert f"{r}: " in out.reason and KEYWORD[f] in out.reason, (k, r, f, out.reason)
    assert seen == set(FAULTS)  # every fault class was exercised
