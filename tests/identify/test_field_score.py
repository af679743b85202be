"""`aerodock field score`: a wake scored on flights pairing by pairing
(aerodock/identify/field_score.py).

- synthetic flights made by a known jet, whose motors answer a known multiple of its torque: the
  jet that made them scores near zero on every figure and the torque ratio is one over the
  multiple; a wrong jet scores its error;
- the shared real flights: the default world's torque is a small fraction of the real one, and
  beyond the jet's edge the flights are pushed up where the world is not;
- the command: the JSON the issue names, a fit folder and a config as FIT, bad input as one
  line.
"""

from __future__ import annotations

import json
from functools import partial

import numpy as np
import pytest
from cli_process import aerodock as run_cli
from wake_synth import answering_motors, synthetic_flights

from aerodock.flightlog import save_flightlogs
from aerodock.identify import field_score as fs
from aerodock.identify import flights as fl

INERTIA = {vid: (1.7e-5, 1.7e-5, 3.0e-5) for vid in ("cf1", "cf2", "cf9")}
PAIRS = {"32 g under 32 g", "32 g under 67 g", "67 g under 32 g"}


@pytest.fixture(scope="module")
def answered(truth):
    """Synthetic flights of all three pairs whose motors answer three times the jet's torque."""
    rng = np.random.default_rng(0)
    return [answering_motors(log, truth, 3.0, np.array([3e-4, -2e-4, 1e-4]), rng)
            for log in synthetic_flights(truth, flights_per_pair=3, seed=3)]


def test_the_jet_that_made_the_flights_scores_its_own_torque_gap(truth, answered):
    """Mean, half-width and vertical sd within the targets for the jet that made the flights;
    the torque ratio 1/3 in every bin (the motors answered 3x), the flights' own torque near
    1 (every flight answers the same multiple)."""
    flights = fl.prepare_flights(answered)
    scores = {s.pair: s for s in fs.score_field(truth, flights, answered, INERTIA)}
    assert set(scores) == PAIRS
    for s in scores.values():
        assert s.flights == 3 and s.samples > 400
        assert abs(s.mean_worst_bin_rel) < fs.TARGETS["mean_worst_bin_rel"], s
        assert abs(s.turb_vertical_rel) < fs.TARGETS["turb_vertical_rel"], s
        assert len(s.torque_ratio_bins) == len(fs.TORQUE_BINS_M)
        for ratio in s.torque_ratio_bins:
            assert ratio == pytest.approx(1 / 3, rel=0.1), s
        for ratio in s.reference["torque_ratio_bins"]:
            assert ratio == pytest.approx(1.0, rel=0.15), s
        met = s.met
        assert met["mean_worst_bin_rel"] and not met["torque_ratio"]
        # beyond the edge the jet that made the flights is what they feel: no upwash either
        edge = s.edge_mps2
        assert edge["samples"] > 50, s
        assert abs(edge["flights"] - edge["world"]) < 3 * edge["flights_se"] + 0.01, s
    # the same flights scored by a jet with three times the disks' torque: the gap closes
    tripled = {**truth, "disk_torque_gain": 3.0}
    for s in fs.score_field(tripled, flights, answered, INERTIA):
        assert s.met["torque_ratio"], s
        for ratio in s.torque_ratio_bins:
            assert ratio == pytest.approx(1.0, rel=0.1), s


def test_a_wrong_jet_scores_its_error(truth, answered):
    """A jet whose force is a third too strong (the ingest coefficient 4/3 times) scores the
    mean about a third high, beyond the target, where the flights' own halves agree."""
    flights = fl.prepare_flights(answered)
    strong = {**truth, "ingest_coeff": truth["ingest_coeff"] * 4 / 3}
    for s in fs.score_field(strong, flights, answered, INERTIA):
        assert s.mean_worst_bin_rel > fs.TARGETS["mean_worst_bin_rel"], s
        assert not s.met["mean_worst_bin_rel"]
        assert abs(s.reference["mean_worst_bin_rel"]) < fs.TARGETS["mean_worst_bin_rel"], s


