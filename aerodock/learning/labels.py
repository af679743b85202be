"""Training labels: the follower's observed minus commanded acceleration, de-biased.

The paper estimates the downwash force on the follower as ``f_ext = a_obs - u_1:3`` and treats the
other differences between commanded and observed acceleration (thrust-scale errors, mounting,
model mismatch) as constant biases that exist with or without the leader's wake (its footnote 2).
This module removes that bias per flight:

* raw label ``a_obs - u_1:3`` (m/s², NED), optionally low-pass filtered (zero-phase Butterworth,
  off by default: the network already averages turbulence out, and filtering blurs the wake's edge);
* *free-air* samples are those where the follower cannot be in the leader's wake: its horizontal
  distance from the leader exceeds a free-air radius or it is above the leader (``dp_z < 0``,
  NED). The radius is the caller's, else the flight's own (``meta["free_air_radius_m"]``: the
  simulated curriculum records one in proportion to its free-air waypoints, so a Crazyflie
  world's flights carry theirs), else 0.6 m (several wake radii at the default curriculum's
  separations);
* a flight's bias is the per-axis median of its free-air raw labels; a flight with no free-air
  samples borrows the median over the free-air samples of the other flights of the same call
  *with the same follower vehicle* (its ``meta``'s ``follower_mass_kg``, ``follower_rotor_radius_m``
  and ``follower_n_rotors``; logs that do not say count as one vehicle), as the bias is a property
  of the vehicle (thrust scale, mounting: the paper's footnote 2); only if none of those has any,
  over all the other flights' free-air samples; if there are none at all, the bias is 0 and a
  warning is recorded. (Pooling over every flight mixed the vehicles of a heterogeneous pair: on
  swap_sl 00-07 the large Crazyflie's flights below the small one took a z-bias of +0.07 m/s², its
  own flights above measure -0.31 to -0.39.)

A FlightLog may carry ``extra["label_valid"]`` (T,), truthy where a sample is a valid label (e.g.
False after the follower has docked and hangs on the cables): invalid samples are excluded from
the bias estimate and, in :mod:`aerodock.learning.dataset`, from the data set.

Torque labels (for the ``so2-wrench`` model) come the same way from a log's torque extras
(:mod:`aerodock.world.torque_sensing`; body FRD, N m): ``tau_ext = obs_torque - rotor_torque -
bias`` with ``obs_torque = extra["follower_obs_torque_nm"]`` (``J dw/dt + w x J w`` from the gyro)
and ``rotor_torque = extra["follower_rotor_torque_nm"]`` (what the rotors explain from their
measured speeds), de-biased per flight from the same free-air samples by the same functions
(:func:`debias`). A log without both extras has no torque labels.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from aerodock.flightlog import FlightLog

FREE_AIR_RADIUS_M = 0.6
FREE_AIR_META_KEY = "free_air_radius_m"
VALID_KEY = "label_valid"
OBS_TORQUE_KEY = "follower_obs_torque_nm"
ROTOR_TORQUE_KEY = "follower_rotor_torque_nm"
TORQUE_KEYS = (OBS_TORQUE_KEY, ROTOR_TORQUE_KEY)


class LabelWarning(UserWarning):
    """A label could not be de-biased as intended (e.g. a flight with no free-air samples)."""


@dataclass(frozen=True)
class BiasEstimate:
    """Constant bias removed from one flight's labels.

    Attributes:
        bias: (3,) bias in the labels' units and frame (force: m/s², NED; torque: N m, FRD).
        source: ``"own"`` (this flight's free-air samples), ``"pooled"`` (other flights'),
            ``"given"`` (passed in) or ``"none"`` (no free-air samples anywhere: 0).
        n_free_air: number of this flight's free-air samples.
    """

    bias: np.ndarray
    source: str
    n_free_air: int

    @property
    def bias_mps2(self) -> np.ndarray:
        """The bias of force labels, m/s², NED (the same array as :attr:`bias`)."""
        return self.bias


def valid_mask(log: FlightLog) -> np.ndarray:
    """Boolean (T,) mask of samples usable as labels (``extra["label_valid"]``, else all)."""
    if VALID_KEY not in log.extra:
        return np.ones(log.n_samples, dtype=bool)
    mask = np.asarray(log.extra[VALID_KEY])
    if mask.shape != (log.n_samples,):
        raise ValueError(f"{log.name}: extra {VALID_KEY!r} must have shape ({log.n_samples},)")
    return mask.astype(bool)


def free_air_radius_of(log: FlightLog, free_air_radius_m: float | None = None) -> float:
    """The free-air radius for ``log``, m: ``free_air_radius_m`` when given, else the flight's
    own (``meta["free_air_radius_m"]``), else :data:`FREE_AIR_RADIUS_M`."""
    if free_air_radius_m is not None:
        return float(free_air_radius_m)
    own = log.meta.get(FREE_AIR_META_KEY)
    return FREE_AIR_RADIUS_M if own is None else float(own)


def free_air_mask(log: FlightLog, free_air_radius_m: float | None = None) -> np.ndarray:
    """Boolean (T,) mask of samples where the follower is out of the leader's wake.

    Out of the wake: horizontal distance (world north-east plane) greater than the free-air
    radius (:func:`free_air_radius_of`), or the follower above the leader (``dp_z < 0`` in NED).
    Samples marked invalid (``extra["label_valid"]``) are never free-air samples.
    """
    dp = log.follower_pos_m - log.leader_pos_m
    horizontal = np.hypot(dp[:, 0], dp[:, 1])
    radius = free_air_radius_of(log, free_air_radius_m)
    return ((horizontal > radius) | (dp[:, 2] < 0.0)) & valid_mask(log)


def follower_vehicle_of(log: FlightLog) -> tuple:
    """The follower vehicle a log says it flew: ``meta``'s ``follower_mass_kg``,
    ``follower_rotor_radius_m`` and ``follower_n_rotors`` (each None where it does not say).
    Flights with equal tuples share a label bias pool (:func:`estimate_biases`)."""
    out = []
    for key in ("follower_mass_kg", "follower_rotor_radius_m", "follower_n_rotors"):
        try:
            out.append(float(log.meta[key]))
        except (KeyError, TypeError, ValueError):
            out.append(None)
    return tuple(out)


def raw_labels(
    log: FlightLog, *, lowpass_hz: float | None = None, lowpass_order: int = 2
) -> np.ndarray:
    """``a_obs - u_1:3`` (T, 3), m/s², NED, optionally low-pass filtered.

    Args:
        log: the flight.
        lowpass_hz: cut-off of a zero-phase Butterworth filter; ``None`` (default) for none.
        lowpass_order: filter order.

    Raises:
        ValueError: a cut-off at or above the Nyquist frequency, or not positive.
    """
    diff = log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2
    if lowpass_hz is None:
        return diff
    return lowpass(diff, log.t_s, lowpass_hz, order=lowpass_order, where=log.name)


def has_torque(log: FlightLog) -> bool:
    """True when ``log`` carries the torque extras torque labels are made from."""
    return all(key in log.extra for key in TORQUE_KEYS)


def raw_torque_labels(
    log: FlightLog, *, lowpass_hz: float | None = None, lowpass_order: int = 2
) -> np.ndarray:
    """``obs_torque - rotor_torque`` (T, 3), N m, the follower's body frame (FRD), optionally
    low-pass filtered as :func:`raw_labels`.

    Raises:
        ValueError: the log lacks a torque extra (one line naming it), or it has the wrong shape.
    """
    arrays = []
    for key in TORQUE_KEYS:
        if key not in log.extra:
            raise ValueError(f"{log.name}: no torque labels: the log lacks extra {key!r} "
                             "(rigid-body simulation or a log with gyro and rotor speeds)")
        arr = np.asarray(log.extra[key], dtype=float)
        if arr.shape != (log.n_samples, 3):
            raise ValueError(f"{log.name}: extra {key!r} has shape {arr.shape}, expected "
                             f"({log.n_samples}, 3)")
        arrays.append(arr)
    diff = arrays[0] - arrays[1]
    if lowpass_hz is None:
        return diff
    return lowpass(diff, log.t_s, lowpass_hz, order=lowpass_order, where=log.name)


def lowpass(
    signal: np.ndarray, t_s: np.ndarray, cutoff_hz: float, *, order: int = 2, where: str = "signal"
) -> np.ndarray:
    """Zero-phase Butterworth low-pass of ``signal`` (T, k) sampled at times ``t_s`` (T,).

    The sample rate is taken from the median time step. Too-short signals are returned unfiltered
    with a :class:`LabelWarning`.
    """
    from scipy.signal import butter, sosfiltfilt

    if not cutoff_hz > 0:
        raise ValueError(f"{where}: low-pass cut-off must be positive, got {cutoff_hz}")
    if len(t_s) < 2:
        return signal.copy()
    fs = 1.0 / float(np.median(np.diff(t_s)))
    if cutoff_hz >= fs / 2:
        raise ValueError(
            f"{where}: low-pass cut-off {cutoff_hz} Hz is not below the Nyquist frequency "
            f"{fs / 2:.4g} Hz"
        )
    sos = butter(order, cutoff_hz, btype="low", fs=fs, output="sos")
    padlen = 3 * (2 * len(sos) + 1)
    if len(t_s) <= padlen:
        warnings.warn(f"{where}: too short to low-pass filter; left unfiltered", LabelWarning,
                      stacklevel=2)
        return signal.copy()
    return sosfiltfilt(sos, signal, axis=0)


def estimate_biases(
    logs: list[FlightLog],
    *,
    free_air_radius_m: float | None = None,
    lowpass_hz: float | None = None,
    raw: list[np.ndarray] | None = None,
) -> tuple[list[BiasEstimate], list[str]]:
    """Per-flight constant biases and the warnings their estimation raised.

    Args:
        logs: flights (estimated together so that a flight without free-air samples can borrow
            the others').
        free_air_radius_m: see :func:`free_air_mask`.
        lowpass_hz: low-pass cut-off applied to the raw labels first (see :func:`raw_labels`).
        raw: precomputed raw labels, one (T, 3) array per log.

    Returns:
        ``(biases, warnings)``: one :class:`BiasEstimate` per log, and human-readable warnings.
    """
    if raw is None:
        raw = [raw_labels(log, lowpass_hz=lowpass_hz) for log in logs]
    masks = [free_air_mask(log, free_air_radius_m) for log in logs]
    vehicles = [follower_vehicle_of(log) for log in logs]
    notes: list[str] = []
    out: list[BiasEstimate] = []
    for i, (log, lab, mask) in enumerate(zip(logs, raw, masks, strict=True)):
        n_free = int(mask.sum())
        if n_free:
            out.append(BiasEstimate(np.median(lab[mask], axis=0), "own", n_free))
            continue
        others = [j for j in range(len(logs)) if j != i and masks[j].any()]
        same = [j for j in others if vehicles[j] == vehicles[i]]
        pool = same or others
        if pool:
            pooled = np.concatenate([raw[j][masks[j]] for j in pool])
            out.append(BiasEstimate(np.median(pooled, axis=0), "pooled", 0))
            whose = "of the same follower vehicle" if same else "(none of its vehicle has any)"
            notes.append(
                f"{log.name}: no free-air samples (horizontal distance > "
                f"{free_air_radius_of(log, free_air_radius_m)} m or "
                f"above the leader); used the median of the other flights' free-air samples "
                f"{whose}"
            )
        else:
            out.append(BiasEstimate(np.zeros(3), "none", 0))
            notes.append(
                f"{log.name}: no free-air samples in this or any other flight; labels not "
                "de-biased (bias 0)"
            )
    return out, notes


def labels_from_logs(
    logs: list[FlightLog],
    *,
    free_air_radius_m: float | None = None,
    lowpass_hz: float | None = None,
) -> tuple[list[np.ndarray], list[BiasEstimate], list[str]]:
    """De-biased labels for several flights at once (biases pooled as described above).

    Returns:
        ``(labels, biases, warnings)``: one (T_i, 3) array and one :class:`BiasEstimate` per
        log, and human-readable warnings (also what :func:`build_dataset` records).
    """
    return debias(logs, [raw_labels(log, lowpass_hz=lowpass_hz) for log in logs],
                  free_air_radius_m=free_air_radius_m)


def torque_labels_from_logs(
    logs: list[FlightLog],
    *,
    free_air_radius_m: float | None = None,
    lowpass_hz: float | None = None,
) -> tuple[list[np.ndarray], list[BiasEstimate], list[str]]:
    """De-biased torque labels ``obs - rotor - bias`` (T_i, 3), N m, body FRD, of several
    flights (as :func:`labels_from_logs`; biases pooled over these flights' free-air samples).

    Raises:
        ValueError: a log without the torque extras (see :func:`raw_torque_labels`).
    """
    return debias(logs, [raw_torque_labels(log, lowpass_hz=lowpass_hz) for log in logs],
                  free_air_radius_m=free_air_radius_m)


def debias(
    logs: list[FlightLog], raw: list[np.ndarray], *, free_air_radius_m: float | None = None
) -> tuple[list[np.ndarray], list[BiasEstimate], list[str]]:
    """Raw labels (one (T_i, 3) array per log, any quantity) minus each flight's bias
    (:func:`estimate_biases`): ``(labels, biases, warnings)``."""
    biases, notes = estimate_biases(logs, free_air_radius_m=free_air_radius_m, raw=raw)
    return [r - b.bias for r, b in zip(raw, biases, strict=True)], biases, notes


def labels_from_log(
    log: FlightLog,
    *,
    free_air_radius_m: float | None = None,
    lowpass_hz: float | None = None,
    bias_mps2: np.ndarray | None = None,
) -> np.ndarray:
    """De-biased labels ``a_obs - u_1:3 - bias`` (T, 3), m/s², NED, for one flight.

    Args:
        log: the flight.
        free_air_radius_m: see :func:`free_air_mask`.
        lowpass_hz: optional low-pass cut-off (see :func:`raw_labels`); off by default.
        bias_mps2: (3,) bias to remove; by default the median of the flight's free-air labels.
            With no free-air samples the bias is 0 and a :class:`LabelWarning` is issued (use
            :func:`labels_from_logs` to borrow other flights' free-air samples instead).
    """
    raw = raw_labels(log, lowpass_hz=lowpass_hz)
    if bias_mps2 is not None:
        return raw - np.asarray(bias_mps2, dtype=float).reshape(3)
    (bias,), notes = estimate_biases([log], free_air_radius_m=free_air_radius_m, raw=[raw])
    for note in notes:
        warnings.warn(note, LabelWarning, stacklevel=2)
    return raw - bias.bias
