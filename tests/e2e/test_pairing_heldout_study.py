"""``studies/pairing_heldout.py``, the real-flight table of docs/results/deep-sets.md, at its
``--smoke`` size on a few real flights (each follower below the other in one flight of the
heterogeneous pair's training and test flights): every kind asked for, ``deepsets`` among
them, gets its row, and the row's figures are the library's ``train_model`` and ``evaluate`` on
the flights of one follower (chosen here by the flights' names, not by the study's helper)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from aerodock.cli.app import run
from aerodock.learning.datafiles import load_data_paths
from aerodock.learning.evaluate import evaluate

pytest.importorskip("torch")

STUDIES = Path(__file__).resolve().parents[2] / "studies"
VEHICLES = ("--vehicle", "cf51=small,cf101=large")


def _ingest(out: Path, files: list[Path], *extra: str) -> str:
    assert files, out
    assert run(["ingest", "--format", "neural-swarm", *map(str, files), *extra,
                "--out", str(out)]) == 0
    return str(out)


def _reduction_pct(predictor, ds) -> float:
    ev = evaluate(predictor, ds)["interaction"]
    return 100 * (1 - ev["model"]["rmse_mps2"]["z"] / ev["zero"]["rmse_mps2"]["z"])


def test_the_heldout_study_gives_deepsets_its_row(tmp_path, shared_data, monkeypatch, capsys):
    from aerodock.learning.train import train_model

    ss = shared_data("neural-swarm", "swap_ss")
    sl = shared_data("neural-swarm", "swap_sl_2020-06-19")
    paths = [_ingest(tmp_path / "ss_train.npz", sorted(ss.glob("cf5?_00.csv"))),
             _ingest(tmp_path / "sl_train.npz", sorted(sl.glob("cf*_0[01].csv")), *VEHICLES),
             _ingest(tmp_path / "ss_test.npz", sorted(ss.glob("cf5?_05.csv"))),
             _ingest(tmp_path / "sl_test.npz", sorted(sl.glob("cf*_0[89].csv")), *VEHICLES)]
    monkeypatch.syspath_prepend(str(STUDIES))
    import pairing_heldout

    capsys.readouterr()
    assert pairing_heldout.main([*paths, "deepsets", "so2", "--smoke"]) == 0
    out = capsys.readouterr().out
    assert "| model, seeds 0 | ss 05-06 | small under large | large under small |" in out
    rows = {m[1]: [float(v) for v in re.findall(r"(-?\d+\.\d) % \(", m[2])]
            for m in re.finditer(r"^\| `([\w-]+)` \|(.*)\|$", out, re.M)}
    assert set(rows) == {"deepsets", "so2"} and all(len(v) == 3 for v in rows.values())

    # the deepsets row, recomputed: seed 0 at the smoke size on the same training flights
    fit = load_data_paths(paths[:2])
    predictor = train_model("deepsets", fit, seed=0,
                            max_epochs=pairing_heldout.SMOKE_EPOCHS).predictor()
    assert predictor.kind == "deepsets" and predictor.needs_wake_scales
    sl_test = load_data_paths(paths[3:])
    names = np.array(sl_test.flight_names)[sl_test.flight_id]
    want = [_reduction_pct(predictor, load_data_paths(paths[2:3]))]
    for follower in ("cf51", "cf101"):  # small under large, then large under small
        want.append(_reduction_pct(predictor,
                                   sl_test.subset(np.char.endswith(names, "_" + follower))))
    np.testing.assert_allclose(rows["deepsets"], want, atol=0.051)
    assert want[0] > 0  # even at this size, on the same pair's held-out flight
