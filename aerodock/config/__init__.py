"""Configuration: defaults from ``defaults.toml``, overridden by a user TOML file, checked against
each key's rule (:mod:`aerodock.config.schema`) and read as typed sections."""

from aerodock.config.loader import Config, ConfigError, load_config, resolve_factory

__all__ = ["Config", "ConfigError", "load_config", "resolve_factory"]
