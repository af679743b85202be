"""The world's ``imu`` term as one compiled call (:func:`aerodock.world.imu.imu_step`) gives the
numbers of the sequence it replaced, to the bit: the samples kernel, the filters' new states, the
delay lines and the navigation's ring as Python lists (append, pop the oldest), the period's
mean by ``np.mean``, the external heading by ``np.arctan2``, then ``estimate_step``.

The reference below is that sequence (``imu`` of ``aerodock/world/terms.py`` before the fused
call) on its own copy of the chain, fed each step the inputs the world's term read and the same
random numbers; its chain is never re-synchronised with the world's, so any difference in a
state would grow and show.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import numpy as np
import pytest

from aerodock.rng import TrialRNG, standard_normal_t
from aerodock.world import World, hover_command, terms
from aerodock.world.attitude_estimator import estimate_step
from aerodock.world.imu import (
    Biquad,
    FilterState,
    ImuState,
    biquad_coeffs,
    filter_sample,
    imu_samples,
    ring_mean,
)
from aerodock.world.step import WORLD_STEP, Term


@dataclass
class ListChain:
    """The chain as the old term held it: lists of arrays, oldest first."""

    z: list[np.ndarray]  # gyro z1, z2, accel z1, z2
    gyro_delay: list[np.ndarray]
    accel_delay: list[np.ndarray]
    ring: list[np.ndarray]
    nav: np.ndarray
    attitude: np.ndarray

    @classmethod
    def of(cls, ims: ImuState) -> ListChain:
        """The lists' form of the world's chain (its rings read from their heads)."""
        def oldest_first(ring: np.ndarray, head: int) -> list[np.ndarray]:
            return [ring[(head + i) % len(ring)].copy() for i in range(len(ring))]

        return cls([ims.gyro.z1.copy(), ims.gyro.z2.copy(), ims.accel.z1.copy(),
                    ims.accel.z2.copy()], oldest_first(ims.gyro.delay, ims.gyro.head),
                   oldest_first(ims.accel.delay, ims.accel.head),
                   oldest_first(ims.accel_ring, ims.ring_head), ims.nav_accel_mps2.copy(),
                   ims.attitude.copy())


def list_step(ref: ListChain, ims: ImuState, inputs: dict, rng, params) -> dict:
    """The old term's sequence after the draws are made, on ``ref`` (advanced)."""
    n = inputs["n"]
    m = 2 * n
    chain = params.imu.chain
    gyro_sd = params.imu.gyro_noise_radps
    gyro_draws = standard_normal_t(rng, n, 6) if gyro_sd else np.zeros((6, 0))
    accel_draws = standard_normal_t(rng, n, 6)
    noise = np.empty((3, m))
    gyro_t, accel_t = np.empty((3, m)), np.empty((3, m))
    gz1, gz2, az1, az2 = (np.empty((3, m)) for _ in range(4))
    ring = np.empty((m, 3))
    imu_samples(n, 0, n, inputs["w"], gyro_draws, gyro_sd, chain.gyro_range_radps,
                biquad_coeffs(ims.gyro_filter), ref.z[0], ref.z[1], inputs["lead_accel"],
                inputs["fol_accel"], params.vehicle.gravity_mps2, inputs["rot"],
                ims.bias_body_mps2, inputs["thrust"], inputs["hover"],
                params.vehicle.accel_noise_mps2 ** 2, params.imu.accel_vibration_mps2,
                accel_draws, chain.accel_range_mps2, biquad_coeffs(ims.accel_filter), ref.z[2],
                ref.z[3], noise, gyro_t, gz1, gz2, accel_t, az1, az2, ring)
    if ims.gyro_filter is not None:
        ref.z[0], ref.z[1] = gz1, gz2
    if ims.accel_filter is not None:
        ref.z[2], ref.z[3] = az1, az2
    for line, sample in ((ref.gyro_delay, gyro_t), (ref.accel_delay, accel_t)):
        if line:
            line.append(sample)
            sample = line.pop(0)
        if line is ref.gyro_delay:
            gyro_t = sample
        else:
            accel_t = sample
    ref.ring.append(ring)
    ref.ring.pop(0)
    if inputs["step_index"] % params.substeps == 0:
        ref.nav = np.mean(ref.ring[:params.substeps], axis=0)
    att = inputs["att"]
    yaw_ext = np.empty(m)
    np.arctan2(att[2][:, 1, 0], att[2][:, 0, 0], out=yaw_ext[:n])
    np.arctan2(att[5][:, 1, 0], att[5][:, 0, 0], out=yaw_ext[n:])
    ref.attitude = estimate_step(ref.attitude, gyro_t, accel_t, ref.nav, yaw_ext,
                                 params.imu.estimator, params.dt_s)
    return {"noise": noise.T if gyro_sd else None, "gyro": gyro_t.T, "accel_t": accel_t,
            "attitude": ref.attitude}


