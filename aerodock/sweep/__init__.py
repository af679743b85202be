"""Parameter studies: ``aerodock sweep SPEC.toml`` (grid or random; local processes or Ray)."""

from aerodock.sweep.run import OUTCOME_COLUMNS, run_cell, run_sweep, write_table
from aerodock.sweep.spec import (
    AXES,
    Cell,
    SweepSpec,
    SweepSpecError,
    cell_config,
    load_spec,
    parse_spec,
)
from aerodock.sweep.store import CellStore

__all__ = ["AXES", "OUTCOME_COLUMNS", "Cell", "CellStore", "SweepSpec", "SweepSpecError",
           "cell_config", "load_spec", "parse_spec", "run_cell", "run_sweep", "write_table"]
