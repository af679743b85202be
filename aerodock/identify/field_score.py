"""A wake (a ``field fit`` or a world's config) scored on any flights, pairing by pairing.

What ``aerodock field score`` prints: per pairing of leader and follower vehicle, the world's
figures against the flights' (world over flights minus one, signed):

- the mean vertical acceleration directly below the leader per separation bin (the worst bin);
- the lateral half-magnitude radius;
- the vertical and lateral turbulence sd near the axis, above the labels' noise;
- the inward torque on the follower per 2 cm bin of horizontal offset, 4-10 cm off the axis
  (where the logs carry the motors' torque), as the world's over the flights';
- beside them, not a target: the mean vertical acceleration in a ring beyond the jet's edge
  (3.5-6 leader equivalent radii off the axis), world and flights, where the real flights are
  pushed up.

Beside each, the flights' own reference: the pairing's flights dealt alternately into two
halves, one half's real figure taken as the prediction of the other's (the same error figures).
It is how far two sets of real flights of one pairing disagree: no wake can be expected to come
closer to a new flight than that. The scores read :func:`aerodock.identify.wake_score.score_wake`
and :func:`aerodock.identify.wake_torque.torque_profile`; the targets are issue 39's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.identify.flights import FlightSamples, WakeFitError
from aerodock.identify.wake_folds import _reference_error
from aerodock.identify.wake_score import score_wake, signed_worst
from aerodock.identify.wake_torque import has_motor_torque, torque_profile

TORQUE_BINS_M = ((0.04, 0.06), (0.06, 0.08), (0.08, 0.10))
"""The torque's bins of horizontal offset from the leader's axis, m (4-10 cm)."""
TORQUE_SEPARATION_M = (0.10, 0.70)
"""The depths below the leader the torque is read over by default, m: every pairing of the
shared flights (the small pair and the large follower near 0.2-0.35 m, the small follower under
the large leader near 0.45-0.65 m)."""
TARGETS = {"mean_worst_bin_rel": 0.20, "half_width_rel": 0.20, "turb_vertical_rel": 0.35,
           "turb_lateral_rel": 0.35, "torque_ratio": (0.7, 1.4)}
"""Issue 39's targets: the largest magnitude of each signed relative error; the torque's
world-over-flights ratio in every bin."""
FIGURES = ("mean_worst_bin_rel", "half_width_rel", "turb_vertical_rel", "turb_lateral_rel")
_SCORE_KEYS = {"mean_worst_bin_rel": "mean_vertical", "half_width_rel": "half_width",
               "turb_vertical_rel": "vertical_sd", "turb_lateral_rel": "lateral_sd"}


@dataclass(frozen=True)
class PairScore:
    """One pairing's scores (module docstring). Relative errors are world over flights minus
    one; nan: too few samples to read the figure."""

    pair: str
    leader: str
    follower: str
    flights: int
    samples: int
    mean_worst_bin_rel: float
    half_width_rel: float
    turb_vertical_rel: float
    turb_lateral_rel: float
    torque_ratio_bins: list[float]
    """World over flights per :data:`TORQUE_BINS_M` bin (empty: no log with the motors'
    torque)."""
    reference: dict[str, float | list[float]]
    """The same figures, one half of the flights over the other (nan: fewer than two
    flights)."""
    mean_bins: list[dict[str, float | list[float]]] = field(default_factory=list)
    half_width_m: dict[str, float] = field(default_factory=dict)
    turbulence_mps2: dict[str, dict[str, float]] = field(default_factory=dict)
    torque_bins: list[dict[str, float | list[float]]] = field(default_factory=list)
    edge_mps2: dict[str, float] = field(default_factory=dict)
    """The mean vertical acceleration (down positive) in the ring beyond the jet's edge
    (:data:`aerodock.identify.wake_score.EDGE_RADII`), world and flights, and its samples: the
    flights' upwash, which no target scores."""

    @property
    def met(self) -> dict[str, bool]:
        """Each target (:data:`TARGETS`): met or not (a figure that cannot be read is not)."""
        out = {key: bool(np.isfinite(getattr(self, key))
                         and abs(getattr(self, key)) <= TARGETS[key]) for key in FIGURES}
        lo, hi = TARGETS["torque_ratio"]
        ratios = self.torque_ratio_bins
        out["torque_ratio"] = bool(ratios) and all(np.isfinite(r) and lo <= r <= hi
                                                   for r in ratios)
        return out

    def as_dict(self) -> dict:
        """The JSON form (``field score --json``'s ``pairs`` entries)."""
        return {**asdict(self), "met": self.met}


