"""The mission's constants, bound once from the configuration (nothing reads the config later)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from aerodock.config import Config
from aerodock.config.schema import MissionSection, PlannerSection
from aerodock.planning.docking import DockGeometry


@dataclass(frozen=True)
class MissionParams:
    """What the mission reads: its own and the planner's sections, the docking geometry, and
    the few vehicle and log constants it needs.

    Attributes:
        mission, planner: ``[mission]`` and ``[planner]``.
        geometry: the offsets between the leader, the bar and the follower at docking.
        mass_kg, gravity_mps2, rotor_radius_m: the follower's nominal values.
        leader_mass_kg: the leader's nominal mass.
        torque_feedforward: ``control.torque_feedforward`` (with a model flown).
        label_basis: what recorded logs hold as the follower's explained acceleration.
        cable_length_m: ``d_p`` of this campaign (recorded in each log).
        log_meta: the vehicles' metadata every recorded log carries.
    """

    mission: MissionSection
    planner: PlannerSection
    geometry: DockGeometry
    mass_kg: float
    leader_mass_kg: float
    gravity_mps2: float
    rotor_radius_m: float
    torque_feedforward: bool
    label_basis: str
    cable_length_m: float
    log_meta: dict[str, Any]

    @classmethod
    def from_config(cls, cfg: Config) -> MissionParams:
        """Bind what the mission reads of ``cfg``."""
        v = cfg.vehicle
        return cls(
            mission=cfg.mission, planner=cfg.planner, geometry=DockGeometry.from_config(cfg),
            mass_kg=v.mass_kg, leader_mass_kg=cfg.leader.mass_kg,
            gravity_mps2=cfg.sim.gravity_mps2, rotor_radius_m=v.rotor_radius_m,
            torque_feedforward=cfg.control.torque_feedforward,
            label_basis=cfg.curriculum.label_basis, cable_length_m=cfg.platform.cable_length_m,
            log_meta=vehicle_meta(cfg),
        )

    @property
    def hover_thrust_n(self) -> float:
        """The follower's weight, N."""
        return self.mass_kg * self.gravity_mps2


def vehicle_meta(cfg: Config) -> dict[str, Any]:
    """FlightLog metadata of both simulated vehicles (model files record what they learnt on)."""
    lead, fol = cfg.leader, cfg.vehicle
    return {"leader_rotor_radius_m": lead.rotor_radius_m,
            "follower_rotor_radius_m": fol.rotor_radius_m,
            "leader_n_rotors": int(lead.n_rotors), "follower_n_rotors": int(fol.n_rotors),
            "leader_diagonal_m": lead.diagonal_m, "follower_diagonal_m": fol.diagonal_m,
            "vehicle_model": fol.model}


def fly_on_configured_rotors(predictor: Any, cfg: Config) -> None:
    """Give a leader-aware model (``needs_wake_scales``) the configured vehicles' rotors.

    Its wake scales come from the leader's thrust and rotors; without this it would build them
    with the training flights' rotors, and a model trained under one leader would be handed
    another leader's thrust with the first one's rotor size. Other predictors are left alone
    (a larger follower's rotor footprint, :mod:`aerodock.learning.footprint`, is applied only
    where a caller asks for it: its second-order argument needs the extra ring small against
    the wake's width, which a Crazyflie's model on the paper's 0.27 m vehicle is not).
    """
    if getattr(predictor, "needs_wake_scales", False):
        lead, fol = cfg.leader, cfg.vehicle
        predictor.set_rotor_geometry(lead.rotor_radius_m, int(lead.n_rotors),
                                     fol.rotor_radius_m, int(fol.n_rotors))
