"""The bias observer's step response, measured on the controller the configuration flies."""

from __future__ import annotations

import pytest

from aerodock.control.observer_response import bias_step_response
from aerodock.control.profiles import controller_config


@pytest.mark.parametrize("tau_s", [0.25, 1.0, 2.0])
def test_time_constant_observer_rises_at_its_time_constant(cfg, tau_s):
    """A first-order estimate: 63 % at tau, 98 % at about 4 tau."""
    c = cfg.with_overrides({"control": {"bias_estimator": "time-constant",
                                        "observer_bias_tau_s": tau_s}})
    step = bias_step_response(c, seconds=10 * tau_s + 2)
    assert step.rise_63_s == pytest.approx(tau_s, rel=0.15)
    assert 3.0 * tau_s < step.rise_98_s < 5.0 * tau_s
    assert step.final_mps2 == pytest.approx(1.0, abs=0.02)


def test_freyja_as_published_rises_in_about_half_a_second(cfg):
    """The paper's flight stack: 63 % in about 0.5 s, 98 % in about 2 s, settling at 95 % of
    the step (its input shaping)."""
    step = bias_step_response(controller_config(cfg, "paper"))
    assert 0.3 < step.rise_63_s < 0.7
    assert 1.5 < step.rise_98_s < 3.0
    assert step.final_mps2 == pytest.approx(0.95, abs=0.02)

