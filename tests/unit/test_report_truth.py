"""The quick report says what happened: a tie is not a dock, the paper's counts as the paper
gives them, one seed said as one seed, every figure captioned with its labels inside the frame."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from aerodock.experiments import report
from aerodock.experiments.cable_study import offset_result
from aerodock.experiments.paper_counts import paper_outcome_probabilities


@pytest.mark.parametrize("docked, attempts, result", [
    (1, 2, "miss"), (2, 2, "dock"), (0, 2, "miss"), (1, 1, "dock"), (0, 1, "miss"),
    (2, 4, "miss"), (3, 4, "dock"), (5, 10, "miss"), (6, 10, "dock")])
def test_an_offset_docks_only_when_most_of_its_attempts_docked(docked, attempts, result):
    assert offset_result(docked, attempts) == result


def test_the_papers_cable_counts_are_quoted_as_the_paper_gives_them():
    """Three offsets flown (a quick run): the paper's counts stay 6/6 and 0/6 (its table has six
    offsets), and the record says how many of them were flown."""
    cable = {"with_model": [{"success_rate": 0.5}] * 3,
             "without_model": [{"success_rate": 0.5}] * 3}
    out = paper_outcome_probabilities({"docked": 8, "trials": 10}, {"docked": 0, "trials": 10},
                                      cable)
    assert out["cable_with_model"]["paper"] == "6/6"
    assert out["cable_without_model"]["paper"] == "0/6"
    assert out["cable_with_model"]["probability"] == pytest.approx(0.125)
    assert "only 3 of the paper's 6 offsets" in out["cable_with_model"]["note"]
    lines = "\n".join(report._paper_counts_markdown(out))
    assert "| 6/6 |" in lines and "| 0/6 |" in lines and "3/3" not in lines
    assert "3 of the paper's 6 offsets flown" in lines


def _se(seeds: list[int]) -> dict:
    model = {"rmse_all_mean": [0.5], "rmse_all_sd": [0.0 if len(seeds) == 1 else 0.1],
             "rmse_interaction_mean": [0.9], "rmse_interaction_sd": [0.2]}
    return {"seeds": seeds, "minutes": [0.5], "models": {"so2": model},
            "zero": {"all": 1.0, "interaction": 2.0}}


def test_one_seed_is_said_as_one_seed_not_as_a_zero_spread():
    one = "\n".join(report._se_table(_se([0]), "Sample efficiency, simulated"))
    assert "one seed" in one and "±" not in one and "sd" not in one
    assert "| 0.5 | all | 0.500 | 1.000 |" in one
    three = "\n".join(report._se_table(_se([0, 1, 2]), "Sample efficiency, simulated"))
    assert "mean ± sd over seeds" in three and "0.500 ± 0.100" in three


def test_every_figure_the_report_can_list_has_a_caption():
    source = Path(report.__file__).read_text()
    names = set(re.findall(r'"(\w+\.(?:png|gif))"', source))
    assert {"observer_bandwidth.png", "cable_trajectories.png", "hover_docking.gif"} <= names
    assert names <= set(report.FIGURE_CAPTIONS), names - set(report.FIGURE_CAPTIONS)
    md = report.figures_markdown(["figures/cable_trajectories.png", "figures/new_one.png"])
    text = "\n".join(md)
    assert f"*Figure 1: {report.FIGURE_CAPTIONS['cable_trajectories.png']}*" in text
    assert "![Figure 1](figures/cable_trajectories.png)" in text
    assert "*Figure 2: new_one.png*" in text  # a figure without a caption is still named


def test_observer_bandwidth_labels_stay_inside_the_frame(monkeypatch, tmp_path):
    drawn = []
    monkeypatch.setattr(report, "_save", lambda fig, path: drawn.append(fig) or path)
    rate = {"success_rate": 0.5, "success_wilson95": [0.3, 0.7]}
    points = [{"rise_63_s": tau, "observer": name, "label": name, "hover_with_model": rate,
               "hover_without_model": rate}
              for tau, name in ((0.5, "freyja"), (0.25, "tau"), (4.0, "tau"))]
    assert report.fig_observer_bandwidth({"observer_bandwidth": points}, tmp_path) is not None
    fig = drawn[0]
    renderer = fig.canvas.get_renderer()
    fig.draw(renderer)
    frame = fig.bbox
    for ax in fig.axes:  # the axes with their labels, ticks, title and legend, as drawn
        box = ax.get_tightbbox(renderer)
        assert (box.x0 >= frame.x0 - 0.5 and box.x1 <= frame.x1 + 0.5
                and box.y0 >= frame.y0 - 0.5 and box.y1 <= frame.y1 + 0.5), (box, frame)


def test_a_saved_figure_takes_in_a_label_longer_than_its_layout(tmp_path):
    """No layout at all and an x label far wider than the axes: the PNG grows to hold it."""
    import struct

    from aerodock.plots import _plt, _save

    fig, ax = _plt().subplots(figsize=(3.0, 2.0))
    ax.set_xlabel("a label that is much, much longer than a figure three inches wide can hold")
    path = _save(fig, tmp_path / "long.png")
    width_px = struct.unpack(">I", path.read_bytes()[16:20])[0]  # the PNG header's width
    assert width_px > 3.0 * 110 * 1.3
