"""The jet's one call per physics step (``RoundJetField.wake_step``, the world's way) gives the
numbers, the random draws and the turbulence of its three calls in turn (``wrench``, then
``body_force_n``, then ``bar_force_n``), to the bit; a field without it (a plug-in, or a
subclass of the jet that replaces one of the three) is still called the three ways; and the
world flies the same numbers either way."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from jets import default_jet

from aerodock.downwash.at_centre import RoundJetAtCentre
from aerodock.downwash.base import BodyState
from aerodock.downwash.jet import RoundJetField
from aerodock.downwash.wrench import wake_step
from aerodock.geometry import rpy_to_rotmat
from aerodock.rng import TrialRNG, standard_normal_t

DT_S = 0.002
BAR_AREA_M2 = 0.0015
# The jet's variants of test_compiled_step: the default, the two ingest laws' special cases (one
# with a torque gain), no planar part and no gusts.
CASES = ({}, {"ingest_exponent": 1.0}, {"ingest_exponent": 2.0, "disk_torque_gain": 3.0},
         {"planar_ratio": 0.0, "turb_lateral": 0.0})


def _bits(a: np.ndarray) -> bytes:
    """An array's shape and bytes: equal only if every number is (-0.0 and NaNs included)."""
    a = np.ascontiguousarray(a, dtype=float)
    return repr(a.shape).encode() + a.tobytes()


def _states(rng: np.random.Generator, n: int, step: int):
    """Random leader and follower states (some followers above the leader's rotors: the wake
    fades there), the bar's position, velocity and axis."""
    lp = rng.normal(0, 0.1, (n, 3)) + [0, 0, -2]
    lead = BodyState(lp, rng.normal(0, 0.3, (n, 3)), rpy_to_rotmat(rng.normal(0, 0.1, (n, 3))),
                     np.abs(rng.normal(7, 1, n)), np.full(n, 0.7))
    fp = lp + rng.normal(0, 0.15, (n, 3)) + [0, 0, 0.4 if step % 3 else -0.1]
    fol = BodyState(fp, rng.normal(0, 0.3, (n, 3)), rpy_to_rotmat(rng.normal(0, 0.2, (n, 3))),
                    np.full(n, 7.0), np.full(n, 0.7))
    yaw = rng.uniform(-np.pi, np.pi, n)
    bar_axis_t = np.stack([np.cos(yaw), np.sin(yaw), np.zeros(n)])  # as the world's frame
    return lead, fol, lp + rng.normal(0, 0.05, (n, 3)) + [0, 0, 0.3], \
        rng.normal(0, 0.1, (n, 3)), bar_axis_t.T


def _pair(kwargs: dict, n_reset: int, trial_rng: bool) -> tuple[RoundJetField, RoundJetField,
                                                                 object, object]:
    """Two equal jets, each reset with its own copy of one random source."""
    rng_a = TrialRNG(7, n_reset) if trial_rng else np.random.default_rng(7)
    rng_b = copy.deepcopy(rng_a)
    a, b = default_jet(**kwargs), default_jet(**kwargs)
    a.reset(n_reset, rng_a)
    b.reset(n_reset, rng_b)
    return a, b, rng_a, rng_b