def test_the_default_world_on_the_real_flights(shared_data):
    """On the shared Crazyflie flights the default world's torque (the jet fitted with the
    logged torque) is a quarter to a half of the real one in every 4-10 cm bin (measured
    0.25-0.47; under a third with the force-only fit, the issue's 4-10x), where the flights' own
    halves agree within a factor of three."""
    from aerodock.config import load_config
    from aerodock.experiments.swap_flights import read_swap_flights

    logs = read_swap_flights(shared_data("neural-swarm"))
    cfg = load_config()
    flights = fl.prepare_flights(logs)
    inertia = fs.scaled_inertia(flights, cfg.vehicle.mass_kg, cfg.vehicle.diagonal_m,
                                cfg.vehicle.inertia_kgm2)
    params = dict(cfg.downwash.params)
    scores = {s.pair: s for s in fs.score_field(params, flights, logs, inertia)}
    assert set(scores) == PAIRS
    for s in scores.values():
        assert len(s.torque_ratio_bins) == 3, s
        assert all(0.2 < r < 0.5 for r in s.torque_ratio_bins), s
        assert all(not np.isfinite(r) or 1 / 3 < r < 3
                   for r in s.reference["torque_ratio_bins"]), s
        # beyond the jet's edge the real flights are pushed up (measured -0.04 to -0.10 m/s^2,
        # 7-33 standard errors) and the Gaussian jet is not
        edge = s.edge_mps2
        assert edge["flights"] < -5 * edge["flights_se"], s
        assert edge["world"] > -0.005, s
    # from the motors' commands as sent (the thrust asked for beyond a motor's ceiling taken
    # away) the flights' torque is smaller, the world's closer to it in every bin (measured
    # 0.29-0.53, docs/crazyflie.md), the gap still there
    from aerodock.identify.motor_commands import logs_as_sent

    sent, _ = logs_as_sent(logs)
    as_sent = {s.pair: s for s in fs.score_field(params, fl.prepare_flights(sent), sent,
                                                 inertia)}
    assert set(as_sent) == PAIRS
    for pair, s in as_sent.items():
        for r_sent, r_asked in zip(s.torque_ratio_bins, scores[pair].torque_ratio_bins,
                                   strict=True):
            assert r_asked < r_sent < 0.6, (pair, s.torque_ratio_bins)


# -- the command ------------------------------------------------------------------------------
aerodock = partial(run_cli, check=True)


@pytest.fixture(scope="module")
def data(answered, tmp_path_factory):
    path = tmp_path_factory.mktemp("score") / "synth.npz"
    return save_flightlogs(path, answered)


def test_field_score_json_from_a_fit_folder_and_a_config(tmp_path, truth, data):
    """A fit folder (fit.json's parameters) and the config with the same values score alike;
    the JSON holds the issue's keys for each pairing."""
    folder = tmp_path / "fit"
    folder.mkdir()
    (folder / "fit.json").write_text(json.dumps({"params": truth, "rotor_radii_m": {}}))
    out = json.loads(aerodock("field", "score", str(folder), "--data", str(data),
                              "--json").stdout)
    assert {p["pair"] for p in out["pairs"]} == PAIRS
    for p in out["pairs"]:
        assert isinstance(p["leader"], str) and isinstance(p["follower"], str)
        assert isinstance(p["samples"], int) and p["samples"] > 0
        for key in ("mean_worst_bin_rel", "half_width_rel", "turb_vertical_rel",
                    "turb_lateral_rel"):
            assert isinstance(p[key], float), key
        assert len(p["torque_ratio_bins"]) == 3
        assert set(p["reference"]) >= {"mean_worst_bin_rel", "torque_ratio_bins"}
    config = json.loads(aerodock("field", "score", "examples/crazyflie.toml", "--data",
                                 str(data), "--json").stdout)
    assert config["params"]["disk_torque_gain"] == 1.0
    by_pair = {p["pair"]: p for p in out["pairs"]}
    for p in config["pairs"]:  # the example's wake is the default's: the same scores
        assert p["mean_worst_bin_rel"] == pytest.approx(by_pair[p["pair"]]["mean_worst_bin_rel"])


def test_field_score_prints_a_table(data):
    res = aerodock("field", "score", "examples/crazyflie.toml", str(data), "--data", str(data))
    assert "cf2 under cf1" in res.stdout and "flights' own" in res.stdout
    assert "met 4/5" in res.stdout or "met 3/5" in res.stdout, res.stdout


@pytest.mark.parametrize("args, message", [
    (["FIT"], "no flights: give FlightLog files with --data"),
    (["FIT", "--data", "missing.npz"], "missing.npz"),
    (["nowhere.toml", "--data", "DATA"], "nowhere.toml: no such file or folder"),
    (["BADFIT", "--data", "DATA"], "'params' must hold the fitted parameters"),
    (["EMPTYDIR", "--data", "DATA"], "not a `field fit --out` folder"),
    (["OTHERFIELD", "--data", "DATA"], "field score scores the default jet"),
    (["FIT", "--data", "DATA", "--torque-separation", "0.5", "0.2"],
     "--torque-separation must be two depths LOW < HIGH"),
])
def test_field_score_bad_input_is_one_line(tmp_path, truth, data, args, message):
    (tmp_path / "fit").mkdir()
    (tmp_path / "fit" / "fit.json").write_text(json.dumps({"params": truth}))
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "fit.json").write_text(json.dumps({"params": {"spread_rate": "x"}}))
    (tmp_path / "empty").mkdir()
    (tmp_path / "other.toml").write_text(
        '[downwash]\nfield = "aerodock.downwash.at_centre:RoundJetAtCentre"\n')
    where = {"FIT": tmp_path / "fit", "DATA": data, "BADFIT": tmp_path / "bad",
             "EMPTYDIR": tmp_path / "empty", "OTHERFIELD": tmp_path / "other.toml"}
    proc = aerodock("field", "score", *[str(where.get(a, a)) for a in args], check=False)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    assert message in lines[0]
