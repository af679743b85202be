"""Strict JSON: :func:`dumps_json` refuses ``NaN``/``Infinity`` (other tools could not parse
them), naming the key; every ``--json`` prints through it and :func:`write_json` writes every JSON
file with it. :func:`json_ready` is the one policy for a non-finite number that means a figure is
missing (a model that could not be scored, a benchmark part that did not run): it becomes
``null``. Used where such gaps are legitimate (``results.json``, ``aerodock bench``,
``aerodock ingest``); anywhere else a NaN is a bug and :func:`dumps_json` refuses it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio.writes import atomic_open


def json_default(obj: Any) -> Any:
    """``json.dumps(default=...)`` for NumPy scalars and arrays and paths."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _first_non_finite(obj: Any, where: str = "") -> str | None:
    if isinstance(obj, float | np.floating):
        return None if math.isfinite(obj) else where or "value"
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fc" and not np.all(np.isfinite(obj)):
            return where or "array"
        return None
    if isinstance(obj, dict):
        items = obj.items()
    elif isinstance(obj, list | tuple):
        items = enumerate(obj)
    else:
        return None
    for key, value in items:
        found = _first_non_finite(value, f"{where}.{key}" if where else str(key))
        if found:
            return found
    return None


def json_ready(obj: Any) -> Any:
    """A JSON-ready copy of ``obj`` in which a non-finite number means "missing": ``null``.

    NaN and infinities (Python or NumPy floats, in arrays too) become ``None``; arrays become
    lists and NumPy scalars Python numbers, tuples lists, and dictionary keys strings. For
    documents where a missing figure is legitimate; :func:`dumps_json` alone refuses them.
    """
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_ready(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_ready(obj.tolist())
    if isinstance(obj, np.generic):
        return json_ready(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def dumps_json(obj: Any, indent: int | None = 2) -> str:
    """Strict JSON text for ``obj`` (NumPy values and paths allowed).

    Raises:
        ValueError: ``obj`` holds a NaN or an infinity (JSON has no such numbers); the message
            names the first such key.
    """
    try:
        return json.dumps(obj, indent=indent, default=json_default, allow_nan=False)
    except ValueError:
        where = _first_non_finite(obj) or "a value"
        raise ValueError(f"result has a non-finite number at '{where}'; refusing to print "
                         "invalid JSON") from None


def write_json(path: str | Path, obj: Any, final_newline: bool = False) -> Path:
    """Write ``obj`` to ``path`` as indented, strict JSON (:func:`dumps_json`), atomically.

    Raises:
        ValueError: ``obj`` holds a NaN or an infinity (pass it through :func:`json_ready`
            first where a missing figure is legitimate); nothing is written.
        OSError: ``path`` cannot be written.
    """
    text = dumps_json(obj) + ("\n" if final_newline else "")
    with atomic_open(path, "w") as fh:
        fh.write(text)
    return Path(path)
