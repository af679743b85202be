"""Trajectory planning for the follower."""

from aerodock.planning.minjerk import MinJerk, minjerk

__all__ = ["MinJerk", "minjerk"]
