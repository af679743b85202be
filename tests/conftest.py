"""Shared fixtures: the default config, and where the shared real data lives (if present)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from aerodock.config import load_config

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session")
def cfg():
    """The default configuration."""
    return load_config()


@pytest.fixture
def rng():
    """A fixed-seed generator."""
    return np.random.default_rng(12345)


@pytest.fixture
def shared_data():
    """``shared_data(*parts)``: a path into ../shared/data; skips when absent (a user's clone)."""

    def get(*parts: str) -> Path:
        path = SHARED.joinpath("data", *parts)
        if not path.exists():
            pytest.skip(f"shared data not present: {path}")
        return path

    return get
