"""One physics step of the world: an ordered, named tuple of terms (:mod:`aerodock.world.terms`).

The order is part of the numbers. Forces come first (each term adds into the step's
accumulators, so the order of additions is the order below), then what the flight computers
sense, then the vehicles move, then the constraints that act on the result (the bar and a hanging
follower, the ground), then ``commit`` makes the new state current and advances the clock, and the
sensors sample the end of the step. Random numbers are drawn in this order too: the field's
turbulence (follower, then bar), the gyros (and, with the filtered IMU chain, the
accelerometers), the strain gauge. A new effect is one function in :mod:`aerodock.world.terms`
and one ``Term`` here, or, outside the package, a step of one's own (:func:`with_term`) passed to
:class:`aerodock.world.World`; :mod:`aerodock.world.term_template` is a documented one to copy.

:data:`WORLD_STEP` also runs as one compiled call per control period
(:mod:`aerodock.world.period`, the same terms in the same order and the same numbers); a term
added to it here runs there only once the period's kernel has it too (until then the world
steps per step: ``period.runs_step``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from functools import lru_cache
from typing import Any, NamedTuple

import numpy as np

from aerodock.downwash import BodyState
from aerodock.downwash.base import frozen_record
from aerodock.world import terms
from aerodock.world.params import WorldParams
from aerodock.world.state import StepFrame, WorldState


class Term(NamedTuple):
    """One named physics term of the step."""

    name: str
    apply: Callable[[WorldState, StepFrame, WorldParams], None]


WORLD_STEP: tuple[Term, ...] = (
    # forces on the vehicles and the bar
    Term("wake on the rotor disks", terms.wake_on_rotor_disks),
    Term("wake on the body", terms.wake_on_body),
    Term("wake on the bar", terms.wake_on_bar),
    Term("gripper contact", terms.gripper_contact),
    Term("cable on the leader", terms.cable_on_leader),
    Term("rotor faults", terms.rotor_faults),
    # what the flight computers sense, then the motion, then the constraints on it
    Term("imu", terms.imu),
    Term("vehicles", terms.vehicles),
    Term("hanging pair", terms.hanging_pair),
    Term("ground", terms.ground),
    Term("commit", terms.commit),
    # sensing at the end of the step
    Term("gripper", terms.gripper),
    Term("motion capture", terms.motion_capture),
)
"""The world's step, in order."""


def with_term(step: tuple[Term, ...], term: Term, after: str) -> tuple[Term, ...]:
    """``step`` with ``term`` inserted after the term named ``after``
    (:mod:`aerodock.world.term_template` shows a term to insert).

    Raises:
        ValueError: ``step`` has no term named ``after``, or already one named as ``term``.
    """
    names = [t.name for t in step]
    if term.name in names:
        raise ValueError(f"the step already has a term named {term.name!r}")
    if after not in names:
        raise ValueError(f"no term named {after!r} in the step (its terms: {', '.join(names)})")
    at = names.index(after) + 1
    return (*step[:at], term, *step[at:])


def begin_step(state: WorldState, params: WorldParams, targets: Any,
               close_command: np.ndarray | None) -> StepFrame:
    """The step's frame: the vehicles as the terms see them, zeroed accumulators. Built as its
    constructor builds it, at a fraction of the cost
    (:func:`~aerodock.downwash.base.frozen_record`: the frame's and the halves' fields straight
    into their ``__dict__``, the frame's defaulted fields from :data:`_FRAME_DEFAULTS`;
    ``tests/unit/test_glue_rest.py`` holds them to their classes' fields)."""
    n = state.n
    both = state.both
    rot, pos, vel = both.R, both.p, both.v
    thrust = both.thrust_n
    body = both.body
    lead_mass, fol_mass, fol_mass_rows = state.body_halves()
    captured, any_captured, _ = state.gripper_flags()
    yaw = state.bar.yaw_rad
    bar_axis = np.zeros((3, n))  # (cos yaw, sin yaw, 0) per bar, component-major
    np.cos(yaw, out=bar_axis[0])
    np.sin(yaw, out=bar_axis[1])
    return frozen_record(StepFrame, **{
        "targets": targets,
        "close_command": state.constants.no_close if close_command is None else close_command,
        "both": both, "rot": rot, "pos": pos, "vel": vel,
        "lead": frozen_record(BodyState, **{"p": pos[:n], "v": vel[:n], "R": rot[:n],
                                    "thrust_n": thrust[:n], "mass_kg": lead_mass}),
        "fol": frozen_record(BodyState, **{"p": pos[n:], "v": vel[n:], "R": rot[n:],
                                   "thrust_n": thrust[n:], "mass_kg": fol_mass}),
        "mass_kg": body.mass_kg, "mass_rows_kg": body.mass_rows_kg,
        "fol_mass_rows_kg": fol_mass_rows, "captured": captured, "any_captured": any_captured,
        "bar_axis_t": bar_axis,
        "force_n": np.zeros((2 * n, 3)),
        "torque_t": np.zeros((3, 2 * n)) if params.rigid else None,
        "bar_force_n": np.zeros((n, 3)),
        **_FRAME_DEFAULTS,
    })


# The frame's fields with a default (None, False: shared, immutable), in their order, after the
# fields begin_step sets (a field added to StepFrame with a plain default needs nothing here).
_FRAME_DEFAULTS: dict[str, Any] = {f.name: f.default for f in dataclasses.fields(StepFrame)
                                   if f.default is not dataclasses.MISSING}


_WAKE_TERMS = (terms.wake_on_rotor_disks, terms.wake_on_body, terms.wake_on_bar)


def wake_terms_together(step: tuple[Term, ...]) -> bool:
    """Whether ``step`` runs the three wake terms one after the other, in :data:`WORLD_STEP`'s
    order: only then may a field give their three forces in one call (its random draws, the
    follower's then the bar's, are then those of the three calls in turn). Kept per step."""
    try:
        return _wake_terms_together(step)
    except TypeError:  # a term of one's own that cannot be hashed: asked every step
        return _wake_terms_together.__wrapped__(step)


@lru_cache(maxsize=64)
def _wake_terms_together(step: tuple[Term, ...]) -> bool:
    applied = [term.apply for term in step]
    return any(tuple(applied[i:i + 3]) == _WAKE_TERMS for i in range(len(applied) - 2))


def step_world(state: WorldState, params: WorldParams, step: tuple[Term, ...], targets: Any,
               close_command: np.ndarray | None) -> None:
    """Advance every trial of ``state`` by one physics step of ``step``'s terms, in order."""
    frame = begin_step(state, params, targets, close_command)
    frame.wake_terms_together = wake_terms_together(step)
    for term in step:
        term.apply(state, frame, params)
