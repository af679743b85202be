"""The default jet with its whole force at the follower's centre of mass: no wake torque.

A bracket, not a world. :class:`aerodock.downwash.jet.RoundJetField` shares its calibrated force
among the follower's rotor disks in proportion to the wake's dynamic pressure at each, so a
follower off the wake's axis feels a torque. At a Crazyflie's scale that torque tilts a follower
holding station 0.3 m below a leader by 13.3 deg RMS, where the real swap flights measure 2.9 deg
below the other vehicle (2.0 in free air); with the force at the centre of mass the same
follower tilts 1.7 deg (``studies/crazyflie_tilt.py``, ``docs/crazyflie.md``). The truth about
the torque lies between the two fields, much nearer this one, until the wake is fitted to the
real flights (issue 23). Use it as ``[downwash] field =
"aerodock.downwash.at_centre:RoundJetAtCentre"`` with the jet's ``[downwash.params]`` (a new
``field`` takes only the parameters given with it).
"""

from __future__ import annotations

from aerodock.downwash.jet import RoundJetField


class RoundJetAtCentre(RoundJetField):
    """:class:`~aerodock.downwash.jet.RoundJetField` without ``wrench``: the world applies its
    ``acceleration * mass`` at the follower's centre of mass
    (:func:`aerodock.downwash.wrench.follower_wrench`); everything else is the jet's."""

    wrench = None  # type: ignore[assignment]
