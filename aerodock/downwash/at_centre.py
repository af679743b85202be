"""The default jet with its whole force at the follower's centre of mass: no wake torque.

A bracket, not a world. :class:`aerodock.downwash.jet.RoundJetField` puts its force on the
follower's rotor disks (and body), so a follower off the wake's axis feels a torque. Measured
with the previous, hand-calibrated jet, which put its whole force on the disks: at a Crazyflie's
scale that torque tilted a follower holding station 0.3 m below a leader by 13.3 deg RMS, where
the real swap flights measure 2.9 deg below the other vehicle (2.0 in free air); with the force
at the centre of mass the same follower tilted 1.7 deg (``studies/crazyflie_tilt.py``,
``docs/crazyflie.md``). The real flights' logged motor torques later showed that the small real
tilt is not a small torque (the wake's torque is 5-8 times the fitted jet's; a real Crazyflie's
attitude loop holds it): the world without the torque is the other side of a bracket, not the
truth. Use it as ``[downwash] field =
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
