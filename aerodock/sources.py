"""A digest of aerodock's own sources: what "the same code" means where numbers are reused
(compiled kernels, finished sweep cells) and a version number is not enough (an editable
install keeps one across commits)."""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from pathlib import Path

ROOT = Path(__file__).resolve().parent
"""The package's folder."""


def sources_digest(containing: bytes | None = None, extra: Iterable[bytes] = ()) -> str:
    """SHA-256 (hex) over the package's modules, each by its path and bytes, in path order (only
    those whose text holds ``containing``, if given), then the ``extra`` byte strings."""
    digest = hashlib.sha256()
    for path in sorted(ROOT.rglob("*.py")):
        text = path.read_bytes()
        if containing is None or containing in text:
            digest.update(str(path.relative_to(ROOT)).encode() + b"\0")
            digest.update(text)
    for more in extra:
        digest.update(b"\0" + more)
    return digest.hexdigest()
