"""How much of a follower's label no wake model can explain: a data-only ceiling on the reduction.

The labels (:mod:`aerodock.learning.labels`) are the wake plus whatever else the follower's
observed-minus-commanded acceleration holds: sensor noise, turbulence of its own, thrust-mapping
errors, and any error of the per-flight bias. Out of any plausible wake (the follower below the
leader but at least ``out_radius_m`` off its axis, so in the same role and the same flights) the
label is that non-wake part alone. Assuming the non-wake part is independent of the wake and of
position (the same mean square in the interaction region as beside it), a model that predicted
the wake exactly would leave an error of RMS ``sqrt(ms_out)``, so no wake model can cut the
interaction region's zero-model RMSE ``sqrt(ms_wake)`` by more than

    ceiling = 1 - sqrt(ms_out / ms_wake)

on the axis measured (z, the vertical, by default: the axis of the documented figures). A constant
offset in the non-wake part (a wrong bias) counts in ``ms_out`` like noise: a model of the wake
alone does not predict it. ``out_mean`` reports that offset apart.

Used by ``studies/label_floor.py`` on the real Neural-Swarm flights (docs/results/label-floor.md).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from aerodock.learning.dataset import INTERACTION_RADIUS_M, Dataset

OUT_OF_WAKE_RADIUS_M = 0.3


@dataclass(frozen=True)
class LabelFloor:
    """One group of samples' label statistics on one axis (m/s², m²/s⁴).

    Attributes:
        n_wake: samples in the interaction region (below, within ``lateral_radius_m``).
        ms_wake: mean square of the label there (the zero model's MSE).
        n_out: samples out of the wake (below, at least ``out_radius_m`` off axis).
        ms_out: mean square of the label there (the non-wake part's estimate).
        out_mean: mean of the label there (a constant offset, e.g. a wrong bias).
        ceiling: ``1 - sqrt(ms_out / ms_wake)``, the best fractional RMSE reduction a model of
            the wake alone could reach (None when either region is empty).
    """

    n_wake: int
    ms_wake: float | None
    n_out: int
    ms_out: float | None
    out_mean: float | None
    ceiling: float | None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict, with the RMS values beside the mean squares."""
        out = asdict(self)
        out["rms_wake"] = None if self.ms_wake is None else float(np.sqrt(self.ms_wake))
        out["rms_out"] = None if self.ms_out is None else float(np.sqrt(self.ms_out))
        return out


def label_floor(
    ds: Dataset,
    samples: np.ndarray | None = None,
    *,
    axis: int = 2,
    lateral_radius_m: float = INTERACTION_RADIUS_M,
    out_radius_m: float = OUT_OF_WAKE_RADIUS_M,
) -> LabelFloor:
    """The label's mean square in and out of the wake and the ceiling it puts on any wake model.

    Args:
        ds: labelled samples.
        samples: boolean (n,) mask of the samples to use (e.g. one follower's flights); all if
            None.
        axis: label axis (0 north, 1 east, 2 down).
        lateral_radius_m: the interaction region's horizontal radius, m (as in evaluation).
        out_radius_m: horizontal distance from which the follower is taken to be out of the
            wake, m; must be at least ``lateral_radius_m``.

    Raises:
        ValueError: ``out_radius_m < lateral_radius_m``, an axis not in 0..2, or a mask of
            another length.
    """
    if out_radius_m < lateral_radius_m:
        raise ValueError(f"out_radius_m ({out_radius_m}) must be >= lateral_radius_m "
                         f"({lateral_radius_m})")
    if axis not in (0, 1, 2):
        raise ValueError(f"axis must be 0, 1 or 2, not {axis}")
    keep = np.ones(ds.n, dtype=bool) if samples is None else np.asarray(samples, dtype=bool)
    if keep.shape != (ds.n,):
        raise ValueError(f"samples has shape {keep.shape}, expected ({ds.n},)")
    dp = ds.x[:, 0:3]
    horizontal = np.hypot(dp[:, 0], dp[:, 1])
    below = dp[:, 2] > 0.0
    wake = keep & ds.interaction_mask(lateral_radius_m)
    out = keep & below & (horizontal >= out_radius_m)
    label = ds.y[:, axis]
    ms_wake = float(np.mean(label[wake] ** 2)) if wake.any() else None
    ms_out = float(np.mean(label[out] ** 2)) if out.any() else None
    ceiling = (None if ms_wake is None or ms_out is None or ms_wake <= 0.0
               else float(1.0 - np.sqrt(ms_out / ms_wake)))
    return LabelFloor(n_wake=int(wake.sum()), ms_wake=ms_wake, n_out=int(out.sum()),
                      ms_out=ms_out, out_mean=float(np.mean(label[out])) if out.any() else None,
                      ceiling=ceiling)