@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("n", [1, 3, 17])
@pytest.mark.parametrize("with_axis", [True, False])
@pytest.mark.parametrize("trial_rng", [True, False])
def test_one_call_gives_the_three_calls_numbers_and_draws(case, n, with_axis, trial_rng):
    """Six steps (the offsets as the world passes them, read-only), then the same random
    source must be where the three calls left it."""
    a, b, rng_a, rng_b = _pair(CASES[case], n, trial_rng)
    offsets = a.rotor_offsets_body_m
    states = np.random.default_rng(100 + case)
    for step in range(6):
        lead, fol, bar_p, bar_v, axis = _states(states, n, step)
        axis = axis if with_axis else None
        force, torque = a.wrench(lead, fol, offsets, DT_S)
        body = a.body_force_n(lead, fol)
        bar = a.bar_force_n(lead, bar_p, bar_v, BAR_AREA_M2, DT_S, axis)
        one = b.wake_step(lead, fol, offsets, bar_p, bar_v, BAR_AREA_M2, DT_S, axis)
        for name, want, got in zip(("force", "torque", "body", "bar"), (force, torque, body, bar),
                                   one, strict=True):
            assert _bits(got) == _bits(want), f"step {step}: {name} differs"
        # the same step's body force, read again, as after wrench
        assert _bits(b.body_force_n(lead, fol)) == _bits(body)
        assert _bits(b._processes) == _bits(a._processes)
        assert _bits(b._bar_noise) == _bits(a._bar_noise)
        assert b._last_dt == a._last_dt
    # the random source drew as many numbers, in the same order
    assert _bits(standard_normal_t(rng_b, n, 5)) == _bits(standard_normal_t(rng_a, n, 5))


@pytest.mark.parametrize("trial_rng", [True, False])
def test_one_call_draws_a_new_batchs_turbulence_in_the_three_calls_order(trial_rng):
    """A field reset for 2 trials and asked about 3 draws its turbulence's start afresh: the
    follower's, its step's draws, then the bar's start and its step's draws (a random source
    that is not per trial: the order of the draws is the numbers)."""
    a, b, rng_a, rng_b = _pair({}, 2, trial_rng)
    if trial_rng:  # a per-trial source draws per-trial numbers only for its own batch size
        rng_a, rng_b = TrialRNG(9, 3), TrialRNG(9, 3)
        a._rng, b._rng = rng_a, rng_b
    lead, fol, bar_p, bar_v, axis = _states(np.random.default_rng(1), 3, 1)
    force, torque = a.wrench(lead, fol, a.rotor_offsets_body_m, DT_S)
    want = (force, torque, a.body_force_n(lead, fol),
            a.bar_force_n(lead, bar_p, bar_v, BAR_AREA_M2, DT_S, axis))
    got = b.wake_step(lead, fol, b.rotor_offsets_body_m, bar_p, bar_v, BAR_AREA_M2, DT_S, axis)
    assert [_bits(x) for x in got] == [_bits(x) for x in want]
    assert _bits(standard_normal_t(rng_b, 3, 4)) == _bits(standard_normal_t(rng_a, 3, 4))


def test_a_step_of_no_time_leaves_the_bars_turbulence_and_draws_none_for_it():
    """``dt = 0``: the follower's turbulence takes a step of nothing (its draws still made, as
    ``wrench`` makes them); the bar's neither advances nor draws, as ``bar_force_n``'s."""
    a, b, rng_a, rng_b = _pair({}, 4, True)
    lead, fol, bar_p, bar_v, axis = _states(np.random.default_rng(2), 4, 1)
    force, torque = a.wrench(lead, fol, a.rotor_offsets_body_m, 0.0)
    want = (force, torque, a.body_force_n(lead, fol),
            a.bar_force_n(lead, bar_p, bar_v, BAR_AREA_M2, 0.0, axis))
    noise = b._bar_noise.copy()
    got = b.wake_step(lead, fol, b.rotor_offsets_body_m, bar_p, bar_v, BAR_AREA_M2, 0.0, axis)
    assert [_bits(x) for x in got] == [_bits(x) for x in want]
    assert _bits(b._bar_noise) == _bits(noise)
    assert _bits(standard_normal_t(rng_b, 4, 4)) == _bits(standard_normal_t(rng_a, 4, 4))


