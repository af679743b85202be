"""The flight computer's IMU: the body rates and specific force it samples, as its driver and
software filters deliver them (noise, vibration, range, anti-alias low-pass, latency).

Per vehicle and physics step (the IMU's sample rate here; an autopilot's fast loop runs at
400-1000 Hz), batch-first over both vehicles (2n rows, leaders first), component-major (3, 2n):

1. truth: the body rates ``w`` and the specific force ``f = R^T (a - g e3)`` at the step's start
   (``a``: the last step's acceleration);
2. what the sensor adds: gyro noise, accelerometer white noise and motor vibration (growing with
   the square of rotor speed, i.e. with thrust), the accelerometer's residual bias (constant in the
   body frame, per vehicle);
3. the range: readings clip at ``gyro_range_radps`` and ``accel_range_mps2``;
4. the software low-pass (a second-order Butterworth biquad, as ArduPilot's ``LowPassFilter2p``
   at ``INS_GYRO_FILTER``/``INS_ACCEL_FILTER``; a cut-off of 0 passes the samples through);
5. the latency: the filtered sample reaches the autopilot ``delay_steps`` physics steps late.

The filtered, delayed gyro feeds the rate loop and the attitude estimator
(:mod:`aerodock.world.attitude_estimator`); the filtered, delayed accelerometer feeds the
estimator and, rotated to the world with the estimate, the follower's accelerometer reading.
A physics step of both vehicles' chains and estimates is one compiled call (:func:`imu_step`,
the world's ``imu`` term; the noise is drawn before it); the chain's memory (filters, delay
lines, the navigation's ring) is held in preallocated rings it updates in place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from aerodock.borrowed import borrowed, keep_alive
from aerodock.jit import dot3_vecmat, njit, np_arctan2
from aerodock.world.attitude_estimator import estimate_into


@dataclass(frozen=True)
class ImuChainParams:
    """The IMU chain's constants (``[imu]``)."""

    gyro_cutoff_hz: float  # software low-pass of the rates (0: none)
    accel_cutoff_hz: float  # software low-pass of the specific force (0: none)
    delay_steps: int  # transport latency, physics steps
    gyro_range_radps: float
    accel_range_mps2: float


@dataclass(frozen=True)
class Biquad:
    """A second-order Butterworth low-pass (direct form II transposed coefficients)."""

    b0: float
    b1: float
    b2: float
    a1: float
    a2: float

    @classmethod
    def butterworth(cls, cutoff_hz: float, dt_s: float) -> Biquad | None:
        """The filter at ``cutoff_hz`` for samples every ``dt_s`` (None: no filter, or a cut-off
        at or beyond Nyquist)."""
        if cutoff_hz <= 0 or cutoff_hz >= 0.5 / dt_s:
            return None
        k = math.tan(math.pi * cutoff_hz * dt_s)
        q = 1.0 / math.sqrt(2.0)
        norm = 1.0 / (1.0 + k / q + k * k)
        b0 = k * k * norm
        return cls(b0, 2.0 * b0, b0, 2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm)


@dataclass
class FilterState:
    """One signal's filter and delay line, component-major (3, m).

    Attributes:
        z1, z2: (3, m) the low-pass's states (transposed direct form).
        delay: (d, 3, m) the delay line of ``d`` steps, a ring: the samples in it, the oldest at
            ``head`` (d = 0: no delay).
        head: the slot of the line's oldest sample (the next to come out; the new one takes
            its place).

    The step updates these arrays in place (they are the chain's memory, read by nothing else;
    :meth:`ImuState.take_rows` copies them); what comes out of the line is a new array.
    """

    z1: np.ndarray
    z2: np.ndarray
    delay: np.ndarray
    head: int = 0

    @classmethod
    def at(cls, value: np.ndarray, biquad: Biquad | None, delay_steps: int) -> FilterState:
        """A filter settled at ``value`` (3, m) (a vehicle at rest since long)."""
        if biquad is None:
            z1, z2 = np.zeros(value.shape), np.zeros(value.shape)
        else:  # the steady state of the transposed direct form for a constant input
            z2 = np.ascontiguousarray((biquad.b2 - biquad.a2) * value)
            z1 = np.ascontiguousarray((biquad.b1 - biquad.a1) * value + z2)
        delay = np.empty((delay_steps, *value.shape))
        delay[:] = value
        return cls(z1, z2, delay)

    def take_cols(self, cols: np.ndarray) -> FilterState:
        """The filter and delay line of the columns ``cols`` (copies, C-ordered as the step's
        kernels take them)."""
        return FilterState(np.ascontiguousarray(self.z1[:, cols]),
                           np.ascontiguousarray(self.z2[:, cols]),
                           np.ascontiguousarray(self.delay[:, :, cols]), self.head)