def score_field(params: dict[str, float], flights: Sequence[FlightSamples],
                logs: Sequence[FlightLog], inertia_kgm2: dict[str, Sequence[float]], *,
                rotor_radii_m: dict[str, float] | None = None,
                torque_separation_m: tuple[float, float] = TORQUE_SEPARATION_M,
                ) -> list[PairScore]:
    """Score the jet with ``params`` (the fitted keys, and ``disk_torque_gain``,
    ``body_area_ratio``, ``body_drag_coeff`` where given) on ``flights``, per pairing.

    Args:
        params: the jet's parameters.
        flights: the flights' samples (:func:`aerodock.identify.flights.prepare_flights`).
        logs: their FlightLogs (for the torque, where they carry the motors' torque).
        inertia_kgm2: each follower vehicle's principal moments of inertia, by id.
        rotor_radii_m: rotor radii by vehicle id overriding the logs' (a fit's estimates).
        torque_separation_m: the depths below the leader the torque is read over, m.

    Raises:
        WakeFitError: no flight with samples below its leader.
    """
    if not flights:
        raise WakeFitError("no flight has samples below its leader")
    radii = rotor_radii_m or {}
    scores = score_wake(params, flights, radii)["pairs"]
    window = (float(torque_separation_m[0]), float(torque_separation_m[1]))
    torque = _torque(params, flights, logs, inertia_kgm2, radii, window)
    out = []
    for pair, entry in sorted(scores.items()):
        group = [f for f in flights if f.pair == pair]
        halves = _halves(group)
        reference = _reference(params, halves, logs, inertia_kgm2, radii, window)
        world_nm, real_nm = torque.get(pair, ([], []))
        out.append(PairScore(
            pair=pair, leader=_ids(group, "leader"), follower=_ids(group, "follower"),
            flights=len({f.flight for f in group}), samples=int(entry["samples"]),
            mean_worst_bin_rel=signed_worst([b["rel_error"]
                                             for b in entry["separation_bins"]]),
            half_width_rel=float(entry["half_width"]["rel_error"]),
            turb_vertical_rel=float(entry["vertical_sd"]["rel_error"]),
            turb_lateral_rel=float(entry["lateral_sd"]["rel_error"]),
            torque_ratio_bins=[w / r if abs(r) > 1e-12 else float("nan")
                               for w, r in zip(world_nm, real_nm, strict=True)],
            reference=reference,
            mean_bins=[{"separation_m": b["separation_m"], "samples": b["samples"],
                        "world_mps2": b["fitted_mps2"], "flights_mps2": b["real_mps2"]}
                       for b in entry["separation_bins"]],
            half_width_m={"world": entry["half_width"]["fitted_m"],
                          "flights": entry["half_width"]["real_m"]},
            turbulence_mps2={axis: {"world": entry[key]["fitted_mps2"],
                                    "flights": entry[key]["real_mps2"]}
                              for axis, key in (("vertical", "vertical_sd"),
                                                ("lateral", "lateral_sd"))},
            torque_bins=[{"offset_m": list(b), "world_nm": w, "flights_nm": r}
                         for b, w, r in zip(TORQUE_BINS_M, world_nm, real_nm, strict=True)],
            edge_mps2={"world": entry["edge"]["fitted_mps2"],
                       "flights": entry["edge"]["real_mps2"],
                       "flights_se": entry["edge"]["real_se_mps2"],
                       "samples": entry["edge"]["samples"]}))
    return out


