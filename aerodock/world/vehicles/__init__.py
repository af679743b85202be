"""The vehicles of the world: rigid bodies under their autopilots, or point masses."""