def filter_sample(state: FilterState, sample: np.ndarray, biquad: Biquad | None) -> np.ndarray:
    """Filter one sample (3, m) and return what comes out of the delay line (a new array; the
    state is updated in place: the compiled low-pass and delay line of the world's chain,
    :func:`imu_step`)."""
    sample = np.ascontiguousarray(sample, dtype=float)
    out = np.empty(sample.shape)
    state.head = _filter_sample_into(sample, biquad_coeffs(biquad), state.z1, state.z2,
                                     state.delay, state.head, out)
    return out


@dataclass
class ImuState:
    """Both vehicles' IMU chains and attitude estimates (2n rows, leaders first).

    Attributes:
        gyro, accel: each signal's filter and delay line, component-major (3, 2n).
        gyro_filter, accel_filter: the low-passes (None: none).
        bias_body_mps2: (2n, 3) each accelerometer's residual bias, body frame.
        attitude: (2n, 3, 3) the flight computers' attitude estimates, body to world.
        accel_ring: (k, 2n, 3) the true accelerations of the last ``k`` steps, a ring (the
            oldest at ``ring_head``), from which the navigation's acceleration is taken one
            control period at a time, motion-capture late.
        ring_head: the slot of the ring's oldest sample (this step's takes its place).
        nav_accel_mps2: (2n, 3) the acceleration the navigation knows (the estimator's
            compensation).
        gyro_radps: (2n, 3) the rates out of the chain this step (what the rate loop reads).
        accel_t: (3, 2n) the specific force out of the chain this step.

    The chain's memory (the filters' states, the delay lines, the ring and the navigation's
    acceleration) is updated in place by the step: nothing else reads it, and
    :meth:`take_rows` copies it. What the chain delivers (``gyro_radps``, ``accel_t``,
    ``attitude``) is a new array every step, so a reference kept to it keeps its values.
    """

    gyro: FilterState
    accel: FilterState
    gyro_filter: Biquad | None
    accel_filter: Biquad | None
    bias_body_mps2: np.ndarray
    attitude: np.ndarray
    accel_ring: np.ndarray
    nav_accel_mps2: np.ndarray
    gyro_radps: np.ndarray
    accel_t: np.ndarray
    ring_head: int = 0

    def take_rows(self, rows: np.ndarray) -> ImuState:
        """The chains of the vehicles at ``rows`` of the 2n batch (copies; the component-major
        arrays by column; C-ordered, as the step's kernels take them)."""
        return ImuState(
            gyro=self.gyro.take_cols(rows), accel=self.accel.take_cols(rows),
            gyro_filter=self.gyro_filter, accel_filter=self.accel_filter,
            bias_body_mps2=self.bias_body_mps2[rows], attitude=self.attitude[rows],
            accel_ring=np.ascontiguousarray(self.accel_ring[:, rows]),
            nav_accel_mps2=np.ascontiguousarray(self.nav_accel_mps2[rows]),
            gyro_radps=self.gyro_radps[rows], accel_t=self.accel_t[:, rows],
            ring_head=self.ring_head)


def start_imu(attitude: np.ndarray, bias_body_mps2: np.ndarray, gravity_mps2: float,
              chain: ImuChainParams, gyro_filter: Biquad | None, accel_filter: Biquad | None,
              ring_steps: int) -> ImuState:
    """The chains of vehicles at rest since long, level at ``attitude`` (2n, 3, 3); the
    estimates equal to it (the vehicles have stood still before take-off)."""
    m = attitude.shape[0]
    rates = np.zeros((3, m))
    force = -gravity_mps2 * attitude[:, 2, :].T + bias_body_mps2.T  # R^T (-g e3) + bias
    return ImuState(
        gyro=FilterState.at(rates, gyro_filter, chain.delay_steps),
        accel=FilterState.at(force, accel_filter, chain.delay_steps),
        gyro_filter=gyro_filter, accel_filter=accel_filter, bias_body_mps2=bias_body_mps2,
        attitude=attitude.copy(), accel_ring=np.zeros((ring_steps, m, 3)),
        nav_accel_mps2=np.zeros((m, 3)), gyro_radps=np.zeros((m, 3)), accel_t=force,
    )


