"""Kind ``"zero"``: no downwash compensation (the "without model" baseline): always 0."""

from __future__ import annotations

from aerodock.learning.kinds.base import Kind

KIND = Kind(name="zero", summary="zero (predicts nothing)", has_network=False)
