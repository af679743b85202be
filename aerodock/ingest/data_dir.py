"""Where the real flights are: one data location for every command, study, test and example.

The data location holds each dataset in a folder of its own name::

    DATA_DIR/neural-swarm/swap_ss/cf50_00.csv ... cf51_06.csv
    DATA_DIR/neural-swarm/swap_sl_2020-06-19/cf51_00.csv ... cf101_11.csv
    DATA_DIR/px4-ulog/sample_log_small.ulg

It is, the first that applies:

1. the command's ``--data-dir DIR`` (``explicit``);
2. the environment variable ``AERODOCK_DATA_DIR``;
3. in this repository's own checkout only, ``../shared/data``: beside the working folder, else
   beside the repository (the project's machines keep the flights there).

A location that was named (1 or 2) and is not a folder is an error for the caller to report; the
fallback (3) is used only when it exists. Where to get the flights: ``docs/real-logs.md``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

ENV_VAR = "AERODOCK_DATA_DIR"
"""The environment variable naming the data location."""
NEURAL_SWARM = "neural-swarm"
"""The Neural-Swarm dataset's folder inside the data location."""
SWAP_FOLDERS = ("swap_ss", "swap_sl_2020-06-19")
"""The Neural-Swarm flight folders the commands read, inside :data:`NEURAL_SWARM`."""

# This file is REPO/aerodock/ingest/data_dir.py: REPO/../shared/data is the project's fallback.
_REPO = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class DataDir:
    """A data location and where it came from.

    Attributes:
        path: the folder, or None when none was named and the fallback is absent.
        source: ``"--data-dir"``, ``"AERODOCK_DATA_DIR"``, ``"../shared/data"`` or ``"none"``.
    """

    path: Path | None
    source: str

    @property
    def named(self) -> bool:
        """True when the user named the location (the option or the environment variable)."""
        return self.source in ("--data-dir", ENV_VAR)

    def problem(self) -> str | None:
        """One line saying why a named location cannot be used (None when it can, or when it
        was not named: a missing fallback is not an error)."""
        if self.named and self.path is not None and not self.path.is_dir():
            return (f"{self.source} {self.path}: no such folder (the data location holding "
                    f"{NEURAL_SWARM}/; see docs/real-logs.md)")
        return None

    def neural_swarm(self) -> Path | None:
        """``path / "neural-swarm"`` (None without a location)."""
        return None if self.path is None else self.path / NEURAL_SWARM


def fallback_dirs(cwd: Path | None = None) -> tuple[Path, Path]:
    """This repository's fallbacks, in order: ``../shared/data`` beside the working folder
    ``cwd`` (default: the current one), then beside the repository."""
    here = Path.cwd() if cwd is None else Path(cwd)
    return here.parent / "shared" / "data", _REPO.parent / "shared" / "data"


def find_data_dir(explicit: str | Path | None = None,
                  environ: Mapping[str, str] | None = None,
                  cwd: Path | None = None) -> DataDir:
    """The data location (module docstring): ``explicit``, else ``environ[AERODOCK_DATA_DIR]``
    (default: ``os.environ``; an empty value counts as unset), else the first fallback that is
    a folder. A named location is returned as named, folder or not (:meth:`DataDir.problem`)."""
    if explicit is not None and str(explicit) != "":
        return DataDir(Path(explicit).expanduser(), "--data-dir")
    env = os.environ if environ is None else environ
    value = env.get(ENV_VAR, "").strip()
    if value:
        return DataDir(Path(value).expanduser(), ENV_VAR)
    for folder in fallback_dirs(cwd):
        if folder.is_dir():
            return DataDir(folder, "../shared/data")
    return DataDir(None, "none")


def has_swap_flights(folder: Path | None, names: tuple[str, ...] = SWAP_FOLDERS[:1]) -> bool:
    """True when ``folder`` (a ``neural-swarm`` folder) holds every flight folder in ``names``,
    each with at least one ``.csv`` file."""
    if folder is None:
        return False
    return all((folder / name).is_dir() and any((folder / name).glob("*.csv"))
               for name in names)
