"""Where the world meets the field: the follower's wrench, its body's force and the bar's force,
for any field.

The world step calls these functions, never a field's optional methods directly, so a plug-in
with only ``reset`` and ``acceleration`` keeps working:

- :func:`follower_wrench`: the field's ``wrench`` (force and torque, sampled per rotor disk) when
  it has one, else ``acceleration * mass`` at the centre of mass with zero torque;
- :func:`follower_body_force_n`: the field's ``body_force_n`` (what lands on the follower's body
  rather than its rotor disks, at the centre of mass), None without one (a field without it puts
  its whole force in ``wrench`` or ``acceleration``);
- :func:`bar_wake_force_n`: the field's ``bar_force_n`` (None without one), passing ``dt`` (and
  the bar's long axis) only to implementations that accept them, so plug-ins written for the
  older four-argument signature keep working.

``follower_wrench`` and ``bar_wake_force_n`` advance the field's turbulence by ``dt``: the world
calls each once per physics step (not also ``acceleration``), then ``follower_body_force_n``,
which reads the same step's turbulence.

A field can also give all three at once: :func:`wake_step` calls its ``wake_step`` (the default
jet's: one compiled call in place of three Python paths, with the numbers and random draws of
the three calls in turn), and returns None for a field without one, or whose ``wake_step``
gives way (then the world makes the three calls above): the jet's gives way when a subclass, a
mixin or the instance has replaced one of the parts it stands for.
"""

from __future__ import annotations

import inspect
from functools import lru_cache
from typing import Any

import numpy as np

from aerodock.downwash.base import BodyState


def quad_rotor_offsets_body_m(diagonal_m: float, n_rotors: int = 4) -> np.ndarray:
    """(n_rotors, 3) rotor-disk centres in the body frame (FRD, z down), m.

    An X frame: rotors on the diagonals (the first at 45° from the nose, then evenly spaced),
    ``diagonal_m / 2`` from the centre of mass, in the plane of the centre of mass (z = 0).
    """
    if not diagonal_m > 0 or n_rotors < 1:
        raise ValueError(f"rotor layout needs diagonal_m > 0 and n_rotors >= 1, got "
                         f"{diagonal_m!r}, {n_rotors!r}")
    return _quad_rotor_offsets_body_m(float(diagonal_m), int(n_rotors)).copy()


@lru_cache(maxsize=64)
def _quad_rotor_offsets_body_m(diagonal_m: float, n_rotors: int) -> np.ndarray:
    """The layout of :func:`quad_rotor_offsets_body_m`, kept per size (a wake fit builds a jet
    per flight at every evaluation of its residual); the caller gets a copy."""
    angle = np.pi / 4 + 2 * np.pi * np.arange(n_rotors) / n_rotors
    arm = 0.5 * diagonal_m
    return np.stack([arm * np.cos(angle), arm * np.sin(angle), np.zeros(n_rotors)], axis=1)


