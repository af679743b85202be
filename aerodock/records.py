"""Typed result records that write themselves as JSON: :class:`Record`.

A result is a frozen dataclass whose :meth:`Record.to_json` gives the JSON object a results
file holds (its fields in their declared order), so a command can return typed records while
its files keep their bytes. This module imports nothing of aerodock: every layer may use it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

Json = dict[str, Any]
"""A JSON-ready object (string keys), as the module that computes it records it."""


def json_of(value: Any) -> Any:
    """``value`` with every record in it (at any depth of dicts, lists and tuples) replaced by
    its :meth:`~Record.to_json`; every other value is returned as it is."""
    if isinstance(value, Record):
        return value.to_json()
    if isinstance(value, dict):
        return {k: json_of(v) for k, v in value.items()}
    if isinstance(value, list):
        return [json_of(v) for v in value]
    if isinstance(value, tuple):
        return tuple(json_of(v) for v in value)
    return value


@dataclass(frozen=True)
class Record:
    """Base of the records: ``to_json`` writes the fields in their declared order.

    A field named in ``_OMIT_NONE`` is left out of the JSON object when it is ``None`` (a key
    the files hold only when that part ran); one named in ``_SPLICE`` (a record or a mapping)
    has its keys written in its place instead of itself."""

    _OMIT_NONE: ClassVar[tuple[str, ...]] = ()
    _SPLICE: ClassVar[tuple[str, ...]] = ()

    def to_json(self) -> Json:
        """The JSON object of this record (the same keys, in the same order, as the files)."""
        out: Json = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None and f.name in self._OMIT_NONE:
                continue
            value = json_of(value)
            if f.name in self._SPLICE:
                out.update(value or {})
            else:
                out[f.name] = value
        return out
