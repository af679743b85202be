"""The simulation's clocks, bound once: :class:`Timing`.

``[sim] physics_rate_hz`` and ``control_rate_hz`` and ``[control] command_rate_hz`` are read
here and nowhere else; the world, the controllers, the mission, the viewer and the commands
read the periods this record derives from them (``Config.timing``). The loader has checked that
each rate is a whole multiple of the next, so every period is a whole number of the one below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from aerodock.config.schema import ControlSection, SimSection


@dataclass(frozen=True)
class Timing:
    """The world's and the controllers' periods.

    Attributes:
        physics_rate_hz: the physics rate (``sim.physics_rate_hz``), Hz.
        control_rate_hz: the controllers' rate (``sim.control_rate_hz``), Hz.
        physics_dt_s: one physics step, s.
        substeps: physics steps per control period.
        control_dt_s: one control period (``substeps`` physics steps): the period the
            controllers integrate over and the mission counts in, s.
        command_ticks: control periods per new position command (Freyja's timer:
            ``sim.control_rate_hz / control.command_rate_hz``).
    """

    physics_rate_hz: float
    control_rate_hz: float
    physics_dt_s: float
    substeps: int
    control_dt_s: float
    command_ticks: int

    @classmethod
    def from_sections(cls, sim: SimSection, control: ControlSection) -> Timing:
        """Bind ``[sim]``'s rates and ``[control] command_rate_hz``."""
        physics_dt_s = 1.0 / sim.physics_rate_hz
        substeps = int(round(sim.physics_rate_hz / sim.control_rate_hz))
        return cls(physics_rate_hz=float(sim.physics_rate_hz),
                   control_rate_hz=float(sim.control_rate_hz), physics_dt_s=physics_dt_s,
                   substeps=substeps, control_dt_s=substeps * physics_dt_s,
                   command_ticks=int(round(sim.control_rate_hz / control.command_rate_hz)))

    def physics_steps(self, duration_s: float) -> int:
        """Physics steps that cover ``duration_s`` (rounded up)."""
        return math.ceil(duration_s * self.physics_rate_hz)

    def control_periods(self, duration_s: float) -> int:
        """Control periods that cover ``duration_s`` (rounded up)."""
        return math.ceil(duration_s * self.control_rate_hz)