def imu_coeffs(ims: ImuState) -> tuple[np.ndarray, np.ndarray]:
    """The chain's two low-passes as the kernels read them (:func:`biquad_coeffs`, kept on
    the state)."""
    hit = ims.__dict__.get("_coeffs")
    if hit is None:
        hit = (biquad_coeffs(ims.gyro_filter), biquad_coeffs(ims.accel_filter))
        ims.__dict__["_coeffs"] = hit
    return hit


# -- the compiled chain -------------------------------------------------------------------------
def biquad_coeffs(biquad: Biquad | None) -> np.ndarray:
    """(6,) ``(on, b0, b1, b2, a1, a2)`` for the kernels (``on`` 0: samples pass through)."""
    if biquad is None:
        return np.zeros(6)
    return np.array([1.0, biquad.b0, biquad.b1, biquad.b2, biquad.a1, biquad.a2])


@njit
def _biquad(x: float, on: bool, b0: float, b1: float, b2: float, a1: float, a2: float,
            z1: float, z2: float) -> tuple[float, float, float]:
    """One sample through the transposed direct form: (output, new z1, new z2); ``on`` False:
    the sample passes through (the states unchanged)."""
    if not on:
        return x, z1, z2
    forward = b0 * x
    out = forward + z1
    a = b1 * x
    a -= a1 * out
    b = forward if b2 == b0 else b2 * x  # the low-pass's b2 is b0: its product is at hand
    return out, a + z2, b - a2 * out


@njit
def imu_samples(n: int, lo: int, hi: int, w: np.ndarray, gyro_draws: np.ndarray,
                gyro_sd: float,
                gyro_range: float, gyro_c: np.ndarray, gz1: np.ndarray, gz2: np.ndarray,
                lead_accel: np.ndarray, fol_accel: np.ndarray, gravity: float,
                rot: np.ndarray, bias: np.ndarray, thrust: np.ndarray, hover: np.ndarray,
                accel_noise_sq: float, vibration: float, accel_draws: np.ndarray,
                accel_range: float, accel_c: np.ndarray, az1: np.ndarray, az2: np.ndarray,
                noise: np.ndarray, gyro_out: np.ndarray, gz1_new: np.ndarray,
                gz2_new: np.ndarray, accel_out: np.ndarray, az1_new: np.ndarray,
                az2_new: np.ndarray, ring: np.ndarray) -> None:
    """Both vehicles' IMU samples at the step's start (2n rows, leaders first; the draws
    (6, n) per trial: the leader's three, then the follower's): the gyro's rates plus noise
    ``noise`` (3, 2n; none when ``gyro_sd`` is 0), clipped and low-passed (``gyro_out``,
    3, 2n, before the delay line); the specific force ``R^T (a - g e3)`` plus the residual bias,
    white noise and vibration (its sd growing with the thrust), clipped and low-passed
    (``accel_out``); the true acceleration for the navigation's ring (``ring``, 2n x 3). The
    filters' new states go to ``gz1_new`` ... ``az2_new``, which may be ``gz1`` ... ``az2``
    themselves (each element is read before it is written). Only trials ``lo..hi`` (their
    leader's row and their follower's): a block of trials, each row its own."""
    nb = hi - lo
    for jj in range(2 * nb):
        j = lo + jj if jj < nb else n + lo + (jj - nb)
        h, i = (0, j) if j < n else (1, j - n)
        if h == 0:
            a0, a1, a2 = lead_accel[i, 0], lead_accel[i, 1], lead_accel[i, 2] - gravity
        else:
            a0, a1, a2 = fol_accel[i, 0], fol_accel[i, 1], fol_accel[i, 2] - gravity
        for c in range(3):
            x = w[j, c]
            if gyro_sd != 0.0:
                e = gyro_draws[3 * h + c, i] * gyro_sd
                noise[c, j] = e
                x = x + e
            x = max(x, -gyro_range) if x == x else x
            x = min(x, gyro_range) if x == x else x
            gyro_out[c, j], gz1_new[c, j], gz2_new[c, j] = _biquad(
                x, gyro_c[0] != 0.0, gyro_c[1], gyro_c[2], gyro_c[3], gyro_c[4], gyro_c[5],
                gz1[c, j], gz2[c, j])
        load = thrust[j] / hover[j]
        vib = vibration * load
        sd = math.sqrt(accel_noise_sq + vib * vib)
        for c in range(3):
            f = dot3_vecmat(a0, a1, a2, rot[j, 0, c], rot[j, 1, c], rot[j, 2, c])
            f += bias[j, c]
            f = f + accel_draws[3 * h + c, i] * sd
            f = max(f, -accel_range) if f == f else f
            f = min(f, accel_range) if f == f else f
            accel_out[c, j], az1_new[c, j], az2_new[c, j] = _biquad(
                f, accel_c[0] != 0.0, accel_c[1], accel_c[2], accel_c[3], accel_c[4],
                accel_c[5], az1[c, j], az2[c, j])
        ring[j, 0] = a0 + 0.0
        ring[j, 1] = a1 + 0.0
        ring[j, 2] = a2 + gravity