def test_a_jet_that_replaces_a_part_is_called_part_by_part():
    """A jet whose wrench, body's or bar's force is not the jet's own (a subclass's, a mixin's,
    the instance's, or None) gives way to its parts, drawing nothing, so the world calls them;
    one that replaces the one call too keeps it; a plug-in without one is told apart (None)."""

    class LouderBar(RoundJetField):
        def bar_force_n(self, *args, **kwargs):
            return 2.0 * super().bar_force_n(*args, **kwargs)

    class Quieter(LouderBar):
        pass

    class OwnStep(LouderBar):
        def wake_step(self, *args, **kwargs):
            return "own"

    class Minimal:
        def reset(self, n, rng):
            pass

        def acceleration(self, leader, follower, dt):
            return np.zeros((leader.n, 3))

    class LouderBarMixin:
        def bar_force_n(self, *args, **kwargs):
            return 2.0 * super().bar_force_n(*args, **kwargs)

    class Mixed(LouderBarMixin, RoundJetField):  # the part inherited, not in its own dict
        pass

    lead, fol, bar_p, bar_v, axis = _states(np.random.default_rng(3), 2, 1)
    args = (lead, fol, np.zeros((4, 3)), bar_p, bar_v, BAR_AREA_M2, DT_S, axis)
    assert wake_step(Minimal(), *args) is None
    jet = default_jet()
    assert wake_step(jet, *args) is not None
    for cls in (RoundJetAtCentre, LouderBar, Quieter, Mixed):  # RoundJetAtCentre: wrench None
        jet.__class__ = cls  # the default jet's parameters, the class's methods
        state = jet._rng.bit_generator.state if hasattr(jet._rng, "bit_generator") else None
        assert wake_step(jet, *args) is None, cls.__name__
        if state is not None:  # gave way before drawing anything
            assert jet._rng.bit_generator.state == state
    jet.__class__ = OwnStep
    assert wake_step(jet, *args) == "own"
    jet.__class__ = RoundJetField
    jet.bar_force_n = lambda *a, **k: np.zeros((2, 3))  # the instance's own part
    assert wake_step(jet, *args) is None
    del jet.bar_force_n
    assert wake_step(jet, *args) is not None


@pytest.mark.parametrize("n", [1, 3])
def test_the_world_flies_the_same_numbers_with_one_call_or_three(n):
    """The terms add the one call's forces where they added the three calls': the world's
    every state after 30 control periods is the same to the bit (the jet told to have no one
    call flies the three)."""
    from aerodock.bench.simulator import SimLoop
    from aerodock.config import load_config

    def fly(one_call: bool) -> list[bytes]:
        loop = SimLoop(load_config(None), n, seed=5)
        if not one_call:
            loop.world.field.wake_step = None  # the instance's: the world's generic path
        loop.reset()  # both a second time: the same draws before the flight
        loop.run(30)
        world = loop.world
        out = [_bits(world.bar.p), _bits(world.cable_force_n),
               _bits(world.last_downwash_mps2), _bits(world.follower_accel)]
        for state in (world.leader, world.follower):
            out += [_bits(state.p), _bits(state.v), _bits(state.R), _bits(state.w)]
        return out

    assert fly(True) == fly(False)


def test_the_one_call_is_made_only_when_the_step_runs_the_three_wake_terms_in_a_row():
    """A step of one's own with a term between the wake terms (which might draw random numbers)
    or without one of them takes the three calls: the one call would draw the bar's turbulence
    before that term, or for a term the step leaves out."""
    from aerodock.world.step import WORLD_STEP, Term, wake_terms_together, with_term

    assert wake_terms_together(WORLD_STEP)
    between = with_term(WORLD_STEP, Term("gust", lambda state, frame, params: None),
                        after="wake on the body")
    assert not wake_terms_together(between)
    without_bar = tuple(t for t in WORLD_STEP if t.name != "wake on the bar")
    assert not wake_terms_together(without_bar)

    class Unhashable:
        __hash__ = None

        def __call__(self, state, frame, params):
            return None

    odd = with_term(WORLD_STEP, Term("odd", Unhashable()), after="ground")
    assert wake_terms_together(odd)
