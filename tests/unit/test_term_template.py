"""The world-term template: inserted where asked, silent when off, and a steady wind's drag
as its physics says."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.config import load_config
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command
from aerodock.world.step import WORLD_STEP, Term, with_term
from aerodock.world.term_template import WindParams, wind_drag

N = 3


def _fly(step, periods: int = 25) -> World:
    """N trials hovering open-loop 1 m apart, leader above follower, for ``periods``."""
    cfg = load_config()
    world = World(cfg, N, TrialRNG(4, N), step=step)
    world.reset(np.tile([0.0, 0.0, -3.0], (N, 1)), np.tile([1.0, 0.0, -2.0], (N, 1)))
    lead = hover_command(world.params.leader_vehicle, N)
    fol = hover_command(world.vehicle, N)
    for _ in range(periods):
        world.advance(lead, fol)
    return world


def _wind(velocity, area=0.02) -> tuple[Term, ...]:
    term = Term("wind", wind_drag(WindParams(velocity_mps=velocity, drag_area_m2=area)))
    return with_term(WORLD_STEP, term, after="cable on the leader")


def test_a_term_goes_where_it_is_asked():
    step = _wind((1.0, 0.0, 0.0))
    names = [t.name for t in step]
    assert names[names.index("cable on the leader") + 1] == "wind"
    assert len(step) == len(WORLD_STEP) + 1
    with pytest.raises(ValueError, match="no term named 'nowhere'"):
        with_term(WORLD_STEP, step[names.index("wind")], after="nowhere")
    with pytest.raises(ValueError, match="already has a term named 'imu'"):
        with_term(WORLD_STEP, WORLD_STEP[0]._replace(name="imu"), after="ground")
    with pytest.raises(ValueError, match="three finite numbers"):
        WindParams(velocity_mps=(1.0, np.nan, 0.0), drag_area_m2=0.02)


def test_a_term_that_adds_nothing_changes_no_number():
    plain, still = _fly(WORLD_STEP), _fly(_wind((0.0, 0.0, 0.0), area=0.0))
    assert np.array_equal(plain.state.both.p, still.state.both.p)
    assert np.array_equal(plain.state.both.v, still.state.both.v)


def test_a_steady_wind_pushes_both_vehicles_downwind_by_its_drag():
    periods, wind_mps, area_m2 = 25, 4.0, 0.02
    plain, windy = _fly(WORLD_STEP, periods), _fly(_wind((0.0, wind_mps, 0.0), area_m2), periods)
    dv = windy.state.both.v - plain.state.both.v  # (2N, 3): leaders, then followers
    t_s = periods * windy.dt_control_s
    masses = np.concatenate([np.full(N, windy.params.leader_vehicle.mass_kg),
                             np.full(N, windy.vehicle.mass_kg)])
    # Quadratic drag from rest towards the wind's speed: dv = W tanh(k W t), k = rho CdA / 2m.
    k = 0.5 * 1.225 * area_m2 / masses
    expected = wind_mps * np.tanh(k * wind_mps * t_s)
    # Within 10 %: the vehicles' own rotor drag (linear in their speed) and the leader's cables
    # take a few per cent off the free body's answer.
    assert np.allclose(dv[:, 1], expected, rtol=0.10)
    assert np.all(dv[:, 1] < expected)
    assert np.all(np.abs(dv[:, [0, 2]]) < 0.2 * expected[:, None])  # east, not north or down
