"""The paper's own docking counts, and how likely each is under a docking rate measured here.

The paper reports single small counts: hover docking 8 of 10 with the model (and, from its
discussion, none without it), and in the cable study one attempt per offset that docked at all
six offsets with the model and at none without it. A simulated rate is consistent with such a
count when the count is not improbable under it: the probability of a result at least as far
from the rate's expectation as the paper's, on the paper's side (one-sided binomial tail), for
the hover counts; for the cable study, the probability of exactly the paper's pattern (every
offset docked, or none) with each offset at its own measured rate.
"""

from __future__ import annotations

from math import comb, prod
from typing import Any

PAPER_HOVER_WITH_MODEL = (8, 10)  # docked, attempts: "successful ... in 8 out of 10 instances"
PAPER_HOVER_WITHOUT_MODEL = (0, 10)  # the paper: without the model Bravo fails to dock
PAPER_CABLE_OFFSETS = 6  # one attempt per offset: 6/6 docked with the model, 0/6 without
CONSISTENT_AT = 0.05  # a count less likely than this under a rate is inconsistent with it


def binomial_tail(k: int, n: int, rate: float) -> float:
    """P(X >= k) if ``k >= n * rate`` else P(X <= k), for X ~ Binomial(n, rate)."""
    if not 0.0 <= rate <= 1.0:
        raise ValueError(f"rate must be in [0, 1], got {rate}")
    pmf = [comb(n, i) * rate**i * (1.0 - rate) ** (n - i) for i in range(n + 1)]
    return float(sum(pmf[k:]) if k >= n * rate else sum(pmf[: k + 1]))


def hover_count_probability(paper: tuple[int, int], docked: int, trials: int) -> dict[str, Any]:
    """How likely the paper's hover count is under the rate ``docked / trials``."""
    k, n = paper
    rate = docked / trials if trials else 0.0
    p = binomial_tail(k, n, rate)
    return {"paper": f"{k}/{n}", "rate": rate, "probability": p,
            "consistent": p >= CONSISTENT_AT}


def cable_pattern_probability(rates: list[float], all_docked: bool) -> dict[str, Any]:
    """How likely the paper's cable-study pattern (all offsets docked, or none) is when each
    offset docks at its own measured rate (one attempt per offset, as in the paper).

    ``paper`` quotes the paper's count as the paper gives it (6/6 or 0/6), whatever the number
    of offsets flown here; the probability is the pattern's over the offsets flown.
    """
    p = prod(rates) if all_docked else prod(1.0 - r for r in rates)
    n = PAPER_CABLE_OFFSETS
    return {"paper": f"{n if all_docked else 0}/{n}", "rates": list(rates),
            "probability": float(p), "consistent": p >= CONSISTENT_AT}


def paper_outcome_probabilities(hover_with: dict[str, Any], hover_without: dict[str, Any],
                                cable: dict[str, Any] | None) -> dict[str, Any]:
    """The probability of each of the paper's outcomes under the measured rates.

    Args:
        hover_with, hover_without: campaign summaries (``docked``, ``trials``) at d_p 0.36 m.
        cable: the cable study record (``with_model`` / ``without_model`` lists of per-offset
            summaries with ``success_rate``), or ``None``.
    """
    out: dict[str, Any] = {
        "hover_with_model": hover_count_probability(PAPER_HOVER_WITH_MODEL,
                                                    hover_with["docked"], hover_with["trials"]),
        "hover_without_model": hover_count_probability(
            PAPER_HOVER_WITHOUT_MODEL, hover_without["docked"], hover_without["trials"]),
    }
    if cable is not None:
        for key, all_docked in (("with_model", True), ("without_model", False)):
            rates = [r["success_rate"] for r in cable[key]]
            rec = cable_pattern_probability(rates, all_docked)
            if len(rates) != PAPER_CABLE_OFFSETS:
                rec["note"] = (f"only {len(rates)} of the paper's {PAPER_CABLE_OFFSETS} offsets "
                               "flown here; the probability is over those")
            out[f"cable_{key}"] = rec
    out["all_consistent"] = all(v["consistent"] for v in out.values())
    return out