def _ids(group: Sequence[FlightSamples], role: str) -> str:
    """The pairing's vehicle ids in ``role``, ``"cf50/cf51"`` (``"?"``: not logged)."""
    return "/".join(sorted({str(f.vehicles.get(role) or "?") for f in group}))


def _halves(group: Sequence[FlightSamples]) -> tuple[list[FlightSamples], list[FlightSamples]]:
    """The pairing's flights in name order dealt alternately into two halves."""
    names = sorted({f.flight for f in group})
    first = set(names[0::2])
    return ([f for f in group if f.flight in first], [f for f in group if f.flight not in first])


def _torque(params: dict[str, float], flights: Sequence[FlightSamples],
            logs: Sequence[FlightLog], inertia_kgm2: dict[str, Sequence[float]],
            radii: dict[str, float], window: tuple[float, float],
            ) -> dict[str, tuple[list[float], list[float]]]:
    """Per pairing: the world's and the flights' inward torque in each :data:`TORQUE_BINS_M`
    bin, N·m (nan: too few samples). Empty when no log carries the motors' torque."""
    names = {f.name for f in flights}
    if not any(has_motor_torque(log) for log in logs if log.name in names):
        return {}
    try:
        profile = torque_profile(params, flights, logs, inertia_kgm2, rotor_radii_m=radii,
                                 separation_m=window,
                                 bin_m=TORQUE_BINS_M[0][1] - TORQUE_BINS_M[0][0],
                                 max_offset_m=TORQUE_BINS_M[-1][1])
    except WakeFitError as err:
        if "no flight carries" in str(err):
            return {}
        raise
    out = {}
    for pair, bins in profile.items():
        world, real = [], []
        for lo, _ in TORQUE_BINS_M:
            hit = [b for b in bins if abs(b.offset_lo_m - lo) < 1e-9]
            world.append(hit[0].jet_nm if hit else float("nan"))
            real.append(hit[0].real_nm if hit else float("nan"))
        out[pair] = (world, real)
    return out


def _reference(params: dict[str, float], halves: tuple[list[FlightSamples], ...],
               logs: Sequence[FlightLog], inertia_kgm2: dict[str, Sequence[float]],
               radii: dict[str, float], window: tuple[float, float],
               ) -> dict[str, float | list[float]]:
    """The flights' own reference: half one's real figures over half two's."""
    first, second = halves
    blank: dict[str, float | list[float]] = {key: float("nan") for key in FIGURES}
    blank["torque_ratio_bins"] = []
    if not first or not second:
        return blank
    try:
        a = next(iter(score_wake(params, first, radii)["pairs"].values()))
        b = next(iter(score_wake(params, second, radii)["pairs"].values()))
    except (StopIteration, WakeFitError):
        return blank
    out: dict[str, float | list[float]] = {
        key: _reference_error(_SCORE_KEYS[key], b, a) for key in FIGURES}
    torque_a = _torque(params, first, logs, inertia_kgm2, radii, window)
    torque_b = _torque(params, second, logs, inertia_kgm2, radii, window)
    if torque_a and torque_b:
        real_a, real_b = next(iter(torque_a.values()))[1], next(iter(torque_b.values()))[1]
        out["torque_ratio_bins"] = [x / y if abs(y) > 1e-12 else float("nan")
                                    for x, y in zip(real_a, real_b, strict=True)]
    else:
        out["torque_ratio_bins"] = []
    return out


def scaled_inertia(flights: Sequence[FlightSamples], mass_kg: float, diagonal_m: float,
                   inertia_kgm2: Sequence[float]) -> dict[str | None, list[float]]:
    """Each follower vehicle's inertia, scaled from a reference vehicle's (``mass_kg``,
    ``diagonal_m``, ``inertia_kgm2``) by its mass and diagonal squared, by vehicle id: an
    assumption, for the torque's ``J dw/dt`` term, which averages out over a bin."""
    out: dict[str | None, list[float]] = {}
    for f in flights:
        g = f.geometry
        scale = g["follower_mass_kg"] / mass_kg * (g["follower_diagonal_m"] / diagonal_m) ** 2
        out[f.vehicles.get("follower")] = [scale * j for j in inertia_kgm2]
    return out
