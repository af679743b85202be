"""Fault campaigns: one docking campaign per injected fault, beside a baseline without faults.

Each row counts the trials the fault struck by how each ended, one outcome per trial (the
outcome columns add up to the trials struck, :data:`OUTCOME_COLUMNS`):

- docked;
- missed: the gate closed without the bar (empty, or the bar slipped through before it shut);
- not held: the follower believed the gate shut, found itself not held and backed off, the gate
  never having closed on anything (a jammed servo that does not report its position);
- safe aborts: aborted with no clearance violation, no collision and no numerical failure;
- unsafe aborts: aborted with one of those;
- other: none of these (a capture that ended in a collision, or a trial still undecided).

Beside them, flags a trial may carry whatever its outcome (:data:`FLAG_COLUMNS`): clearance
violations, collisions (rotor strikes, ground) and a non-finite state (NaN).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.mission import CampaignResult, MissionSpec, run_campaign
from aerodock.mission.faults import Fault

OUTCOME_COLUMNS = (
    ("docked", "docked"),
    ("missed_or_slipped", "missed (gate closed empty)"),
    ("not_held", "not held (gate never shut)"),
    ("safe_aborts", "safe aborts"),
    ("unsafe_aborts", "unsafe aborts"),
    ("other", "other"),
)
"""(row key, table header) of each way a struck trial can end; one per trial."""

FLAG_COLUMNS = (
    ("clearance_violations", "clearance violations"),
    ("collisions", "collisions"),
    ("nan_trials", "NaN"),
)
"""(row key, table header) of what a trial may also have done, whatever its outcome."""


def trial_outcomes(res: CampaignResult) -> dict[str, np.ndarray]:
    """(n,) bool per key of :data:`OUTCOME_COLUMNS`: exactly one is true for every trial."""
    docked = res.success
    collided = res.rotor_strike | res.ground_contact
    aborted = res.aborted & ~docked
    safe = aborted & ~res.clearance_violation & ~collided & ~res.nan_state
    missed = (res.missed | res.slipped) & ~docked & ~aborted
    not_held = res.sensed_missed & ~missed & ~docked & ~aborted
    out = {"docked": docked, "missed_or_slipped": missed, "not_held": not_held,
           "safe_aborts": safe, "unsafe_aborts": aborted & ~safe}
    out["other"] = ~np.any(list(out.values()), axis=0)
    return out


def fault_campaign(cfg: Config, faults: list[Fault], trials: int, seed: int,
                   compensation: Compensation, predictor: AccelPredictor | None,
                   progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """One row per fault (and a first row without faults); see the module docstring.

    A row holds ``fault``, ``kind``, ``trials``, ``struck``, the counts of
    :data:`OUTCOME_COLUMNS` and :data:`FLAG_COLUMNS` over the struck trials, ``aborts`` (all
    aborts), ``sensed_misses`` (every trial that found itself not held, whatever the gate did)
    and ``abort_reasons``.
    """
    rows = []
    for fault in [None, *faults]:
        name = "no fault" if fault is None else fault.name
        if progress is not None:
            progress(name)
        spec = MissionSpec(trials=trials, offset_m=0.36, compensation=compensation, seed=seed,
                           faults=() if fault is None else (fault,))
        res = run_campaign(cfg, spec, predictor)
        hit = res.fault_hit
        row: dict[str, Any] = {"fault": name, "kind": None if fault is None else fault.kind,
                               "trials": trials, "struck": int(hit.sum())}
        row.update({key: int((ended & hit).sum()) for key, ended in trial_outcomes(res).items()})
        row.update({
            "aborts": int((res.aborted & hit).sum()),
            "sensed_misses": int((res.sensed_missed & hit).sum()),
            "clearance_violations": int((res.clearance_violation & hit).sum()),
            "collisions": int(((res.rotor_strike | res.ground_contact) & hit).sum()),
            "nan_trials": int((res.nan_state & hit).sum()),
            "abort_reasons": res.summary()["abort_reasons"],
        })
        rows.append(row)
    return rows


def table_cells(row: dict[str, Any]) -> list[str]:
    """One row of the fault table as text, in the order of :func:`table_headers`."""
    return ([row["fault"], f"{row['struck']}/{row['trials']}"]
            + [str(row[key]) for key, _ in (*OUTCOME_COLUMNS, *FLAG_COLUMNS)])


def table_headers() -> list[str]:
    """The fault table's column headers: the fault, the trials struck, every outcome a trial can
    end in, then the flags."""
    return ["fault", "struck"] + [head for _, head in (*OUTCOME_COLUMNS, *FLAG_COLUMNS)]


def rows_markdown(rows: list[dict[str, Any]]) -> str:
    """The fault table as Markdown (as in docs/research-tools.md)."""
    heads = table_headers()
    lines = ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    lines += ["| " + " | ".join(table_cells(r)) + " |" for r in rows]
    return "\n".join(lines)
