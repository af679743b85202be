"""TOML text of a configuration's values (Python's ``tomllib`` reads TOML but does not write it):
what :meth:`aerodock.config.Config.to_toml` returns and a child process reads back."""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from typing import Any

from aerodock.config.errors import ConfigError


def dumps_toml(table: Mapping[str, Any]) -> str:
    """``table`` (nested tables of booleans, numbers, strings and lists) as TOML text.

    Raises:
        ConfigError: a value TOML cannot hold (None, an object).
    """
    return _toml_tables(table, "")


def _toml_string(text: str) -> str:
    # JSON's escapes are TOML's, but not its surrogate pairs: non-ASCII stays as it is; DEL, raw
    # in JSON, is escaped as TOML wants.
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _toml_key(key: Any) -> str:
    key = str(key)
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else _toml_string(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)  # inf and nan are TOML too
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise ConfigError(f"cannot write {value!r} as TOML")


def _toml_tables(table: Mapping[str, Any], prefix: str) -> str:
    """``table``'s plain keys, then each sub-table as ``[prefix.key]``."""
    lines = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in table.items()
             if not isinstance(v, Mapping)]
    text = "\n".join(lines) + ("\n" if lines else "")
    for key, value in table.items():
        if isinstance(value, Mapping):
            name = f"{prefix}{_toml_key(key)}"
            text += f"\n[{name}]\n" + _toml_tables(value, f"{name}.")
    return text
