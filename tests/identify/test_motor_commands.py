"""The motors' commands as sent (aerodock/identify/motor_commands.py): a synthetic flight whose
commands are capped below what its firmware asks for, and the real Crazyflie flights."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from wake_synth import synthetic_flights

from aerodock.config import load_config
from aerodock.geometry import quat_to_rotmat, thrust_accel
from aerodock.identify import flights as fl
from aerodock.identify import motor_commands as mc
from aerodock.identify import wake_fit as wf
from aerodock.identify import wake_torque as wt
from aerodock.identify.flights import WakeFitError, log_geometry

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ARM_M = 0.0325
MIXER = np.array([[-ARM_M, -ARM_M, ARM_M, ARM_M],  # the logs' own: torquex, torquey (FRD)
                  [ARM_M, -ARM_M, -ARM_M, ARM_M],
                  [-0.006, 0.006, -0.006, 0.006]]).T


def firmware_map(pwm: np.ndarray, volts: np.ndarray) -> np.ndarray:
    """A firmware's thrust for a command and voltage, N (quadratic in the command, scaled by
    the voltage: in the map's own terms)."""
    return (0.02 + 0.1 * pwm + 0.22 * pwm**2) * (volts / 3.7)


def commanded(log, cap: float, seed: int = 0):
    """``log`` with motors whose asked-for thrust follows the map of an uncapped command, the
    command sent capped at ``cap``: thrusts, commands, voltage, torque columns and the
    collective (and the acceleration it explains) as a Neural-Swarm log holds them."""
    rng = np.random.default_rng(seed)
    n = log.n_samples
    wanted = np.clip(0.7 + 0.08 * rng.standard_normal((n, 4)), 0.5, 1.0)
    volts = np.linspace(3.9, 3.5, n)
    asked = firmware_map(wanted, volts[:, None])
    sent = np.minimum(wanted, cap)
    thrust = asked.sum(axis=1)
    cmd = thrust_accel(quat_to_rotmat(log.follower_quat), thrust,
                       log_geometry(log)["follower_mass_kg"])
    return replace(log, follower_thrust_n=thrust, follower_cmd_accel_mps2=cmd, extra={
        **log.extra, mc.MOTOR_THRUST_KEY: asked, wt.MOTOR_PWM_KEY: sent,
        mc.BATTERY_KEY: volts, wt.MOTOR_TORQUE_KEY: asked @ MIXER}), sent, volts


@pytest.fixture(scope="module")
def flight():
    cfg = load_config()
    params = {k: float(cfg.downwash.params[k]) for k in wf.FITTED_PARAMS}
    return synthetic_flights(params, flights_per_pair=1, seed=3)[0]


def test_as_sent_takes_away_the_thrust_asked_beyond_the_ceiling(flight):
    """Capped commands: the maps are recovered from the samples below the top, the thrusts the
    commands make replace the asked-for ones in the torque, the collective and the acceleration
    it explains; the excess asked for at the ceiling is reported."""
    log, sent, volts = commanded(flight, cap=0.93)
    out, motor_map = mc.as_sent(log)
    expected = firmware_map(sent, volts[:, None])
    np.testing.assert_allclose(out.extra[wt.MOTOR_TORQUE_KEY], expected @ MIXER, atol=1e-9)
    np.testing.assert_allclose(out.follower_thrust_n, expected.sum(axis=1), atol=1e-9)
    np.testing.assert_allclose(
        out.follower_cmd_accel_mps2,
        thrust_accel(quat_to_rotmat(log.follower_quat), expected.sum(axis=1),
                     log_geometry(log)["follower_mass_kg"]), atol=1e-9)
    assert motor_map.residual_sd_n < 1e-9
    wanted_over = log.extra[mc.MOTOR_THRUST_KEY] - expected
    top = sent >= mc.CEILING_PWM
    assert motor_map.ceiling_samples == int(top.sum()) > 0
    assert motor_map.ceiling_excess_n == pytest.approx(float(wanted_over[top].mean()))
    assert motor_map.ceiling_excess_n > 0
    # below the cap, what was asked for is what was sent: nothing changes there
    below = np.all(sent < 0.93, axis=1)
    np.testing.assert_allclose(out.extra[wt.MOTOR_TORQUE_KEY][below],
                               log.extra[wt.MOTOR_TORQUE_KEY][below], atol=1e-9)


def test_commands_below_the_ceiling_change_nothing(flight):
    log, _, _ = commanded(flight, cap=1.0)
    out, motor_map = mc.as_sent(log)
    np.testing.assert_allclose(out.extra[wt.MOTOR_TORQUE_KEY], log.extra[wt.MOTOR_TORQUE_KEY],
                               atol=1e-9)
    np.testing.assert_allclose(out.follower_cmd_accel_mps2, log.follower_cmd_accel_mps2,
                               atol=1e-9)
    assert motor_map.ceiling_samples == 0 or motor_map.ceiling_excess_n == pytest.approx(
        0.0, abs=1e-9)


def test_logs_that_cannot_be_read_are_refused_and_left_out(flight):
    log, _, _ = commanded(flight, cap=0.93)
    bare = replace(flight, extra={k: v for k, v in flight.extra.items()
                                  if k != wt.MOTOR_TORQUE_KEY})
    with pytest.raises(WakeFitError, match="has no"):
        mc.as_sent(bare)
    unmixed = replace(log, extra={**log.extra, wt.MOTOR_TORQUE_KEY:
                                  log.extra[wt.MOTOR_TORQUE_KEY] ** 2})
    with pytest.raises(WakeFitError, match="not a mix"):
        mc.as_sent(unmixed)
    high = replace(log, extra={**log.extra, wt.MOTOR_PWM_KEY:
                               np.full_like(log.extra[wt.MOTOR_PWM_KEY], 0.95)})
    with pytest.raises(WakeFitError, match="needed to fit the maps"):
        mc.as_sent(high)
    kept, maps = mc.logs_as_sent([log, bare, high])
    assert [m.name for m in maps] == [log.name] and len(kept) == 1


