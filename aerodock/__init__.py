"""aerodock: docking two multirotors in close proximity with learnt downwash models.

``aerodock.__version__`` is the installed distribution's version (``importlib.metadata``) or,
in a source checkout that is not installed, the version in its ``pyproject.toml``.
"""

from __future__ import annotations


def _version() -> str:
    """The installed package's version, else the source tree's ``pyproject.toml``'s, else
    ``"unknown"`` (a copy of the package without either)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("aerodock")
    except PackageNotFoundError:
        pass
    import tomllib
    from pathlib import Path

    pyproject = Path(__file__).resolve().parent.parent / "pyproject.toml"
    try:
        project = tomllib.loads(pyproject.read_text(encoding="utf-8")).get("project", {})
    except (OSError, ValueError):
        return "unknown"
    ours = project.get("name") == "aerodock" and "version" in project
    return str(project["version"]) if ours else "unknown"


__version__: str = _version()
