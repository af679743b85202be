"""Which code a config may name, and the one place that imports it.

A config's ``[downwash] field = "package.module:factory"`` names code: importing the module runs
it, and so does calling the factory. A file received from someone else must not run code
unless its reader has said that the code is trusted, so :func:`resolve_factory` imports a
module only when one of these holds, and refuses in one line before any import otherwise:

- it is aerodock's own (``aerodock`` or a module below it): the built-in fields;
- an installed package declares ``package.module:factory`` in the entry-point group
  :data:`ENTRY_POINT_GROUP` (``aerodock.fields``); reading that metadata imports nothing;
- the user trusts it: the environment variable :data:`TRUST_ENV` (comma-separated module
  prefixes, ``*`` for every module) or ``--trust-plugin MODULE`` on the command line, given
  here as ``trusted``. A prefix ``pkg`` trusts ``pkg`` and ``pkg.sub``; an entry of the form
  ``module:factory`` trusts exactly that factory.

The named object must then be a field factory (:func:`is_field_factory`) before anything calls
it: a class whose instances have ``reset`` and ``acceleration``, or a callable marked with
:func:`field_factory`. A function such as ``os:system`` is neither and is refused unbuilt.
"""

from __future__ import annotations

import importlib
import inspect
import os
import re
from collections.abc import Callable, Iterable
from importlib import metadata
from typing import Any, TypeVar

from aerodock.config.errors import ConfigError

ENTRY_POINT_GROUP = "aerodock.fields"
"""Entry-point group in which an installed package declares its fields (``name = "mod:attr"``)."""

TRUST_ENV = "AERODOCK_TRUST_PLUGINS"
"""Environment variable: comma-separated module prefixes whose fields a config may name."""

FACTORY_MARK = "__aerodock_field_factory__"
"""Attribute :func:`field_factory` sets to True on a function that builds a field."""

_FIELD_PATH = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*")

F = TypeVar("F", bound=Callable[..., Any])


class PluginError(ConfigError):
    """A field path that is malformed, untrusted, missing or not a field factory."""


def field_factory(fn: F) -> F:
    """Mark a function as a field factory (it returns a downwash field), so that a config may
    name it; a class with ``reset`` and ``acceleration`` needs no mark."""
    setattr(fn, FACTORY_MARK, True)
    return fn


def is_field_factory(obj: Any) -> bool:
    """A class whose instances have ``reset`` and ``acceleration``, or a callable marked with
    :func:`field_factory`. Nothing is called to decide."""
    if inspect.isclass(obj):
        return all(callable(inspect.getattr_static(obj, name, None))
                   for name in ("reset", "acceleration"))
    return callable(obj) and inspect.getattr_static(obj, FACTORY_MARK, False) is True


def env_trusted() -> tuple[str, ...]:
    """The entries of :data:`TRUST_ENV` (empty when unset)."""
    return tuple(p.strip() for p in os.environ.get(TRUST_ENV, "").split(",") if p.strip())


def declared_fields() -> frozenset[str]:
    """The ``module:attr`` values installed packages declare in :data:`ENTRY_POINT_GROUP`."""
    try:
        points = metadata.entry_points(group=ENTRY_POINT_GROUP)
    except Exception:  # noqa: BLE001 - broken metadata of some package: declares nothing
        return frozenset()
    return frozenset(re.sub(r"\s+", "", ep.value.split("[", 1)[0]) for ep in points)


def _trusted_by(path: str, entries: Iterable[str]) -> bool:
    module = path.partition(":")[0]
    for entry in entries:
        if entry == "*" or entry == path:
            return True
        if ":" not in entry and (module == entry or module.startswith(entry + ".")):
            return True
    return False


def is_trusted(path: str, trusted: Iterable[str] = ()) -> bool:
    """May a config name ``path``? aerodock's own, declared by an installed package, or trusted
    by ``trusted`` or :data:`TRUST_ENV` (see the module docstring). Imports nothing."""
    return (_trusted_by(path, ("aerodock",)) or _trusted_by(path, (*trusted, *env_trusted()))
            or path in declared_fields())


def resolve_factory(path: str, source: str = "config", trusted: Iterable[str] = ()) -> Any:
    """Import ``"package.module:attr"`` if it may be named (:func:`is_trusted`) and return the
    attribute, checked to be a field factory (:func:`is_field_factory`); nothing is called.

    Raises:
        PluginError: a malformed path; an untrusted module (refused before it is imported); a
            module that cannot be imported (whatever it raises, including ``SystemExit``); a
            missing attribute; an object that is not a field factory.
    """
    key = "'downwash.field'"
    if not isinstance(path, str) or not _FIELD_PATH.fullmatch(path):
        raise PluginError(f"{source}: {key} must look like 'package.module:factory', got {path!r}")
    module_name, _, attr = path.partition(":")
    if not is_trusted(path, trusted):
        raise PluginError(
            f"{source}: {key} names code outside aerodock ({path}) and a config runs no code "
            f"unless you trust it: --trust-plugin {module_name} or {TRUST_ENV}={module_name} "
            "(docs/plugins.md)")
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise PluginError(
            f"{source}: {key} plug-in module {module_name!r} cannot be imported ({err})"
        ) from None
    except (Exception, SystemExit) as err:  # a plug-in's own code failed while importing
        raise PluginError(
            f"{source}: {key} plug-in module {module_name!r} failed on import "
            f"({type(err).__name__}: {err})"
        ) from None
    try:
        factory = getattr(module, attr)
    except AttributeError:
        raise PluginError(
            f"{source}: {key} plug-in {module_name!r} has no attribute {attr!r}"
        ) from None
    except (Exception, SystemExit) as err:  # a module __getattr__ that fails
        raise PluginError(f"{source}: {key} plug-in {path} failed on lookup "
                          f"({type(err).__name__}: {err})") from None
    if not is_field_factory(factory):
        raise PluginError(
            f"{source}: {key} {path} is not a field factory (a class with reset(n, rng) and "
            "acceleration(leader, follower, dt), or a function marked "
            "@aerodock.downwash.field_factory); it was not called")
    return factory
