"""The mission's waiting times cut (``reproduce --smoke``'s), for tests of a property that holds
whatever the timing: batch equality, determinism, bookkeeping, a plug-in going through a command.
A test of what the mission achieves (docking rates, sinks, errors) flies the configured timing."""

from __future__ import annotations

from aerodock.experiments.reproduce import SHORT_MISSION

__all__ = ["SHORT_MISSION", "short_mission_toml"]


def short_mission_toml() -> str:
    """:data:`SHORT_MISSION` as TOML sections (for a ``--config`` file)."""
    return "".join(f"[{section}]\n" + "".join(f"{k} = {v!r}\n" for k, v in keys.items())
                   for section, keys in SHORT_MISSION.items())
