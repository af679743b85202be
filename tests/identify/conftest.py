"""Fixtures for the tests of wake identification: the wake the synthetic flights are made with
(see ``wake_synth``)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def truth() -> dict[str, float]:
    """The default world's wake (the fit to the real flights) as the known parameters of the
    synthetic wake flights (``wake_synth``)."""
    from aerodock.config import load_config
    from aerodock.identify.wake_fit import FITTED_PARAMS

    params = load_config().downwash.params
    return {k: float(params[k]) for k in FITTED_PARAMS}
