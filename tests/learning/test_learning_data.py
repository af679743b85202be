"""Labels (bias removal), datasets (build, save/load, path loading), splits and subsets."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from learning_synth import make_log, make_logs

from aerodock.flightlog import FlightLog, save_flightlogs
from aerodock.learning.datafiles import load_data_paths, load_dataset, save_dataset
from aerodock.learning.dataset import DataError, Dataset, build_dataset
from aerodock.learning.labels import (
    LabelWarning,
    estimate_biases,
    free_air_mask,
    labels_from_log,
    labels_from_logs,
)
from aerodock.learning.splits import split_by_flight, take_minutes, time_block_split_mask


def _simple_log(dp: np.ndarray, force: np.ndarray, bias, name="simple", noise=0.0, seed=0,
                meta=None):
    """Leader level at the origin; obs = cmd + force + bias (+ noise)."""
    n = len(dp)
    rng = np.random.default_rng(seed)
    cmd = rng.normal(0, 1.0, (n, 3))
    quat = np.tile([1.0, 0, 0, 0], (n, 1))
    return FlightLog(
        t_s=np.arange(n) * 0.01, leader_pos_m=np.zeros((n, 3)), leader_vel_mps=np.zeros((n, 3)),
        leader_quat=quat, follower_pos_m=dp, follower_vel_mps=np.zeros((n, 3)),
        follower_quat=quat, follower_cmd_accel_mps2=cmd, follower_thrust_n=np.full(n, 6.9),
        follower_obs_accel_mps2=cmd + force + np.asarray(bias) + noise * rng.normal(size=(n, 3)),
        meta={"name": name, "source": "test", **(meta or {})},
    )


def _under_and_out(n_under=300, n_out=100):
    dp = np.zeros((n_under + n_out, 3))
    dp[:n_under] = [0.05, -0.02, 0.5]  # in the wake
    dp[n_under:] = [1.0, 0.3, 0.5]  # 1.04 m off axis: free air
    force = np.zeros_like(dp)
    force[:n_under] = [0.2, 0.0, 3.0]
    return dp, force


def test_labels_remove_a_constant_bias():
    dp, force = _under_and_out()
    bias = np.array([0.3, -0.2, 0.7])
    log = _simple_log(dp, force, bias)
    assert free_air_mask(log).sum() == 100
    np.testing.assert_allclose(labels_from_log(log), force, atol=1e-12)
    # without the bias removal the labels would be off by exactly the bias
    np.testing.assert_allclose(labels_from_log(log, bias_mps2=np.zeros(3)) - force,
                               np.broadcast_to(bias, force.shape), atol=1e-12)


def test_follower_above_leader_counts_as_free_air():
    dp = np.zeros((50, 3))
    dp[:, 2] = -0.3  # above the leader (NED z down)
    log = _simple_log(dp, np.zeros_like(dp), [0.0, 0.0, 1.0])
    assert free_air_mask(log).all()
    np.testing.assert_allclose(labels_from_log(log), 0.0, atol=1e-12)


def test_flight_without_free_air_borrows_other_flights_bias():
    dp, force = _under_and_out()
    bias = np.array([0.1, 0.2, -0.4])
    with_free = _simple_log(dp, force, bias, name="a")
    only_under = _simple_log(dp[:300], force[:300], bias, name="b", seed=1)
    labels, biases, notes = labels_from_logs([with_free, only_under])
    assert [b.source for b in biases] == ["own", "pooled"]
    np.testing.assert_allclose(labels[1], force[:300], atol=1e-12)
    assert len(notes) == 1 and "b:" in notes[0]
    ds = build_dataset([with_free, only_under])
    assert ds.meta["flights"][1]["bias_source"] == "pooled"
    assert ds.meta["warnings"] == notes


def test_a_flight_without_free_air_borrows_the_bias_of_its_own_vehicle():
    # Two follower vehicles with different biases in one call (a heterogeneous pair's day): a
    # flight of the large one that is never in free air takes the large one's bias, not a
    # median dominated by the small one's flights.
    dp, force = _under_and_out()
    small, large = np.array([0.1, 0.0, 0.2]), np.array([0.3, -0.1, -0.35])
    small_meta = {"follower_mass_kg": 0.032, "follower_rotor_radius_m": 0.0225,
                  "follower_n_rotors": 4}
    large_meta = {"follower_mass_kg": 0.067, "follower_rotor_radius_m": 0.0325,
                  "follower_n_rotors": 4}
    logs = [_simple_log(dp, force, bias, name=f"free{k}", seed=k, meta=meta) for k, (bias, meta)
            in enumerate([(small, small_meta)] * 3 + [(large, large_meta)])]
    under = _simple_log(dp[:300], force[:300], large, name="under", seed=9, meta=large_meta)
    labels, biases, notes = labels_from_logs(logs + [under])
    assert biases[-1].source == "pooled"
    np.testing.assert_allclose(biases[-1].bias, large, atol=1e-12)
    np.testing.assert_allclose(labels[-1], force[:300], atol=1e-12)
    assert "same follower vehicle" in notes[0]
    # a vehicle with no free-air flight of its own falls back on all the others
    lone = _simple_log(dp[:300], force[:300], large, name="lone", seed=9,
                       meta={**large_meta, "follower_mass_kg": 0.5})
    (*_, lone_bias), _ = estimate_biases(logs[:3] + [lone])
    np.testing.assert_allclose(lone_bias.bias, small, atol=1e-12)


def test_no_free_air_anywhere_means_zero_bias_and_a_warning():
    dp, force = _under_and_out()
    log = _simple_log(dp[:300], force[:300], [0.0, 0.0, 0.5], name="lonely")
    with pytest.warns(LabelWarning, match="lonely"):
        lab = labels_from_log(log)
    np.testing.assert_allclose(lab, force[:300] + [0.0, 0.0, 0.5], atol=1e-12)
    ds = build_dataset([log])
    assert ds.meta["flights"][0]["bias_source"] == "none"
    assert any("lonely" in w for w in ds.meta["warnings"])


def test_lowpass_is_off_by_default_and_reduces_noise():
    dp = np.tile([2.0, 0.0, 0.5], (2000, 1))
    log = _simple_log(dp, np.zeros_like(dp), [0, 0, 0], noise=0.5)
    raw = labels_from_log(log)
    filt = labels_from_log(log, lowpass_hz=2.0)
    assert raw.std() > 0.4 and filt.std() < 0.5 * raw.std()
    with pytest.raises(ValueError, match="Nyquist"):
        labels_from_log(log, lowpass_hz=80.0)


def test_label_valid_mask_excludes_samples(rng):
    log = make_log(rng, duration_s=5.0)
    valid = np.ones(log.n_samples, dtype=bool)
    valid[-100:] = False
    log = FlightLog(**{k: getattr(log, k) for k in (
        "t_s", "leader_pos_m", "leader_vel_mps", "leader_quat", "follower_pos_m",
        "follower_vel_mps", "follower_quat", "follower_cmd_accel_mps2", "follower_thrust_n",
        "follower_obs_accel_mps2")}, meta=log.meta, extra={**log.extra, "label_valid": valid})
    assert build_dataset([log]).n == log.n_samples - 100


def test_dataset_contents(synth_logs, synth_ds):
    ds = synth_ds
    log = synth_logs[2]
    sel = ds.flight_id == 2
    np.testing.assert_allclose(ds.x[sel, 0:3], log.follower_pos_m - log.leader_pos_m)
    np.testing.assert_allclose(ds.x[sel, 3:6], log.leader_vel_mps)
    np.testing.assert_allclose(ds.x[sel, 6:9], log.follower_vel_mps)
    np.testing.assert_allclose(ds.y_true_mean[sel], log.extra["true_field_mean_mps2"])
    assert ds.n == sum(lg.n_samples for lg in synth_logs)
    assert ds.minutes == pytest.approx(2.0, rel=1e-6)
    # the synthetic bias (0.1, -0.05, 0.3) is recovered from the free-air samples (up to the
    # wake's tail beyond the free-air radius and the noise)
    for f, lg in zip(ds.meta["flights"], synth_logs):
        tail = np.median(lg.extra["true_field_mean_mps2"][free_air_mask(lg)], axis=0)
        np.testing.assert_allclose(np.subtract(f["bias_mps2"], tail), [0.1, -0.05, 0.3],
                                   atol=0.05)
    json.dumps(ds.meta)  # JSON-serialisable


def test_dataset_save_load_round_trip(tmp_path, synth_ds):
    path = save_dataset(tmp_path / "ds", synth_ds)
    assert path.name == "ds.npz"
    back = load_dataset(path)
    for name in ("x", "leader_R", "y", "flight_id", "t_s", "y_true_mean"):
        np.testing.assert_array_equal(getattr(back, name), getattr(synth_ds, name))
    assert back.meta == synth_ds.meta
    assert not list(tmp_path.glob(".*tmp"))


def test_dataset_without_true_mean_round_trip(tmp_path):
    dp, force = _under_and_out()
    ds = build_dataset([_simple_log(dp, force, [0, 0, 0])])
    assert ds.y_true_mean is None
    assert load_dataset(save_dataset(tmp_path / "d.npz", ds)).y_true_mean is None


def test_load_data_paths_detects_file_kinds(tmp_path, synth_logs, synth_ds):
    save_flightlogs(tmp_path / "logs" / "a.npz", synth_logs[:2])
    save_flightlogs(tmp_path / "logs" / "sub" / "b.npz", synth_logs[2:3])
    save_dataset(tmp_path / "data.npz", synth_ds.subset(synth_ds.flight_id == 5))
    ds = load_data_paths([tmp_path / "logs", tmp_path / "data.npz"])
    assert ds.n_flights == 4
    assert ds.n == sum(lg.n_samples for lg in synth_logs[:4])
    assert len(ds.meta["files"]) == 3
    single = load_data_paths([tmp_path / "logs" / "a.npz"])
    assert single.n_flights == 2
    # other .npz files in a folder (a model's weights) are skipped; a file given twice counts once
    np.savez(tmp_path / "logs" / "weights.npz", W0=np.zeros((2, 2)))
    again = load_data_paths([tmp_path / "logs", tmp_path / "logs" / "a.npz"])
    assert again.n_flights == 3
    assert again.meta["skipped_files"] == [str(tmp_path / "logs" / "weights.npz")]
    with pytest.raises(DataError, match="not an aerodock"):
        load_data_paths([tmp_path / "logs" / "weights.npz"])


def test_load_data_paths_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip file")
    other = tmp_path / "other.npz"
    np.savez(other, a=np.zeros(3))
    (tmp_path / "empty").mkdir()
    cases = [(bad, "bad.npz"), (other, "not an aerodock"), (tmp_path / "missing.npz", "no such"),
             (tmp_path / "empty", "no FlightLog")]
    for path, match in cases:
        with pytest.raises(DataError, match=match) as err:
            load_data_paths([path])
        assert "\n" not in str(err.value)


def test_load_dataset_rejects_pickles_and_bad_contents(tmp_path, synth_ds):
    path = tmp_path / "obj.npz"
    np.savez(path, format=np.array("aerodock-dataset"), version=np.array(1),
             x=np.array([{"evil": 1}], dtype=object))
    with pytest.raises(DataError, match="obj.npz"):
        load_dataset(path)
    ds = synth_ds.subset(np.arange(10))
    x = ds.x.copy()
    x[0, 0] = np.nan
    bad = Dataset(x=x, leader_R=ds.leader_R, y=ds.y, flight_id=ds.flight_id, t_s=ds.t_s,
                  meta=ds.meta)
    with pytest.raises(DataError, match="NaN"):
        load_dataset(save_dataset(tmp_path / "nan.npz", bad))


def test_split_by_flight_has_no_flight_in_both(synth_ds):
    train, held = split_by_flight(synth_ds, 0.3, np.random.default_rng(0))
    names_train, names_held = set(train.flight_names), set(held.flight_names)
    assert names_train and names_held and not names_train & names_held
    assert train.n + held.n == synth_ds.n
    assert 0.15 <= held.n / synth_ds.n <= 0.45
    with pytest.raises(DataError):
        split_by_flight(synth_ds.subset(synth_ds.flight_id == 0), 0.3)


def test_time_block_split_is_contiguous_blocks(synth_ds):
    one = synth_ds.subset(synth_ds.flight_id == 0)
    mask = time_block_split_mask(one, 0.2, np.random.default_rng(0))
    assert 0.1 < mask.mean() < 0.35
    changes = np.count_nonzero(np.diff(mask.astype(int)))
    assert changes <= 2 * 10  # at most 10 blocks of 2 s: whole blocks, not scattered samples


@pytest.mark.parametrize("mode", ["flights", "stratified"])
def test_take_minutes(synth_ds, mode):
    rng = np.random.default_rng(0)
    sub = take_minutes(synth_ds, 0.75, rng, mode=mode)
    assert sub.minutes == pytest.approx(0.75, abs=0.01)
    for k in np.unique(sub.flight_id):  # contiguous in time within each flight
        t = np.sort(sub.t_s[sub.flight_id == k])
        assert np.allclose(np.diff(t), 0.01)
    if mode == "stratified":
        assert sub.n_flights == synth_ds.n_flights
    assert take_minutes(synth_ds, 100.0, rng) is synth_ds
    with pytest.raises(ValueError):
        take_minutes(synth_ds, 0.0, rng)


def test_build_dataset_needs_flights():
    with pytest.raises(DataError):
        build_dataset([])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        build_dataset(make_logs(np.random.default_rng(3), n_flights=2, duration_s=3.0))