@njit
def _delay_slot(line: np.ndarray, head: int, out: np.ndarray, n: int, lo: int,
                hi: int) -> np.ndarray:
    """Where a sample entering the delay ``line`` (d, 3, 2n) is written: with a line, its
    oldest sample (slot ``head``) is copied to ``out`` (3, 2n: what leaves the line now) and
    that slot is returned; without one (d = 0), ``out`` itself (the sample leaves at once).
    Only the columns of trials ``lo..hi`` are copied (their leader's and their follower's)."""
    if line.shape[0] == 0:
        return out
    slot = line[head]
    for c in range(3):
        for j in range(lo, hi):
            out[c, j] = slot[c, j]
        for j in range(n + lo, n + hi):
            out[c, j] = slot[c, j]
    return slot


@njit
def _next_slot(ring: np.ndarray, head: int) -> int:
    """The slot after ``head`` of a ring of ``ring.shape[0]`` slots (0 for an empty ring)."""
    k = ring.shape[0]
    return (head + 1) % k if k else 0


@njit
def _filter_sample_into(sample: np.ndarray, c: np.ndarray, z1: np.ndarray, z2: np.ndarray,
                        line: np.ndarray, head: int, out: np.ndarray) -> int:
    """:func:`filter_sample`: :func:`_biquad` over a (3, m) sample, the states ``z1``, ``z2``
    updated in place, through the delay ``line`` (slot ``head`` the oldest) into ``out``; the
    line's new head."""
    into = _delay_slot(line, head, out, 0, 0, sample.shape[1])
    for row in range(sample.shape[0]):
        for col in range(sample.shape[1]):
            into[row, col], z1[row, col], z2[row, col] = _biquad(
                sample[row, col], c[0] != 0.0, c[1], c[2], c[3], c[4], c[5], z1[row, col],
                z2[row, col])
    return _next_slot(line, head)


def ring_mean(ring: np.ndarray, oldest: int, count: int) -> np.ndarray:
    """(m, 3) the mean of the ``count`` oldest samples of ``ring`` (k, m, 3), the oldest at slot
    ``oldest`` (compiled: :func:`_ring_mean_into`, as :func:`imu_step` takes the navigation's
    acceleration)."""
    out = np.empty(ring.shape[1:])
    _ring_mean_into(np.ascontiguousarray(ring, dtype=float), oldest, count, out)
    return out


@njit
def _ring_mean_into(ring: np.ndarray, oldest: int, count: int, out: np.ndarray) -> None:
    """The mean of the ``count`` oldest samples of ``ring`` (k, m, 3), the oldest at slot
    ``oldest``, into ``out`` (m, 3): NumPy's ``np.mean(samples, axis=0)`` bit for bit (the
    samples added in order, oldest first, onto +0.0, then divided by the count)."""
    k = ring.shape[0]
    for j in range(ring.shape[1]):
        for c in range(ring.shape[2]):
            total = 0.0
            for i in range(count):
                total += ring[(oldest + i) % k, j, c]
            out[j, c] = total / count


