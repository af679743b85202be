"""Finished cells on disk: what ``aerodock sweep --resume`` reuses.

Every cell's outcomes are saved as the cell finishes, one JSON file per cell named by its key:
the SHA-256 of everything its numbers depend on (:func:`cell_settings`: the configuration the
cell flies, resolved, with its config keys, controller profile and noise scale applied; the
campaign's trials, cable length, leader speed, fault, compensation and seed; the model's files
when it flies one; aerodock's version). A changed spec, config or model gives other keys, so a
stale cell is never reused; a cell's place in the grid is not part of its key, so a spec that
gains an axis value or a seed reuses the cells it already had.

A sweep keeps the cells it flies in ``.NAME.cells/`` beside its ``--out NAME`` while it runs
(kept when it is interrupted or fails), then writes them into the study as ``OUT/cells/`` and
removes the hidden folder. ``--resume`` looks in both. A cell file is data (JSON, bounded size):
one that does not parse, or does not match its key and the outcome columns, is not reused.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from aerodock.config import Config
from aerodock.fileio import (
    MAX_JSON_BYTES,
    InputError,
    atomic_open,
    dumps_json,
    json_ready,
    read_input_text,
    refuse_symlink,
)
from aerodock.mission.spec import AbortReason
from aerodock.sources import sources_digest
from aerodock.sweep.spec import Cell

CELL_FORMAT = 1
"""The version of a cell file's layout (part of every key)."""
OUTCOME_NAMES = ("trial", "docked", "missed", "slipped", "aborted", "abort_reason",
                 "clearance_violation", "min_clearance_m", "capture_time_s", "err_down_m",
                 "err_3d_m")
"""A trial's outcome columns (:data:`aerodock.sweep.run.OUTCOME_COLUMNS`), what a cell file holds
per trial; the cell's settings columns are rebuilt from the spec."""
_BOOLS = ("docked", "missed", "slipped", "aborted", "clearance_violation")
_FLOATS = ("min_clearance_m", "err_down_m", "err_3d_m")  # null in the file: NaN (a failed trial)


def code_version() -> str:
    """aerodock's version (``aerodock.__version__``, else the installed package's)."""
    import aerodock

    version = getattr(aerodock, "__version__", None)
    if version is None:
        from importlib import metadata

        try:
            version = metadata.version("aerodock")
        except metadata.PackageNotFoundError:
            version = "unknown"
    return str(version)


def code_digest(cfg: Config | None = None) -> str:
    """SHA-256 over aerodock's sources (every module of the package, by path and bytes) and,
    when ``cfg`` names a plug-in field outside aerodock, that module's source: a cell flown
    by other code is never reused (an editable install keeps one version number across
    commits)."""
    plugin = _plugin_source(cfg)
    return sources_digest(extra=[] if plugin is None else [plugin.read_bytes()])


def _plugin_source(cfg: Config | None) -> Path | None:
    """The source file of the plug-in field ``cfg`` names, if it is not aerodock's own (the
    config's trust check has imported it already; nothing is imported here)."""
    import sys

    name = str(((cfg.data.get("downwash") or {}) if cfg is not None else {}).get("field") or "")
    module = name.split(":", 1)[0]
    if not module or module == "aerodock" or module.startswith("aerodock."):
        return None
    loaded = sys.modules.get(module)
    origin = getattr(loaded, "__file__", None)
    return Path(origin) if origin and Path(origin).is_file() else None


def model_digest(model: str | Path | None) -> str | None:
    """SHA-256 over a model folder's files (names and bytes), or None without a model."""
    if model is None:
        return None
    h = hashlib.sha256()
    folder = Path(model)
    for path in sorted(p for p in folder.iterdir() if p.is_file()):
        h.update(path.name.encode() + b"\0")
        h.update(path.read_bytes())
    return h.hexdigest()


def cell_settings(cell_cfg: Config, cell: Cell, trials: int, model_sha256: str | None
                  ) -> dict[str, Any]:
    """Everything a cell's outcomes depend on (JSON-ready): its resolved configuration and
    campaign, the model's digest (:func:`model_digest`; compensation ``model`` only),
    aerodock's version and the digest of the code that flies it (:func:`code_digest`)."""
    offset = cell.cable_length_m
    return {"format": CELL_FORMAT, "aerodock": code_version(), "code": _code_digest(cell_cfg),
            "config": cell_cfg.data,
            "campaign": {"trials": trials,
                         "cable_length_m": (cell_cfg.platform.cable_length_m if offset is None
                                            else offset),
                         "leader_speed_mps": cell.leader_speed_mps,
                         "leader_dropout_s": (None if cell.leader_dropout_s is None
                                              else list(cell.leader_dropout_s)),
                         "compensation": cell.compensation, "seed": cell.seed},
            "model": model_sha256 if cell.compensation == "model" else None}


