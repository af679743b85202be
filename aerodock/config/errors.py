"""The configuration's one error type (its own module, so that the loader and the plug-in
checks share it)."""

from __future__ import annotations


class ConfigError(ValueError):
    """A configuration value is invalid; the message names the key and the file."""
