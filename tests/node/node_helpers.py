"""Helpers of the node tests (the model and flight builders live in aerodock.node.bench)."""

from __future__ import annotations

from aerodock.node.bench import orbit_log, random_model

__all__ = ["orbit_log", "random_model"]
