"""The probability of the paper's own counts under a measured docking rate."""

from __future__ import annotations

import pytest
from scipy.stats import binom

from aerodock.experiments.paper_counts import (
    binomial_tail,
    cable_pattern_probability,
    paper_outcome_probabilities,
)


@pytest.mark.parametrize("rate", [0.0, 0.27, 0.5, 0.8, 0.95, 1.0])
def test_binomial_tail_is_on_the_papers_side(rate):
    """8 of 10: P(X >= 8) when the rate expects fewer, P(X <= 8) when it expects more."""
    expected = binom.sf(7, 10, rate) if 8 >= 10 * rate else binom.cdf(8, 10, rate)
    assert binomial_tail(8, 10, rate) == pytest.approx(expected, abs=1e-12)


def test_the_issues_figure_27_percent_makes_8_of_10_improbable():
    assert binomial_tail(8, 10, 0.27) < 0.001
    assert binomial_tail(0, 10, 0.27) == pytest.approx(0.73**10)


def test_cable_pattern_takes_each_offset_at_its_own_rate():
    rates = [1.0, 0.9, 0.5, 1.0, 0.8, 1.0]
    assert cable_pattern_probability(rates, True)["probability"] == pytest.approx(0.36)
    assert cable_pattern_probability(rates, False)["probability"] == 0.0
    assert not cable_pattern_probability(rates, False)["consistent"]


def test_outcomes_are_judged_from_campaign_summaries():
    cable = {"with_model": [{"success_rate": 1.0}] * 6,
             "without_model": [{"success_rate": 0.1}] * 6}
    out = paper_outcome_probabilities({"docked": 72, "trials": 80},
                                      {"docked": 11, "trials": 80}, cable)
    assert out["hover_with_model"]["consistent"]  # 90 % docks: 8/10 is plausible
    assert out["hover_without_model"]["probability"] == pytest.approx((1 - 11 / 80) ** 10)
    assert out["cable_with_model"]["probability"] == 1.0
    assert out["cable_without_model"]["probability"] == pytest.approx(0.9**6)
    assert out["all_consistent"]
    out = paper_outcome_probabilities({"docked": 54, "trials": 200},
                                      {"docked": 0, "trials": 200}, None)
    assert not out["hover_with_model"]["consistent"] and not out["all_consistent"]
    assert "cable_with_model" not in out
