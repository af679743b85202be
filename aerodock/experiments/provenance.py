"""Where a result came from: the resolved configuration, aerodock's version and, in a git
checkout, its commit. Recorded in ``results.json`` so that a run can be repeated from its file
(``tools/same_numbers.py`` leaves these fields out when it compares numbers: :data:`KEYS`)."""

from __future__ import annotations

import subprocess
from importlib import metadata
from pathlib import Path
from typing import Any

from aerodock.config import Config

KEYS = ("config", "config_source", "version", "git_commit", "git_dirty")
"""The provenance fields :func:`provenance` returns (none of them a result)."""

_GIT_TIMEOUT_S = 10.0


def code_version() -> str:
    """aerodock's version: ``aerodock.__version__`` if it has one, else the installed
    distribution's, else ``"unknown"``."""
    import aerodock

    version = getattr(aerodock, "__version__", None)
    if isinstance(version, str) and version:
        return version
    try:
        return metadata.version("aerodock")
    except metadata.PackageNotFoundError:
        return "unknown"


def _git(root: Path, *args: str) -> str | None:
    try:
        done = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True,
                              timeout=_GIT_TIMEOUT_S, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() if done.returncode == 0 else None


def git_state(root: Path | None = None) -> tuple[str | None, bool | None]:
    """``(commit, dirty)`` of the git checkout holding aerodock's source (``root``: the folder
    above the package); ``(None, None)`` outside a checkout or without git. ``dirty``: tracked
    files differ from the commit."""
    if root is None:
        import aerodock

        root = Path(aerodock.__file__).resolve().parent.parent
    if not (root / ".git").exists():  # a folder (a clone) or a file (a worktree)
        return None, None
    commit = _git(root, "rev-parse", "HEAD")
    if commit is None:
        return None, None
    status = _git(root, "status", "--porcelain", "--untracked-files=no")
    return commit, (None if status is None else bool(status))


def provenance(cfg: Config) -> dict[str, Any]:
    """The fields of :data:`KEYS` for a run of ``cfg``: its resolved values (every key, what
    ``--config`` and ``--set`` made of the defaults), where it came from, the code's version
    and commit (None outside a git checkout)."""
    commit, dirty = git_state()
    return {"config": cfg.to_dict(), "config_source": cfg.source, "version": code_version(),
            "git_commit": commit, "git_dirty": dirty}