def test_real_commands_reach_a_ceiling_and_the_torque_as_sent_is_smaller(shared_data):
    """The real flights: each motor's map holds to a few mN below the top of its range; at
    commands of 0.9 and up the firmware asks for tens of mN more than the command sent makes
    (docs/crazyflie.md); taken away, the inward torque 4-10 cm off the axis is smaller, and
    still more than the jet's; the downward force at the wake's edge shrinks most."""
    from aerodock.experiments.swap_flights import read_swap_flights

    logs = read_swap_flights(shared_data("neural-swarm"))
    sent, maps = mc.logs_as_sent(logs)
    assert len(sent) == len(logs)
    assert max(m.residual_sd_n for m in maps) < 0.004
    for vid in ("cf50", "cf51", "cf101"):
        top = [m for m in maps if m.vehicle == vid and m.ceiling_samples >= 50]
        assert top, vid
        assert all(m.ceiling_excess_n > 0.01 for m in top), (vid, top)
    cfg = load_config(EXAMPLES / "crazyflie_small_under_large.toml")
    inertia = {"cf50": cfg.vehicle.inertia_kgm2, "cf51": cfg.vehicle.inertia_kgm2,
               "cf101": cfg.leader.inertia_kgm2}
    radii = {"cf101": cfg.leader.rotor_radius_m}
    params = dict(cfg.downwash.params)
    asked = wt.torque_profile(params, fl.prepare_flights(logs), logs, inertia,
                              rotor_radii_m=radii)
    as_sent = wt.torque_profile(params, fl.prepare_flights(sent), sent, inertia,
                                rotor_radii_m=radii)
    force_asked, force_sent = wt.force_profile(logs), wt.force_profile(sent)
    for pair in ("32 g under 32 g", "67 g under 32 g"):
        for a, s in zip(asked[pair], as_sent[pair], strict=True):
            if 0.04 <= a.offset_lo_m < 0.10:
                assert s.real_nm < 0.95 * a.real_nm, (pair, a, s)  # measured 0.77-0.92
                assert s.real_nm > 1.5 * s.jet_nm, (pair, s)  # measured 1.9-3.5
        edge = [(a, s) for a, s in zip(force_asked[pair], force_sent[pair], strict=True)
                if a.offset_lo_m == pytest.approx(0.08)]
        assert len(edge) == 1
        a, s = edge[0]
        assert s.below_n < 0.95 * a.below_n, (pair, a, s)  # measured 0.48-0.89


def test_sent_where_logged_leaves_other_logs_as_they_are(flight):
    log, sent, volts = commanded(flight, cap=0.93)
    out = mc.sent_where_logged([log, flight])
    assert out[1] is flight  # no motor commands: a simulated world's log, as it is
    np.testing.assert_allclose(out[0].follower_thrust_n,
                               firmware_map(sent, volts[:, None]).sum(axis=1), atol=1e-9)


def test_field_fit_refuses_commands_it_cannot_map_in_one_line(tmp_path, flight):
    """``field fit --commands sent`` on a log whose every command sits at the top: one line
    naming the flight, exit code 2, nothing written."""
    from cli_process import aerodock as run_cli

    from aerodock.flightlog import save_flightlogs

    log, _, _ = commanded(flight, cap=0.93)
    high = replace(log, extra={**log.extra, wt.MOTOR_PWM_KEY:
                               np.full_like(log.extra[wt.MOTOR_PWM_KEY], 0.95)})
    data = tmp_path / "flights.npz"
    save_flightlogs(data, [high])
    proc = run_cli("field", "fit", str(data), "--commands", "sent", "--bootstrap", "0",
                   "--out", str(tmp_path / "o"), check=False)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    assert log.name in lines[0] and "needed to fit the maps" in lines[0]
    assert not (tmp_path / "o").exists()


def test_ceiling_by_vehicle_weighs_each_flight_by_its_samples_at_the_top():
    maps = [mc.MotorMap("a", "cf9", 100, 0.001, 10, 0.020, 0.95),
            mc.MotorMap("b", "cf9", 100, 0.003, 30, 0.040, 0.93),
            mc.MotorMap("c", "cf9", 100, 0.002, 0, float("nan"), 0.85),
            mc.MotorMap("d", "cf1", 100, 0.001, 0, float("nan"), 0.80)]
    rows = mc.ceiling_by_vehicle(maps)
    assert [r["vehicle"] for r in rows] == ["cf1", "cf9"]
    cf1, cf9 = rows
    assert cf9["flights"] == 3 and cf9["ceiling_samples"] == 40
    assert cf9["ceiling_excess_n"] == pytest.approx((10 * 0.020 + 30 * 0.040) / 40)
    assert cf9["residual_sd_n"] == 0.003 and cf9["top_pwm"] == 0.95
    assert cf1["ceiling_samples"] == 0 and np.isnan(cf1["ceiling_excess_n"])


def test_a_log_taken_as_sent_keeps_its_own_maps(flight):
    """The report reads the maps from the logs it fitted: taken as sent, a log still gives the
    maps (and the excess at the ceiling) of the commands it logged."""
    log, _, _ = commanded(flight, cap=0.93)
    sent, motor_map = mc.as_sent(log)
    assert mc.command_maps([sent, flight]) == [motor_map]
