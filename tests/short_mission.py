"""The mission's waiting times cut (``reproduce --smoke``'s), for tests of a property that holds
whatever the timing: batch equality, determinism, bookkeeping, a plug-in going through a command.
A test of what the mission achieves (docking rates, sinks, errors) flies the configured timing.
:func:`short_config` flies the world before issue 39 (``worlds.EARLIER_WORLD``), where trials
dock: the machinery these tests check is the docking's."""

from __future__ import annotations

from functools import cache

from worlds import EARLIER_WORLD

from aerodock.config import Config, load_config
from aerodock.experiments.reproduce import SHORT_MISSION

__all__ = ["SHORT_MISSION", "short_config", "short_mission_toml"]


@cache
def short_config() -> Config:
    """The world before issue 39 with :data:`SHORT_MISSION`'s timing (built once)."""
    return load_config().with_overrides(EARLIER_WORLD).with_overrides(SHORT_MISSION)


def short_mission_toml() -> str:
    """:data:`SHORT_MISSION` as TOML sections (for a ``--config`` file)."""
    return "".join(f"[{section}]\n" + "".join(f"{k} = {v!r}\n" for k, v in keys.items())
                   for section, keys in SHORT_MISSION.items())
