"""`aerodock field fit`: the jet identified from flight logs (aerodock/identify/wake_fit.py).

- synthetic flights made by the simulator's wake with known parameters: the fit recovers them;
- the shared real Crazyflie flights: the fit reproduces examples/crazyflie_wake_fitted.toml and
  meets the held-out targets it meets (docs/world.md says which it does not);
- the command: its outputs, and bad input as one-line errors.
"""

from __future__ import annotations

import json
import tomllib
from functools import partial
from pathlib import Path

import pytest
from cli_process import aerodock as run_cli
from wake_synth import synthetic_flights

from aerodock.flightlog import save_flightlogs
from aerodock.identify import flights as fl
from aerodock.identify import wake_fit as wf
from aerodock.identify import wake_score as ws

FITTED = Path(__file__).resolve().parents[2] / "examples" / "crazyflie_wake_fitted.toml"
SPEED_FITTED = FITTED.with_name("wake_fitted_speed_noise.toml")
HOLDOUT = ("swap_ss_0[56]", "swap_sl_2020-06-19_0[89]", "swap_sl_2020-06-19_1[01]")


@pytest.fixture(scope="module")
def synthetic(truth):
    return synthetic_flights(truth, flights_per_pair=4, seed=1)


def test_fit_recovers_the_simulators_wake(truth, synthetic):
    """Known parameters in, the same parameters out: the mean's within a few percent, the
    turbulence's within its estimate's spread; the labels' bias and white noise are removed."""
    flights = fl.prepare_flights(synthetic)
    fit = wf.fit_wake(flights)
    got = fit.params
    print({k: (round(truth[k], 4), round(got[k], 4)) for k in wf.FITTED_PARAMS})
    for key, rel in (("width0_ratio", 0.1), ("ingest_coeff", 0.1), ("ingest_exponent", 0.1),
                     ("turb_vertical", 0.15), ("turb_lateral", 0.2), ("turb_time_ratio", 0.35)):
        assert got[key] == pytest.approx(truth[key], rel=rel), key
    assert got["spread_rate"] == pytest.approx(truth["spread_rate"], abs=0.02)
    assert got["planar_ratio"] == pytest.approx(truth["planar_ratio"], abs=0.03)
    # the disks' shared share is what the two follower sizes tell apart: loosely identified
    assert 0.25 * truth["turb_length_ratio"] < got["turb_length_ratio"] \
        < 4 * truth["turb_length_ratio"]
    scores = ws.score_wake(got, flights)
    for pair, entry in scores["pairs"].items():
        assert entry["mean_vertical"]["met"], pair
        assert entry["half_width"]["met"], pair
        assert entry["vertical_sd"]["met"], pair


def test_fit_estimates_a_rotor_radius_the_logs_get_wrong(truth, synthetic):
    """The large vehicle's rotor radius, logged wrong (0.0325 m instead of the 0.024 m its wake
    was made with) and estimated with the rest, comes back."""
    wrong = []
    for log in synthetic:
        meta = dict(log.meta)
        for role in ("leader", "follower"):
            if meta[f"{role}_id"] == "cf9":
                meta[f"{role}_rotor_radius_m"] = 0.0325
        wrong.append(type(log)(**{**log.__dict__, "meta": meta}))
    flights = fl.prepare_flights(wrong)
    params, radii, _ = wf.fit_mean(flights, estimate_rotor_for=["cf9"])
    assert radii["cf9"] == pytest.approx(0.024, rel=0.1)
    assert params["ingest_exponent"] == pytest.approx(truth["ingest_exponent"], rel=0.1)


def test_bootstrap_brackets_the_estimate(synthetic):
    flights = fl.prepare_flights(synthetic)
    fit = wf.fit_wake(flights, bootstrap=3, seed=2)
    assert fit.bootstrap_runs == 3
    for key in ("width0_ratio", "ingest_coeff", "turb_vertical"):
        spread = fit.bootstrap[key]
        assert spread["sd"] > 0
        assert spread["p2_5"] <= spread["p97_5"]


