"""The simulated world: two vehicles, the downwash wake, the hanging bar and the gripper."""

from aerodock.world.world import Observation, World, hover_command

__all__ = ["Observation", "World", "hover_command"]
