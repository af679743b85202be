"""`reproduce` flies the tuned controller's steps 2-4 on its second process, beside the paper's
and ours (aerodock/experiments/reproduce.py ``_tuned_job``): the row it hands back is the one
this process flies, to the bit, from the model saved on disk."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from aerodock.fileio import json_ready
from aerodock.processes import side_worker, usable_cores

MODEL = Path(__file__).resolve().parents[1] / "learning" / "data" / "kind_pins" / "so2"
"""A small so2 model kept for the kinds' pins: what it predicts does not matter here."""


@pytest.mark.skipif(usable_cores() < 2, reason="one usable core: the side jobs run here")
def test_the_tuned_row_flown_on_the_side_worker_is_the_one_flown_here(short_cfg):
    from aerodock.experiments.reproduce import _tuned_job
    from aerodock.experiments.run_size import SMOKE

    size = replace(SMOKE, tuned_row=True, hover_trials=1, moving_trials=1)
    with side_worker() as side:
        assert not side.run_here
        there = side.submit(_tuned_job, short_cfg, size, 7, MODEL)
        here, here_times = _tuned_job(short_cfg, size, 7, MODEL)
        docking, times = there()
    assert json.dumps(json_ready(docking.to_json())) == json.dumps(json_ready(here.to_json()))
    assert set(times) == set(here_times) == {"cable_study_s", "hover_s", "moving_s"}
    # it flew the size asked for: the hover's trials in each mode
    hover = docking.to_json()["hover_docking"]
    assert {mode: hover[mode]["trials"] for mode in ("with_model", "without_model")} == {
        "with_model": 1, "without_model": 1}