def test_prepare_refuses_logs_without_geometry(synthetic):
    log = synthetic[0]
    meta = {k: v for k, v in log.meta.items() if k != "follower_diagonal_m"}
    bare = type(log)(**{**log.__dict__, "meta": meta})
    with pytest.raises(wf.WakeFitError, match="follower_diagonal_m"):
        fl.prepare_flights([bare])


def _torque_labels(fitted, logs):
    """``field fit``'s torque labels (the default config's vehicle scaled to each follower)."""
    from aerodock.config import load_config
    from aerodock.identify.field_score import scaled_inertia
    from aerodock.identify.torque_labels import torque_labels

    v = load_config().vehicle
    return torque_labels(fitted, logs, scaled_inertia(fitted, v.mass_kg, v.diagonal_m,
                                                      v.inertia_kgm2))


def test_real_fit_on_the_shared_flights(shared_data):
    """Fitted on swap_ss 00-04 and swap_sl 00-07 with their logged torque (the large vehicle's
    rotor radius its airframe's, 33 mm): the fit is examples/crazyflie_wake_fitted.toml (the
    command's output; bootstrap aside, the fit is deterministic); on the held-out flights
    (swap_ss 05-06, swap_sl 08-11) the mean is within 15 % in every separation bin, the
    half-width within 20 % under both leaders for the small follower, and the vertical
    turbulence within 20 % for every pair. (Not met, docs/world.md: the lateral turbulence of
    the equal pair and of the large follower, and the large follower's half-width, +30 %.)"""
    import warnings

    from aerodock.ingest import read_logs

    folders = [shared_data("neural-swarm", "swap_ss"),
               shared_data("neural-swarm", "swap_sl_2020-06-19")]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        logs = read_logs("neural-swarm", folders, vehicle="cf50=small,cf51=small,cf101=large")
    flights = fl.prepare_flights(logs)
    fitted, held = fl.select_flights(flights, HOLDOUT)
    assert len({f.flight for f in held}) == 6
    labels = _torque_labels(flights, logs)  # as `field fit` reads them: every flight's
    assert len({f.flight for f in fitted if f.name in labels}) == 5  # free air for the trim
    fit = wf.fit_wake(fitted, torque=labels)
    shipped = tomllib.loads(FITTED.read_text())["downwash"]["params"]
    assert set(shipped) == set(fit.keys)
    for key in fit.keys:
        # the file rounds to four digits; the fit settles at its valley's floor
        # (wake_fit.settled_least_squares), so any machine gets the command's numbers
        assert fit.params[key] == pytest.approx(shipped[key], rel=2e-3, abs=2e-4), key
    scores = ws.score_wake(fit.params, held, fit.rotor_radii_m)
    pairs = scores["pairs"]
    assert set(pairs) == {"32 g under 32 g", "32 g under 67 g", "67 g under 32 g"}
    for pair, entry in pairs.items():
        assert entry["mean_vertical"]["met"], (pair, entry["separation_bins"])
        assert entry["vertical_sd"]["met"], (pair, entry["vertical_sd"])
        # the wake explains most of the residual in the region (measured: 33-59 % of the zero
        # model's RMSE left, the rest turbulence and the labels' noise)
        assert entry["rmse_mps2"] < 0.7 * entry["zero_model_rmse_mps2"]
    for pair in ("32 g under 32 g", "32 g under 67 g"):
        assert pairs[pair]["half_width"]["met"], (pair, pairs[pair]["half_width"])
    # the large vehicle's rotors are its airframe's (the reader's table), not fitted
    assert fit.rotor_radii_m == {}
    assert {f.geometry["leader_rotor_radius_m"] for f in fitted
            if f.vehicles["leader"] == "cf101"} == {0.033}


