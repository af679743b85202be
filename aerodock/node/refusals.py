"""The node's account of the messages it refused, bounded however long it runs (its
diagnostics' ``refused_total``, ``refused_recent`` and one count per kind of reason)."""

from __future__ import annotations

import re
from collections import deque

MAX_REFUSAL_KINDS = 16
"""Kinds of refusal counted apart (per vehicle and reason, numbers left out); the rest count
under ``"other"``. The node's account of refused messages stays this size however long it runs
and whatever its inputs send."""
RECENT_REFUSALS = 5
"""Refusals kept word for word (the newest)."""
MAX_REASON_CHARS = 200
"""A kept reason is cut to this many characters."""
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|[-+]?\b(?:nan|inf)\b",
                     re.IGNORECASE)


def refusal_kind(reason: str) -> str:
    """A reason with its numbers as ``#`` (``"stamp frozen at 12.3"`` -> ``"stamp frozen at
    #"``), cut to :data:`MAX_REASON_CHARS`: what :class:`RefusalLog` counts by."""
    return _NUMBER.sub("#", reason)[:MAX_REASON_CHARS]


class RefusalLog:
    """Bounded bookkeeping of the messages the node refused, for its diagnostics.

    :meth:`record` counts each refusal under ``"role: kind"`` (:func:`refusal_kind`; after
    :data:`MAX_REFUSAL_KINDS` kinds, new ones count as ``"other"``) and keeps the last
    :data:`RECENT_REFUSALS` reasons word for word (cut to :data:`MAX_REASON_CHARS`). Memory is
    bounded whatever the messages are and however many arrive.
    """

    def __init__(self) -> None:
        self.total = 0
        self.counts: dict[str, int] = {}
        self.recent: deque[str] = deque(maxlen=RECENT_REFUSALS)
        self._values: dict[str, str] | None = None

    def record(self, role: str, reason: str) -> None:
        """Count one refused message of ``role`` (``"leader"``/``"follower"``) for ``reason``."""
        kind = f"{role}: {refusal_kind(reason)}"
        if kind not in self.counts and len(self.counts) >= MAX_REFUSAL_KINDS:
            kind = "other"
        self.counts[kind] = self.counts.get(kind, 0) + 1
        self.total += 1
        self.recent.append(f"{role}: {reason}"[:MAX_REASON_CHARS])
        self._values = None

    def values(self) -> dict[str, str]:
        """The diagnostics' entries: ``refused_total``, ``refused_recent`` (the kept reasons,
        oldest first, ``" | "``-joined) and one ``"refused <role>: <kind>"`` count per kind."""
        if self._values is None:
            self._values = {"refused_total": str(self.total),
                            "refused_recent": " | ".join(self.recent),
                            **{f"refused {kind}": str(n) for kind, n in self.counts.items()}}
        return self._values