@njit
def imu_step(loops: np.ndarray, n: int, lo: int, hi: int, w: np.ndarray,
             gyro_draws: np.ndarray,
             gyro_sd: float, gyro_range: float, gyro_c: np.ndarray, gz1: np.ndarray,
             gz2: np.ndarray, gyro_line: np.ndarray, gyro_head: int, lead_accel: np.ndarray,
             fol_accel: np.ndarray, gravity: float, rot: np.ndarray, bias: np.ndarray,
             thrust: np.ndarray, hover: np.ndarray, accel_noise_sq: float, vibration: float,
             accel_draws: np.ndarray, accel_range: float, accel_c: np.ndarray,
             az1: np.ndarray, az2: np.ndarray, accel_line: np.ndarray, accel_head: int,
             ring: np.ndarray, ring_head: int, step_index: int, substeps: int,
             nav_accel: np.ndarray, lead_att_ext: np.ndarray, fol_att_ext: np.ndarray,
             rot_hat: np.ndarray, k_p: float, k_yaw: float, dt: float, noise: np.ndarray,
             gyro_out: np.ndarray, accel_out: np.ndarray,
             rot_hat_out: np.ndarray) -> tuple[int, int, int]:
    """One physics step of both vehicles' chains and estimates (2n rows, leaders first), in one
    call: the samples (:func:`imu_samples`, its arguments up to ``az2``; the filters' states
    ``gz1``, ``gz2``, ``az1``, ``az2`` updated in place), each signal through its delay line
    (``gyro_line``, ``accel_line``: (d, 3, 2n) rings, the oldest at ``gyro_head``,
    ``accel_head``) into ``gyro_out`` and ``accel_out`` (3, 2n); the true acceleration into the
    navigation's ``ring`` (k, 2n, 3; the oldest at ``ring_head``) and, at the first step of each
    control period (``step_index`` a multiple of ``substeps``), the mean of its ``substeps``
    oldest samples into ``nav_accel`` (2n, 3); the external heading, the yaw of the motion
    capture's attitudes ``lead_att_ext`` and ``fol_att_ext`` (n, 3, 3: NumPy's ``arctan2``,
    its own loop in ``loops``); and the attitude estimate's step from ``rot_hat`` into
    ``rot_hat_out`` (:func:`~aerodock.world.attitude_estimator.estimate_into`, gains ``k_p``,
    ``k_yaw``, 1/s, over ``dt`` s). Returns the new heads of the gyro's and the
    accelerometer's delay lines and of the ring. Only trials ``lo..hi`` (their leader's row and
    their follower's; ``0, n`` for all): each row is its own, so blocks of trials compute the
    batch's numbers (the compiled period's blocks)."""
    gyro_into = _delay_slot(gyro_line, gyro_head, gyro_out, n, lo, hi)
    accel_into = _delay_slot(accel_line, accel_head, accel_out, n, lo, hi)
    imu_samples(n, lo, hi, w, gyro_draws, gyro_sd, gyro_range, gyro_c, gz1, gz2, lead_accel,
                fol_accel, gravity, rot, bias, thrust, hover, accel_noise_sq, vibration,
                accel_draws,
                accel_range, accel_c, az1, az2, noise, gyro_into, gz1, gz2, accel_into, az1,
                az2, ring[ring_head])
    ring_head = _next_slot(ring, ring_head)
    count = min(substeps, ring.shape[0])
    owner = np.empty(2 * n)  # each half's heading, without joining the rotations first
    (yaw_ext,) = borrowed((owner,))
    for a, b in ((lo, hi), (n + lo, n + hi)):  # the block's leaders, then its followers
        if step_index % substeps == 0:
            _ring_mean_into(ring[:, a:b], ring_head, count, nav_accel[a:b])
    np_arctan2(loops, lead_att_ext[lo:hi, 1, 0], lead_att_ext[lo:hi, 0, 0], yaw_ext[lo:hi])
    np_arctan2(loops, fol_att_ext[lo:hi, 1, 0], fol_att_ext[lo:hi, 0, 0], yaw_ext[n + lo:n + hi])
    for a, b in ((lo, hi), (n + lo, n + hi)):
        estimate_into(loops, rot_hat[a:b], gyro_out[:, a:b], accel_out[:, a:b], nav_accel[a:b],
                      yaw_ext[a:b], k_p, k_yaw, dt, rot_hat_out[a:b])
    keep_alive(owner)
    return _next_slot(gyro_line, gyro_head), _next_slot(accel_line, accel_head), ring_head
