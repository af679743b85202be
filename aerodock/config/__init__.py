"""Configuration: defaults from ``defaults.toml``, overridden by a user TOML file and ``--set``,
checked against each key's rule (:mod:`aerodock.config.schema`) and read as typed sections. A
plug-in field is imported only from a trusted source (:mod:`aerodock.config.plugins`)."""

from aerodock.config.loader import Config, ConfigError, load_config, parse_set
from aerodock.config.plugins import field_factory, is_field_factory, resolve_factory

__all__ = ["Config", "ConfigError", "field_factory", "is_field_factory", "load_config",
           "parse_set", "resolve_factory"]