def test_the_fit_settles_wherever_it_starts(shared_data):
    """The mean's least squares, started from two places of its flat valley, settles at one
    floor: the parameters agree within 2e-4 (one run of it stopped 1 % apart, at `width0_ratio`
    0.7253 from the default start and 0.7326 from this one, on an AVX2 machine; restarting it
    from its result left an AVX-512 machine at 0.7353, another floor, until the default fit
    also started from `OTHER_START`)."""
    from aerodock.experiments.swap_flights import read_swap_flights

    logs = read_swap_flights(shared_data("neural-swarm"))
    flights = fl.prepare_flights(logs)
    fitted, _ = fl.select_flights(flights, HOLDOUT)
    labels = _torque_labels(flights, logs)
    first, _, _ = wf.fit_mean(fitted, torque=labels)
    other, _, _ = wf.fit_mean(fitted, torque=labels,
                              start={"width0_ratio": 0.9, "spread_rate": 0.05, "ingest_coeff": 0.7})
    for key in wf.MEAN_PARAMS + wf.TORQUE_PARAMS:
        assert other[key] == pytest.approx(first[key], rel=2e-4, abs=1e-4), key


def test_real_fit_above_the_noise_at_speed(shared_data):
    """`--noise speed` on the same split is examples/wake_fitted_speed_noise.toml: the mean is
    the same fit, the lateral intensity a third lower (0.035 against 0.052: the pooled noise
    read part of the follower's own noise as gusts), the vertical 4 % lower."""
    from aerodock.experiments.swap_flights import read_swap_flights
    from aerodock.identify.label_noise import noise_by_speed, with_speed_noise

    logs = read_swap_flights(shared_data("neural-swarm"))
    flights = with_speed_noise(fl.prepare_flights(logs), noise_by_speed(logs))
    fitted, _ = fl.select_flights(flights, HOLDOUT)
    fit = wf.fit_wake(fitted, torque=_torque_labels(flights, logs))
    shipped = tomllib.loads(SPEED_FITTED.read_text())["downwash"]["params"]
    pooled = tomllib.loads(FITTED.read_text())["downwash"]["params"]
    for key in fit.keys:
        assert fit.params[key] == pytest.approx(shipped[key], rel=2e-3, abs=2e-4), key
    for key in wf.MEAN_PARAMS + wf.TORQUE_PARAMS:
        assert shipped[key] == pooled[key], key
    assert 0.6 < shipped["turb_lateral"] / pooled["turb_lateral"] < 0.75
    assert 0.9 < shipped["turb_vertical"] / pooled["turb_vertical"] < 1.0
    # it loads as the paper-scale world with only the turbulence changed (docs/world.md flies it)
    from aerodock.config import load_config

    default, variant = load_config().downwash.params, load_config(SPEED_FITTED).downwash.params
    assert {k for k in default if default[k] != variant[k]} == {
        "turb_vertical", "turb_lateral", "turb_length_ratio"}


# -- the command ------------------------------------------------------------------------------
aerodock = partial(run_cli, check=True)


