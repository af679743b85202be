"""The registry of model kinds: one module per kind, each holding one :class:`Kind` record.

Training, the NumPy runtime, the ONNX export, model files, the config and the command line all
read a kind's facts here (``aerodock.learning.features`` keeps its older per-kind tables as views
of this registry). To add a kind, write ``kinds/<name>.py`` with a ``KIND`` record and its feature
map (see :mod:`aerodock.learning.kinds.base` and :mod:`aerodock.learning.kinds.template`) and
add its module's name below. Importing this package imports no array library.
"""

from __future__ import annotations

from importlib import import_module

from aerodock.learning.kinds.base import Kind

_MODULES = (
    "so2",
    "so2_ext",
    "so2_wrench",
    "so2_leader",
    "so2_pair",
    "deepsets",
    "mlp",
    "zero",
)
"""The kinds' modules, in the order the command line lists them (one line per kind)."""

REGISTRY: dict[str, Kind] = {
    kind.name: kind for kind in (import_module(f"{__name__}.{m}").KIND for m in _MODULES)
}
KINDS: tuple[str, ...] = tuple(REGISTRY)


def get_kind(name: str) -> Kind:
    """The registered kind ``name``.

    Raises:
        ValueError: unknown kind (the message lists the known ones).
    """
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown model kind {name!r} (expected one of "
                         f"{', '.join(KINDS)})") from None


def trained_kinds() -> tuple[str, ...]:
    """The kinds with a network (every kind but the zero model): what a curriculum trains."""
    return tuple(name for name, kind in REGISTRY.items() if kind.has_network)


def kinds_help() -> str:
    """The kinds' one-line summaries, for the command line's help."""
    return ", ".join(kind.summary for kind in REGISTRY.values())
