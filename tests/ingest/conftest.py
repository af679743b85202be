"""Fixtures for the log-reader tests (helpers live in ``ingest_helpers``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from ingest_helpers import NEURAL_SWARM_DIR, ULOG_SAMPLE


@pytest.fixture
def neural_swarm_dir() -> Path:
    """The shared real Neural-Swarm folder (skips when ``../shared`` beside the clone is absent)."""
    if not NEURAL_SWARM_DIR.is_dir():
        pytest.skip(f"shared data not found at {NEURAL_SWARM_DIR}")
    return NEURAL_SWARM_DIR


@pytest.fixture
def ulog_sample() -> Path:
    """The shared real PX4 ULog sample (read in place, never copied)."""
    if not ULOG_SAMPLE.is_file():
        pytest.skip(f"shared data not found at {ULOG_SAMPLE}")
    return ULOG_SAMPLE
