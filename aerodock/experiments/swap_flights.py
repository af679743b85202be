"""The Neural-Swarm swap flights the wake studies read: the small pair (``swap_ss``) and the small
and large Crazyflie (``swap_sl_2020-06-19``), both roles of every flight, as FlightLogs."""

from __future__ import annotations

import warnings
from pathlib import Path

from aerodock.flightlog import FlightLog
from aerodock.ingest import read_logs

FOLDERS = ("swap_ss", "swap_sl_2020-06-19")
VEHICLES = "cf50=small,cf51=small,cf101=large"


def read_swap_flights(data_dir: Path) -> list[FlightLog]:
    """Both folders under ``data_dir`` (the dataset's ``neural-swarm`` folder), the vehicles
    typed by :data:`VEHICLES`; the ingest's notes on the flights' clocks are not repeated.

    Raises:
        FileNotFoundError: a folder is missing (named).
    """
    folders = [Path(data_dir) / name for name in FOLDERS]
    for folder in folders:
        if not folder.is_dir():
            raise FileNotFoundError(f"{folder}: no such folder (the Neural-Swarm flights)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_logs("neural-swarm", folders, vehicle=VEHICLES)
