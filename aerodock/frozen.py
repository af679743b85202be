"""Read-only arrays, the condition for caching anything computed from an array by its identity.

The hot loop keeps numbers derived from constant arrays (a body's inertia, the rotors' offsets,
a mass) keyed by the array object: the same object every step, so one ``is`` test finds them.
An array that can be written in place may hold other numbers under the same identity, so such a
cache is trusted only for arrays nobody can write: :func:`freeze` makes the arrays the world
creates read-only, and :func:`is_frozen` tells whether a cache keyed by an array may be used
(otherwise the value is computed afresh, as it was before there was a cache).
"""

from __future__ import annotations

import numpy as np


def freeze(*arrays: np.ndarray) -> None:
    """Make ``arrays`` read-only (writing them in place then raises ``ValueError``); anything
    that is not an array is left alone."""
    for a in arrays:
        if isinstance(a, np.ndarray):
            a.flags.writeable = False


def is_frozen(a: object) -> bool:
    """Whether ``a`` is an array whose numbers cannot change: read-only, and so is every array
    it is a view of (a read-only view of a writable array changes with it). A base that is not
    an array (a buffer) counts as writable."""
    if type(a) is not np.ndarray:
        return False
    while not a.flags.writeable:
        a = a.base
        if a is None:
            return True
        if type(a) is not np.ndarray:
            return False
    return False