def cell_key(settings: dict[str, Any]) -> str:
    """The key of a cell's settings: SHA-256 of their canonical JSON."""
    text = json.dumps(settings, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


class CellStore:
    """Finished cells: saved into ``folder`` as they finish, looked up in ``reuse_from``.

    Args:
        folder: where :meth:`save` writes (created when the first cell is saved).
        reuse_from: the folders :meth:`load` looks in, in order; empty: nothing is reused (a run
            without ``--resume`` still saves its cells).

    Raises:
        InputError: ``folder`` is a symbolic link.
    """

    def __init__(self, folder: str | Path, reuse_from: Sequence[str | Path] = ()) -> None:
        self.folder = Path(folder)
        refuse_symlink(self.folder)
        self.reuse_from = tuple(Path(p) for p in reuse_from)
        self.reused: list[int] = []
        """The indices of the cells taken from a folder instead of flown."""
        self.flown: list[int] = []
        """The indices of the cells flown (and saved)."""
        self.keys: dict[int, str] = {}
        """Every cell's key by index (set by :func:`aerodock.sweep.run.run_sweep`)."""
        self.validated: dict[str, Path] = {}
        """The folder each reused cell's file was read (and checked) from, by key."""

    def load(self, key: str, trials: int) -> list[dict[str, Any]] | None:
        """The outcomes of the cell ``key`` (one dict per trial), or None if no folder holds a
        valid file for it (a damaged or crafted file is flown again, never an error)."""
        for folder in self.reuse_from:
            try:
                doc = json.loads(read_input_text(folder / f"{key}.json", "sweep cell",
                                                 MAX_JSON_BYTES), parse_constant=_no_constant)
                if _valid(doc, key, trials):
                    outcomes = [_outcome(o) for o in doc["outcomes"]]
                    self.validated[key] = folder
                    return outcomes
            except (OSError, InputError, ValueError, OverflowError, TypeError, RecursionError):
                continue
        return None

    def save(self, key: str, settings: dict[str, Any], outcomes: list[dict[str, Any]]) -> Path:
        """Write one finished cell (atomically) into :attr:`folder`."""
        path = self.folder / f"{key}.json"
        text = dumps_json(json_ready({"key": key, "settings": settings, "outcomes": outcomes}),
                          indent=None)
        with atomic_open(path, "w") as fh:
            fh.write(text + "\n")
        return path

    def export(self, keys: Iterable[str], target: str | Path) -> None:
        """Copy the cell files of ``keys`` from :attr:`folder` (else the reuse folders) into
        ``target`` (the study's ``cells/``)."""
        target = Path(target)
        target.mkdir(parents=True, exist_ok=True)
        for key in keys:
            # a reused cell from the file that was checked; a flown one from what this run saved
            folders = ((self.validated[key],) if key in self.validated
                       else (self.folder, *self.reuse_from))
            for folder in folders:
                source = folder / f"{key}.json"
                if source.is_file() and not source.is_symlink():
                    shutil.copyfile(source, target / source.name)
                    break

    def discard(self) -> None:
        """Remove :attr:`folder` (once the study that holds its cells is written)."""
        if self.folder.is_symlink():
            return
        shutil.rmtree(self.folder, ignore_errors=True)


def _valid(doc: Any, key: str, trials: int) -> bool:
    """A cell file's document holds ``trials`` outcomes with the outcome columns, for ``key``."""
    if not isinstance(doc, dict) or doc.get("key") != key:
        return False
    settings, outcomes = doc.get("settings"), doc.get("outcomes")
    if not isinstance(settings, dict) or cell_key(settings) != key:
        return False
    return (isinstance(outcomes, list) and len(outcomes) == trials
            and all(_valid_outcome(o, i) for i, o in enumerate(outcomes)))


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _valid_outcome(o: Any, trial: int) -> bool:
    """One trial's outcome as :func:`aerodock.sweep.run.run_cell` writes it (typed columns)."""
    return (isinstance(o, dict) and tuple(o) == OUTCOME_NAMES and o["trial"] == trial
            and type(o["trial"]) is int and all(isinstance(o[k], bool) for k in _BOOLS)
            and o["abort_reason"] in _ABORT_NAMES
            and all(o[k] is None or (_is_number(o[k]) and math.isfinite(float(o[k])))
                    for k in (*_FLOATS, "capture_time_s")))


_ABORT_NAMES = frozenset(reason.name.lower() for reason in AbortReason)


def _no_constant(name: str) -> float:
    """``json.loads``'s ``parse_constant``: a cell file holds no NaN or Infinity."""
    raise ValueError(f"a sweep cell file holds no {name}")


_DIGESTS: dict[tuple[str, ...], str] = {}


def _code_digest(cfg: Config) -> str:
    """:func:`code_digest`, computed once per process and plug-in module."""
    plugin = _plugin_source(cfg)
    key = (str(plugin),)
    if key not in _DIGESTS:
        _DIGESTS[key] = code_digest(cfg)
    return _DIGESTS[key]


def _outcome(o: dict[str, Any]) -> dict[str, Any]:
    """A stored outcome as a row holds it: floats, NaN where the file has null."""
    out = dict(o)
    for k in _FLOATS:
        out[k] = math.nan if o[k] is None else float(o[k])
    if o["capture_time_s"] is not None:
        out["capture_time_s"] = float(o["capture_time_s"])
    return out


def partial_folder(out: str | Path) -> Path:
    """Where a sweep into ``out`` keeps its cells while it runs: ``.NAME.cells`` beside it."""
    out = Path(os.path.abspath(out))
    return out.parent / f".{out.name}.cells"
