"""A template for a new physics term of the world step: a steady wind's drag on both vehicles.

Copy this file to add an effect to the world (ground effect, a tether, a gust model...). A term
is a plain function ``term(state, frame, params)`` (:mod:`aerodock.world.terms`): it reads the
batch state and the step's frame (:class:`~aerodock.world.state.StepFrame`), adds what it
contributes into the frame's accumulators (``force_n``, ``torque_t``, ``bar_force_n``) in place,
and returns nothing. Its own parameters are a frozen record bound once, closed over by the
function :func:`wind_drag` returns (the world's own terms read :class:`WorldParams`, bound from the
configuration in the same way). Insert it into a step with :func:`aerodock.world.step.with_term`
and give the step to the world::

    from aerodock.world import World
    from aerodock.world.step import WORLD_STEP, Term, with_term
    from aerodock.world.term_template import WindParams, wind_drag

    wind = Term("wind", wind_drag(WindParams(velocity_mps=(3.0, 0.0, 0.0), drag_area_m2=0.02)))
    step = with_term(WORLD_STEP, wind, after="cable on the leader")
    world = World(cfg, n, rng, step=step)

Where the term goes is part of the numbers: a force belongs before ``"vehicles"`` (which moves
the vehicles under the forces added so far), and its place among the forces sets the order of
the additions (so a term added last changes no other term's bits). A term written in NumPy, as
this one, costs its own NumPy calls each physics step (a few µs at a batch of one;
docs/performance.md, "What a plug-in costs"). Its tests (``tests/unit/test_term_template.py``)
show what to check of a new term: that it changes no number when it adds nothing, and that it
acts as its physics says.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from aerodock.world.params import WorldParams
from aerodock.world.state import StepFrame, WorldState


@dataclass(frozen=True)
class WindParams:
    """A steady, uniform wind and the vehicles' drag in it.

    Attributes:
        velocity_mps: the wind's velocity, world NED, m/s.
        drag_area_m2: drag coefficient times frontal area of each vehicle, m^2 (about 0.02 for
            a 0.3 m quadrotor; the user's own vehicle's figure).
        air_density_kgpm3: the air's density, kg/m^3.
    """

    velocity_mps: tuple[float, float, float]
    drag_area_m2: float
    air_density_kgpm3: float = 1.225

    def __post_init__(self) -> None:
        if len(self.velocity_mps) != 3 or not np.all(np.isfinite(self.velocity_mps)):
            raise ValueError(f"velocity_mps must be three finite numbers, got "
                             f"{self.velocity_mps!r}")
        if not (self.drag_area_m2 >= 0.0 and self.air_density_kgpm3 > 0.0):
            raise ValueError("drag_area_m2 must be >= 0 and air_density_kgpm3 > 0")


def wind_drag(wind: WindParams) -> Callable[[WorldState, StepFrame, WorldParams], None]:
    """The term: quadratic drag ``0.5 rho CdA |u| u`` of the air relative to each vehicle,
    ``u = wind - v``, on both vehicles at their centres of mass (no torque). No random draws."""
    wind_mps = np.asarray(wind.velocity_mps, dtype=float)
    half_rho_cda = 0.5 * wind.air_density_kgpm3 * wind.drag_area_m2

    def term(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
        relative = wind_mps - frame.vel  # (2n, 3): the air as each vehicle meets it
        speed = np.sqrt(np.einsum("ij,ij->i", relative, relative))
        frame.force_n += (half_rho_cda * speed)[:, None] * relative

    return term
