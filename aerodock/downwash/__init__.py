"""Downwash fields: the default truth (``jet``), the protocol (``base``), plug-in loading, and the
helpers that let every field (also one with only the required methods) be used everywhere: its
mean (``mean``) and its force and torque on the follower and the bar (``wrench``)."""

from __future__ import annotations

import inspect
from typing import Any

from aerodock.config import Config, ConfigError, field_factory, resolve_factory
from aerodock.downwash.base import BodyState, DownwashField
from aerodock.downwash.mean import mean_acceleration_fn
from aerodock.downwash.wrench import (
    bar_wake_force_n,
    follower_body_force_n,
    follower_wrench,
    quad_rotor_offsets_body_m,
    wake_step,
)

__all__ = ["BodyState", "DownwashField", "bar_wake_force_n", "build_field", "field_factory",
           "field_kwargs",
           "follower_body_force_n", "follower_wrench", "mean_acceleration_fn",
           "quad_rotor_offsets_body_m", "wake_step"]

# World constants a field factory may accept; passed only when its signature names them. The
# plain names are the follower's (both vehicles', for a field that does not tell them apart).
_WORLD_KWARGS = ("rotor_radius_m", "n_rotors", "air_density_kgpm3", "gravity_mps2",
                 "leader_rotor_radius_m", "leader_n_rotors", "leader_mass_kg",
                 "leader_diagonal_m", "follower_rotor_radius_m", "follower_n_rotors",
                 "follower_mass_kg", "follower_diagonal_m")


def field_kwargs(cfg: Config, factory: Any) -> dict[str, Any]:
    """The keyword arguments :func:`build_field` passes ``factory``: ``[downwash.params]`` of
    ``cfg``, plus each world constant (:data:`_WORLD_KWARGS`: the vehicles' rotors, masses and
    diagonals, air density, gravity) that the factory's signature names and the params do not
    set. With the shipped defaults and :class:`~aerodock.downwash.jet.RoundJetField`, these are
    the default jet's every parameter, from their one home in ``defaults.toml``."""
    params: dict[str, Any] = dict(cfg.downwash.params)
    try:
        accepted = inspect.signature(factory).parameters
    except (TypeError, ValueError):
        accepted = {}
    lead, fol = cfg.leader, cfg.vehicle
    world = {"rotor_radius_m": fol.rotor_radius_m, "n_rotors": fol.n_rotors,
             "air_density_kgpm3": cfg.sim.air_density_kgpm3, "gravity_mps2": cfg.sim.gravity_mps2,
             "leader_rotor_radius_m": lead.rotor_radius_m, "leader_n_rotors": lead.n_rotors,
             "leader_mass_kg": lead.mass_kg, "leader_diagonal_m": lead.diagonal_m,
             "follower_rotor_radius_m": fol.rotor_radius_m, "follower_n_rotors": fol.n_rotors,
             "follower_mass_kg": fol.mass_kg, "follower_diagonal_m": fol.diagonal_m}
    for key in _WORLD_KWARGS:
        if key in accepted and key not in params:
            params[key] = world[key]
    return params


def build_field(cfg: Config) -> DownwashField:
    """Instantiate the configured field: ``[downwash] field`` with ``[downwash.params]``.

    Only the configured field's own parameters are passed (the config never carries the
    default field's parameters over to a plug-in), plus the world constants its signature names.
    The factory is checked to be one (:func:`aerodock.config.plugins.is_field_factory`) before
    it is called; the config's own field was checked for trust when the config was read.

    Raises:
        ConfigError: unknown plug-in, not a field factory, bad parameters, a factory that fails
            (whatever it raises, including ``SystemExit``), or an object that is not a field.
    """
    path = cfg.downwash.field
    factory = resolve_factory(path, cfg.source, (*cfg.trusted, path))
    params = field_kwargs(cfg, factory)
    try:
        field = factory(**params)
    except TypeError as err:
        raise ConfigError(f"{cfg.source}: 'downwash.params' do not fit {path} ({err})") from None
    except ValueError as err:
        raise ConfigError(f"{cfg.source}: 'downwash.params': {err}") from None
    except (Exception, SystemExit) as err:  # a plug-in's own code failed
        raise ConfigError(f"{cfg.source}: 'downwash.field' {path} failed to build "
                          f"({type(err).__name__}: {err})") from None
    if not isinstance(field, DownwashField):
        raise ConfigError(
            f"{cfg.source}: 'downwash.field' {path} does not build a field "
            "(needs reset(n, rng) and acceleration(leader, follower, dt))"
        )
    return field