def test_field_fit_writes_the_report_and_the_config(tmp_path, synthetic):
    """In-process (what it writes is checked; the bad inputs below run as a user's process)."""
    from typer.testing import CliRunner

    from aerodock.cli.app import app

    data = tmp_path / "synth.npz"
    save_flightlogs(data, synthetic)
    out, toml = tmp_path / "fit", tmp_path / "wake.toml"
    res = CliRunner().invoke(app, ["field", "fit", str(data), "--holdout", "synth_ss_03",
                                   "--bootstrap", "2", "--out", str(out), "--config-out",
                                   str(toml), "--json"])
    assert res.exit_code == 0, (res.output, res.exception)
    result = json.loads(res.stdout)
    assert set(result["params"]) == set(wf.FITTED_PARAMS)
    assert result["held_out_flights"] == ["synth_ss_03"]
    assert result["bootstrap_runs"] == 2
    assert result["commands"] == "asked" and "--commands" not in result["command"]
    assert [r["separation_m"] for r in result["world"]["rows"]] == [0.36, 0.64, 1.35]
    for name in ("report.md", "fit.json", "wake.toml", "figures/mean_vs_separation.png",
                 "figures/mean_vs_offset.png", "figures/autocorrelation.png",
                 "figures/turbulence.png"):
        assert (out / name).is_file(), name
    assert toml.read_text() == (out / "wake.toml").read_text()
    # the checks beside the fit: the synthetic labels' noise does not grow with speed, so the
    # turbulence above it is the pooled reading's; no synthetic log carries a motor torque
    noise = result["turbulence_above_speed_noise"]
    assert set(noise) == {"held_out", "fitted"}
    for rows in noise.values():
        for r in rows.values():
            assert r["vertical_speed"] == pytest.approx(r["vertical_pooled"], rel=0.25)
    assert result["wake_torque"] is None
    assert result["motor_ceiling"] is None  # nor the motor commands: no ceiling to report
    report = (out / "report.md").read_text()
    assert "## The turbulence above the labels' noise at the follower's speed" in report
    assert "No log carries the follower's motor torque" in report
    assert "## The motors' ceiling" not in report
    # the fragment loads as a world's config, with the fitted values
    from aerodock.config import load_config

    cfg = load_config(toml)
    for key, value in result["params"].items():
        assert cfg.downwash.params[key] == pytest.approx(value, rel=1e-3)


@pytest.mark.parametrize("args, message", [
    (["missing.npz"], "missing.npz"),
    (["DATA", "--holdout", "nothing_like_it"], "--holdout nothing_like_it matches no flight"),
    (["DATA", "--holdout", "synth_*"], "--holdout leaves no flight to fit"),
    (["DATA", "--bootstrap", "-1"], "--bootstrap must be between 0 and 1000"),
    (["DATA", "--noise", "fast"], "'fast' is not one of 'pooled', 'speed'"),
    (["DATA", "--commands", "wanted"], "'wanted' is not one of 'asked', 'sent'"),
    (["DATA", "--estimate-rotor", "cf77"], "--estimate-rotor cf77: no log has a vehicle"),
    (["NOTLOG"], "NOTLOG"),
])
def test_field_fit_bad_input_is_one_line(tmp_path, synthetic, args, message):
    data = tmp_path / "synth.npz"
    save_flightlogs(data, synthetic[:2] + synthetic[4:6])
    notlog = tmp_path / "notlog.npz"
    notlog.write_bytes(b"not a flight log")
    args = [str(data) if a == "DATA" else str(notlog) if a == "NOTLOG" else a for a in args]
    message = message.replace("NOTLOG", str(notlog))
    if "--bootstrap" not in args:
        args += ["--bootstrap", "0"]
    proc = aerodock("field", "fit", *args, "--out", str(tmp_path / "o"), check=False)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    assert message in lines[0]
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists()


def test_a_fit_holds_every_blas_to_one_thread_scipys_too():
    """``serial_blas`` in a fresh process (no thread limits in its environment, SciPy not yet
    imported): inside the fit every BLAS library runs one thread, SciPy's own (which its least
    squares load on first use) included. Before, SciPy's was loaded inside the limit and kept
    its threads: a fit kept a second core busy, its numbers the same."""
    import os
    import subprocess
    import sys

    code = ("from threadpoolctl import threadpool_info\n"
            "from aerodock.identify.wake_fit import serial_blas\n"
            "def fit():\n"
            "    from scipy.optimize import least_squares  # as settled_least_squares does\n"
            "    return [(i['filepath'], i['num_threads']) for i in threadpool_info()\n"
            "            if i['user_api'] == 'blas']\n"
            "import json\n"
            "print(json.dumps(serial_blas(fit)()))\n")
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    libraries = json.loads(out.stdout.strip().splitlines()[-1])
    assert libraries and all(threads == 1 for _, threads in libraries), libraries