def same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    """Equal to the bit (shape, every byte, -0.0 and NaN payloads included)."""
    if a is None or b is None:
        return a is None and b is None
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def checked_step(log: list[int]) -> tuple[Term, ...]:
    """The world's step with its ``imu`` term checked against :func:`list_step` every step."""
    refs: dict[int, ListChain] = {}

    def imu(state, frame, params) -> None:
        ims = state.imu
        ref = refs.setdefault(id(ims), ListChain.of(ims))
        n = state.n
        latency = params.latency_steps
        inputs = {"n": n, "w": frame.both.w.copy(), "rot": frame.rot.copy(),
                  "lead_accel": state.leader_accel.copy(),
                  "fol_accel": state.follower_accel.copy(), "thrust": frame.both.thrust_n.copy(),
                  "hover": state.constants.hover_thrust_n, "step_index": state.step_index,
                  "att": tuple(a.copy() for a in
                               state.history[(state.step_index - latency) % (latency + 1)])}
        rng = copy.deepcopy(state.rng)
        terms.imu(state, frame, params)
        want = list_step(ref, ims, inputs, rng, params)
        step = state.step_index
        assert same(frame.gyro_noise_radps, want["noise"]), step
        assert same(frame.gyro_radps, want["gyro"]) and same(ims.gyro_radps, want["gyro"]), step
        assert same(ims.accel_t, want["accel_t"]), step
        assert same(frame.attitude_est, want["attitude"]), step
        assert same(ims.attitude, want["attitude"]), step
        assert same(ims.nav_accel_mps2, ref.nav), step
        for got, ref_z in zip((ims.gyro.z1, ims.gyro.z2, ims.accel.z1, ims.accel.z2), ref.z,
                              strict=True):
            assert same(got, ref_z), step
        now = ListChain.of(ims)
        for got, ref_list in ((now.gyro_delay, ref.gyro_delay),
                              (now.accel_delay, ref.accel_delay), (now.ring, ref.ring)):
            assert len(got) == len(ref_list), step
            assert all(same(a, b) for a, b in zip(got, ref_list, strict=True)), step
        # the same numbers drawn: both streams stand at the same place
        assert same(standard_normal_t(copy.deepcopy(state.rng), n, 2),
                    standard_normal_t(rng, n, 2)), step
        log.append(step)

    return tuple(Term(t.name, imu) if t.name == "imu" else t for t in WORLD_STEP)


CHAINS = {
    "default": {},  # 80 and 20 Hz low-passes, one step of latency, ring of 5 + 5 steps
    "no filter, no latency": {"imu": {"gyro_cutoff_hz": 0.0, "accel_cutoff_hz": 0.0,
                                      "latency_s": 0.0}},
    "long latency, clipping, no heading": {
        "imu": {"latency_s": 0.006, "gyro_range_dps": 10.0, "accel_range_g": 1.02,
                "accel_cutoff_hz": 0.0, "heading_gain_radps": 0.0},
        "mocap": {"latency_s": 0.004}},
    "noiseless gyro": {"imu": {"gyro_noise_radps": 0.0, "gyro_cutoff_hz": 0.0,
                               "latency_s": 0.004}},
}


@pytest.mark.parametrize("n", [1, 3, 64])
@pytest.mark.parametrize("chain", list(CHAINS))
def test_the_fused_term_gives_the_list_sequences_numbers(cfg, chain, n):
    """Over 60 steps (twelve control periods, the ring and the delay lines wrapping many
    times): every output and every state equal the old sequence's, bit for bit."""
    c = cfg.with_overrides({"imu": {"chain": "filtered"}}, source="test").with_overrides(
        CHAINS[chain], source="test")
    log: list[int] = []
    world = World(c, n, TrialRNG(11, n), step=checked_step(log))
    world.reset(np.array([0.0, 0.0, -3.0]), np.array([0.3, 0.0, -2.4]))
    rng = np.random.default_rng(n)
    world.follower = replace(world.follower, w=rng.normal(0.0, 0.4, (n, 3)))
    world.leader = replace(world.leader, w=rng.normal(0.0, 0.1, (n, 3)))
    assert world.state.imu.gyro.delay.shape[0] == world.params.imu.chain.delay_steps
    lead = hover_command(world.params.leader_vehicle, n)
    fol = hover_command(world.params.vehicle, n)
    for _ in range(60):
        world.step(lead, fol)
    assert log == list(range(60))
    if chain == "long latency, clipping, no heading":  # the ranges do clip
        assert np.any(np.abs(world.state.imu.gyro_radps) == np.deg2rad(10.0))


