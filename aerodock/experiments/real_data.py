"""The real-data study: learn the downwash from real two-Crazyflie flights (Neural-Swarm).

Leave flights out: train on flights 00-04, evaluate on 05-06 (both vehicles take the follower's
role in each flight). Models: the paper's SO(2) model, the extended SO(2) model, a plain MLP and
the zero model; RMSE of the vertical and planar residual over all samples and over the
interaction region; a sample-efficiency curve; predicted vs measured residual along a held-out
flight.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from aerodock.flightlog import FlightLog
    from aerodock.learning.dataset import Dataset

# The swap flights pass at 0.2-0.5 m laterally: free air for the bias estimate starts nearer
# than in our simulated curriculum (the dataset README: "beyond about 12 cm almost nothing").
FREE_AIR_RADIUS_M = 0.2
TRAIN_FLIGHTS = ("00", "01", "02", "03", "04")
TEST_FLIGHTS = ("05", "06")
# The sample-efficiency curve: minutes of training data (the five training flights hold about
# four) and seeds, by run size (``reproduce``'s full, quick and smoke runs).
SE_MINUTES = {"full": (0.5, 1, 2, 3), "quick": (0.5, 1, 2), "smoke": (0.5,)}
SMOKE_MAX_EPOCHS = 5
"""Every training's epoch limit under ``smoke`` (the held-out models and the sample-efficiency
point: a check that every step runs, not a figure; else up to 200 epochs with early
stopping)."""
SE_SEEDS = {"full": (0, 1, 2), "quick": (0, 1), "smoke": (0,)}


def _flight_number(name: str) -> str | None:
    m = re.search(r"_(\d\d)_cf\d+$", name)
    return m.group(1) if m else None


def _rmse_parts(ev: dict[str, Any], region: str, who: str) -> dict[str, float]:
    r = ev[region][who]["rmse_mps2"]
    return {"vertical": float(r["z"]), "planar": float(np.hypot(r["x"], r["y"])),
            "overall": float(r["overall"])}


def real_split(folder: Path) -> tuple[list[FlightLog], list[FlightLog], Dataset, Dataset]:
    """The Neural-Swarm folder's flights split for the study: (train logs, test logs, train data
    set, test data set), flights :data:`TRAIN_FLIGHTS` to train, :data:`TEST_FLIGHTS` to judge
    (both vehicles' logs of each), labels with :data:`FREE_AIR_RADIUS_M`; other files are left
    out."""
    from aerodock.ingest import read_logs
    from aerodock.learning.dataset import build_dataset

    logs = read_logs("neural-swarm", [Path(folder)])
    train_logs = [lg for lg in logs if _flight_number(lg.name) in TRAIN_FLIGHTS]
    test_logs = [lg for lg in logs if _flight_number(lg.name) in TEST_FLIGHTS]
    return (train_logs, test_logs, build_dataset(train_logs, free_air_radius_m=FREE_AIR_RADIUS_M),
            build_dataset(test_logs, free_air_radius_m=FREE_AIR_RADIUS_M))


OTHER_PAIR_VEHICLES = "cf51=small,cf101=large"
"""The vehicles of the small-large swap day (``swap_sl_2020-06-19``): who is which size."""
FOLLOWERS = {"cf51": "small under large", "cf101": "large under small"}
"""Each vehicle of the small-large day, as the follower: the pairing its flights show."""


def follower_vehicle(ds: Dataset) -> np.ndarray:
    """Per sample of a Neural-Swarm data set, the follower's vehicle: its flight name's last
    part (``"cf51"`` of ``swap_sl_2020-06-19_08_cf51``)."""
    return np.array([name.rsplit("_", 1)[-1] for name in ds.flight_names])[ds.flight_id]


def transfer_to_other_pair(predictors: dict[str, Any], folder: Path) -> dict[str, Any]:
    """Models trained on the small pair, judged on every flight of the small-large day
    (``folder``), each follower apart: a leader (or a follower) of a size the training never
    showed.

    Returns:
        ``{"folder", "flights", "pairings": {pairing: {"interaction_samples", "models": {kind:
        {"vertical_mps2", "vertical_reduction"}}}}}`` over the interaction region; the reduction
        is against the zero model (``predictors`` must hold ``"zero"``).
    """
    from aerodock.ingest import read_logs
    from aerodock.learning.dataset import build_dataset
    from aerodock.learning.evaluate import evaluate

    logs = read_logs("neural-swarm", [Path(folder)], vehicle=OTHER_PAIR_VEHICLES)
    ds = build_dataset(logs, free_air_radius_m=FREE_AIR_RADIUS_M)
    follower = follower_vehicle(ds)
    out: dict[str, Any] = {"folder": str(folder), "flights": len(logs), "pairings": {}}
    for vehicle, pairing in FOLLOWERS.items():
        sub = ds.subset(follower == vehicle)
        models = {}
        for kind, pred in predictors.items():
            ev = evaluate(pred, sub)["interaction"]
            models[kind] = {"vertical_mps2": float(ev["model"]["rmse_mps2"]["z"]),
                            "vertical_reduction": float(1.0 - ev["model"]["rmse_mps2"]["z"]
                                                        / ev["zero"]["rmse_mps2"]["z"])}
        out["pairings"][pairing] = {"interaction_samples": int(ev["n"]), "models": models}
    return out


def real_data_study(folder: Path, fig_dir: Path, quick: bool = False, seed: int = 0,
                    other_pair: Path | None = None, smoke: bool = False) -> dict[str, Any]:
    """Run the study on the Neural-Swarm folder; figures go to ``fig_dir``. With
    ``other_pair`` (the small-large day's folder), the models are also judged on it
    (:func:`transfer_to_other_pair`, ``transfer``). ``smoke`` trains them, and the
    sample-efficiency point, for at most :data:`SMOKE_MAX_EPOCHS` epochs. ``quick`` and ``smoke``
    shorten the sample-efficiency curve (:data:`SE_MINUTES`, :data:`SE_SEEDS`; smoke: one point,
    one seed)."""
    from aerodock.experiments.sample_efficiency import sample_efficiency
    from aerodock.learning.evaluate import evaluate
    from aerodock.learning.runtime import ZeroPredictor
    from aerodock.learning.train import train_model

    train_logs, test_logs, train_ds, test_ds = real_split(folder)
    out: dict[str, Any] = {
        "folder": str(folder), "train_flights": [lg.name for lg in train_logs],
        "test_flights": [lg.name for lg in test_logs], "train_minutes": train_ds.minutes,
        "free_air_radius_m": FREE_AIR_RADIUS_M, "models": {},
    }
    predictors = {"zero": ZeroPredictor()}
    for kind in ("so2", "so2-ext", "mlp"):
        predictors[kind] = train_model(kind, train_ds, seed=seed,
                                       max_epochs=SMOKE_MAX_EPOCHS if smoke else 200
                                       ).predictor()
    for kind, pred in predictors.items():
        ev = evaluate(pred, test_ds)
        out["models"][kind] = {region: _rmse_parts(ev, region, "model")
                               for region in ("all", "interaction")}
        out["interaction_samples"] = int(ev["interaction"]["n"])
    out["transfer"] = (None if other_pair is None
                       else transfer_to_other_pair(predictors, other_pair))
    zero_v = out["models"]["zero"]["interaction"]["vertical"]
    out["so2_vertical_reduction_interaction"] = 1.0 - out["models"]["so2"]["interaction"][
        "vertical"] / zero_v
    size = "smoke" if smoke else "quick" if quick else "full"
    out["sample_efficiency"] = sample_efficiency(
        train_ds, test_ds, kinds=("so2", "so2-ext", "mlp"),
        minutes=SE_MINUTES[size], seeds=SE_SEEDS[size], metric="interaction",
        train_kwargs={"max_epochs": SMOKE_MAX_EPOCHS} if smoke else None)
    from aerodock.experiments.sample_efficiency import plot_sample_efficiency

    plot_sample_efficiency(out["sample_efficiency"], fig_dir / "real_sample_efficiency.png")
    _plot_heldout(test_logs, test_ds, predictors, fig_dir / "real_heldout_vertical.png")
    return out


def _plot_heldout(test_logs, test_ds, predictors, path: Path) -> Path:
    from aerodock.plots import _plt, _save

    plt = _plt()
    # The held-out flight with the most interaction samples.
    mask = test_ds.interaction_mask()
    counts = np.bincount(test_ds.flight_id[mask], minlength=test_ds.n_flights)
    f = int(np.argmax(counts))
    sel = test_ds.flight_id == f
    t = test_ds.t_s[sel]
    fig, ax = plt.subplots(figsize=(10, 4.5))
    ax.plot(t, test_ds.y[sel, 2], color="0.6", lw=0.8, label="measured residual (label)")
    for kind, colour in (("so2", "tab:blue"), ("mlp", "tab:orange")):
        pred = predictors[kind].predict(test_ds.x[sel], test_ds.leader_R[sel])
        ax.plot(t, pred[:, 2], color=colour, label=f"predicted, {kind}")
    inter = mask[sel]
    ax.fill_between(t, 0, 1, where=inter, transform=ax.get_xaxis_transform(), color="tab:green",
                    alpha=0.12, label="below the other vehicle (< 0.2 m)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("vertical residual, down positive [m/s²]")
    ax.set_title(f"Held-out real flight {test_ds.flight_names[f]}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, path)