def follower_wrench(field: Any, leader: BodyState, follower: BodyState,
                    rotor_offsets_body_m: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The field's force and torque on the follower; advances its turbulence by ``dt``.

    Args:
        field: a downwash field.
        leader, follower: batch-first states (n trials).
        rotor_offsets_body_m: (k, 3) rotor-disk centres in the follower's body frame (FRD), m
            (see :func:`quad_rotor_offsets_body_m`).
        dt: physics step, s.

    Returns:
        ``(force_n, torque_nm)``: (n, 3) force in N, world NED, and (n, 3) torque in N·m in the
        follower's body frame about its centre of mass. A field without ``wrench`` gives
        ``acceleration * mass`` and zero torque (applied at the centre of mass).

    Raises:
        ValueError: the field's ``wrench`` returned arrays of the wrong shape.
    """
    wrench = getattr(field, "wrench", None)
    n = follower.n
    if wrench is None:
        force = np.asarray(field.acceleration(leader, follower, dt), dtype=float)
        return force * np.asarray(follower.mass_kg, dtype=float)[:, None], np.zeros((n, 3))
    force, torque = wrench(leader, follower, np.asarray(rotor_offsets_body_m, dtype=float), dt)
    force, torque = np.asarray(force, dtype=float), np.asarray(torque, dtype=float)
    if force.shape != (n, 3) or torque.shape != (n, 3):
        raise ValueError(f"{type(field).__name__}.wrench returned shapes {force.shape} and "
                         f"{torque.shape}, expected ({n}, 3) and ({n}, 3)")
    return force, torque


def follower_body_force_n(field: Any, leader: BodyState,
                          follower: BodyState) -> np.ndarray | None:
    """(n, 3) the field's force on the follower's body (not its rotor disks), N, world NED, at
    the centre of mass, with the turbulence of this step's :func:`follower_wrench`; None if the
    field has no ``body_force_n``.

    Raises:
        ValueError: the field's ``body_force_n`` returned an array of the wrong shape.
    """
    method = getattr(field, "body_force_n", None)
    if method is None:
        return None
    force = np.asarray(method(leader, follower), dtype=float)
    if force.shape != (follower.n, 3):
        raise ValueError(f"{type(field).__name__}.body_force_n returned shape {force.shape}, "
                         f"expected ({follower.n}, 3)")
    return force


def bar_wake_force_n(field: Any, leader: BodyState, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                     bar_area_m2: float, dt: float,
                     bar_axis: np.ndarray | None = None) -> np.ndarray | None:
    """(n, 3) the wake's force on the hanging bar, N, NED; None if the field has no
    ``bar_force_n``.

    Args:
        field: a downwash field.
        leader: the leader's state.
        bar_p_m, bar_v_mps: (n, 3) the bar's centre position, m, and velocity, m/s.
        bar_area_m2: the bar's projected area (length x diameter), m².
        dt: physics step, s (a field whose ``bar_force_n`` takes ``dt`` advances its bar
            turbulence by it).
        bar_axis: (n, 3) unit vectors along the bar's length, world NED (for cross-flow drag;
            passed only to fields that accept it).
    """
    method = getattr(field, "bar_force_n", None)
    if method is None:
        return None
    func = getattr(method, "__func__", method)
    try:
        accepts = _keywords(func)
    except TypeError:  # an unhashable callable: ask without the cache
        accepts = _keywords.__wrapped__(func)
    kwargs: dict[str, Any] = {}
    if "dt" in accepts:
        kwargs["dt"] = dt
    if bar_axis is not None and "bar_axis" in accepts:
        kwargs["bar_axis"] = bar_axis
    return method(leader, bar_p_m, bar_v_mps, bar_area_m2, **kwargs)


def wake_step(field: Any, leader: BodyState, follower: BodyState,
              rotor_offsets_body_m: np.ndarray, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
              bar_area_m2: float, dt: float, bar_axis: np.ndarray | None = None,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """The whole physics step's wake from the field's ``wake_step`` in one call, None if the
    field has none (or it is None, or returns None: then nothing was drawn).

    Its numbers and random draws are those of :func:`follower_wrench`, then
    :func:`follower_body_force_n`, then :func:`bar_wake_force_n` with the same arguments, so
    it advances the follower's turbulence, then the bar's, by ``dt``.

    Returns:
        ``(force_n, torque_nm, body_force_n, bar_force_n)``, each (n, 3): the follower's
        disks' force, N, world NED; their torque, N·m, body FRD, about the centre of mass; the
        force on its body and on the bar, N, world NED.
    """
    method = getattr(field, "wake_step", None)
    if method is None:
        return None
    return method(leader, follower, rotor_offsets_body_m, bar_p_m, bar_v_mps, bar_area_m2, dt,
                  bar_axis)


@lru_cache(maxsize=64)
def _keywords(func: Any) -> frozenset[str]:
    """Keyword names a callable accepts (cached: the world asks every physics step)."""
    try:
        params = inspect.signature(func).parameters.values()
    except (TypeError, ValueError):
        return frozenset()
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return frozenset({"dt", "bar_axis"})
    return frozenset(p.name for p in params
                     if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                   inspect.Parameter.KEYWORD_ONLY))
