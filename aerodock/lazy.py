"""A package's names that load their modules on first use (PEP 562's module ``__getattr__``):
``aerodock.control`` and ``aerodock.mission`` export names whose modules import the compiled
world (numba), which a command that refuses its input, or ``aerodock --help``, should not wait
for."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_names(package: str, homes: Mapping[str, str]) -> Callable[[str], Any]:
    """The module ``__getattr__`` of ``package``: each name of ``homes`` is read from the module
    named beside it, imported on first use; any other name raises :class:`AttributeError`."""

    def __getattr__(name: str) -> Any:
        if name not in homes:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(homes[name]), name)

    return __getattr__
