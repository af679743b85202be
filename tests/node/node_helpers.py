"""Helpers of the node tests (the model and flight builders live in aerodock.bench.node)."""

from __future__ import annotations

from aerodock.bench.node import orbit_log, random_model

__all__ = ["orbit_log", "random_model"]
