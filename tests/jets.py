"""The default jet for tests: :class:`RoundJetField` with the shipped defaults' every parameter
(``defaults.toml``, their one home), some of them overridden."""

from __future__ import annotations

from typing import Any

from aerodock.config import load_config
from aerodock.downwash import field_kwargs
from aerodock.downwash.jet import RoundJetField


def default_jet(**overrides: Any) -> RoundJetField:
    """The default jet between the default vehicles, with ``overrides`` (any of its keyword
    arguments)."""
    return RoundJetField(**{**field_kwargs(load_config(), RoundJetField), **overrides})
