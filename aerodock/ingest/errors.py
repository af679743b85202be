"""Errors and warnings of the log readers: one line, naming the file and the problem."""

from __future__ import annotations

from pathlib import Path


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


class IngestError(ValueError):
    """A log cannot be read. The message is one line: ``FILE: problem``.

    Args:
        where: The file (or folder, or ``FILE:topic``) the problem is in.
        problem: What is wrong, in a few words.
    """

    def __init__(self, where: str | Path, problem: str) -> None:
        self.where = str(where)
        self.problem = _one_line(problem)
        super().__init__(_one_line(f"{self.where}: {self.problem}"))

    def __reduce__(self) -> tuple:
        # rebuilt from its two parts (an error raised on a worker process reaches the driver)
        return (type(self), (self.where, self.problem))


class IngestWarning(UserWarning):
    """A log was read, but something in it deserves attention (``FILE: remark``)."""


def ingest_warning(where: str | Path, remark: str) -> IngestWarning:
    """Build a one-line :class:`IngestWarning` for ``warnings.warn``."""
    return IngestWarning(_one_line(f"{where}: {remark}"))