def test_the_rings_heads_travel_with_taken_rows(cfg):
    """A trial taken out of a batch mid-flight (its chain's rings at their heads) flies on as
    the batch's row does, to the bit."""
    n = 3
    c = cfg.with_overrides({"imu": {"chain": "filtered", "latency_s": 0.006}}, source="test")
    world = World(c, n, TrialRNG(5, n))
    world.reset(np.array([0.0, 0.0, -3.0]), np.array([0.3, 0.0, -2.4]))
    lead = hover_command(world.params.leader_vehicle, n)
    fol = hover_command(world.params.vehicle, n)
    for _ in range(13):  # the heads mid-ring
        world.step(lead, fol)
    assert world.state.imu.ring_head != 0 and world.state.imu.gyro.head != 0
    taken = world.take_rows(np.array([1]))
    lead1 = hover_command(world.params.leader_vehicle, 1)
    fol1 = hover_command(world.params.vehicle, 1)
    for _ in range(17):
        world.step(lead, fol)
        taken.step(lead1, fol1)
        whole, one = world.state.imu, taken.state.imu
        assert same(one.attitude, whole.attitude[[1, n + 1]])
        assert same(one.accel_t, whole.accel_t[:, [1, n + 1]])
        assert same(one.nav_accel_mps2, whole.nav_accel_mps2[[1, n + 1]])


def _biquad_reference(x, c, z1, z2):
    """The transposed direct form, elementwise in NumPy (each operation one rounding, as the
    kernel's)."""
    forward = c[1] * x
    out = forward + z1
    a = c[2] * x
    a = a - c[4] * out
    b = forward if c[3] == c[1] else c[3] * x
    return out, a + z2, b - c[5] * out


@pytest.mark.parametrize("cutoff_hz", [0.0, 35.0])
@pytest.mark.parametrize("delay_steps", [0, 1, 3])
def test_filter_sample_is_the_list_delay_line(cutoff_hz, delay_steps):
    """``filter_sample``'s ring gives what the old list (append, pop the oldest) gave."""
    quad = Biquad.butterworth(cutoff_hz, 0.002)
    c = biquad_coeffs(quad)
    rng = np.random.default_rng(delay_steps)
    start = rng.normal(size=(3, 4))
    state = FilterState.at(start, quad, delay_steps)
    z1, z2 = state.z1.copy(), state.z2.copy()
    line = [start.copy() for _ in range(delay_steps)]
    for _ in range(25):
        x = rng.normal(size=(3, 4))
        if quad is None:
            want = x
        else:
            want, z1, z2 = _biquad_reference(x, c, z1, z2)
        if line:
            line.append(want)
            want = line.pop(0)
        got = filter_sample(state, x, quad)
        assert same(got, want)
        if quad is not None:
            assert same(state.z1, z1) and same(state.z2, z2)


def test_ring_mean_is_numpys_mean_from_any_head():
    """The navigation's mean over a ring read from its head equals ``np.mean`` of the samples
    oldest first, bit for bit (-0.0 included)."""
    rng = np.random.default_rng(2)
    for k in (1, 4, 10):
        ring = rng.normal(size=(k, 7, 3))
        ring[:, 0, 0] = -0.0
        for head in range(k):
            for count in range(1, k + 1):
                samples = [ring[(head + i) % k] for i in range(count)]
                assert same(ring_mean(ring, head, count), np.mean(samples, axis=0))


def test_the_kernels_heading_is_numpys_arctan2():
    """The external heading as :func:`imu_step` takes it (NumPy's own ``arctan2`` loop called
    from compiled code, on the strided column views of (n, 3, 3) rotations) equals
    ``np.arctan2`` on the same views, to the bit, for one trial as for many."""
    import numba

    from aerodock.jit import NUMPY_LOOPS, np_arctan2

    @numba.njit
    def heading(loops, att, out):
        np_arctan2(loops, att[:, 1, 0], att[:, 0, 0], out)

    rng = np.random.default_rng(4)
    for n in (1, 3, 8, 64):
        for rep in range(200):
            att = rng.normal(size=(2 * n, 3, 3)) * 10.0 ** rng.integers(-3, 3)
            att[rng.integers(2 * n), 1, 0] = -0.0
            half = att[:n] if rep % 2 else att[n:]
            got, want = np.empty(2 * n), np.empty(2 * n)
            heading(NUMPY_LOOPS, half, got[n:])
            np.arctan2(half[:, 1, 0], half[:, 0, 0], out=want[n:])
            assert same(got[n:], want[n:]), (n, rep)
