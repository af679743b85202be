"""The compiled world step gives the NumPy step's numbers, to the bit.

``tests/data/numpy_step_ea3179b.npz`` holds what the NumPy implementation of the world (main at
``ea3179b``, before the kernels of :mod:`aerodock.jit`) computed for the scenarios of
:func:`fly` and :func:`field_outputs`: that commit ran this module's functions
(``python tests/unit/test_compiled_step.py OUT.npz``). The kernels replaced that code operation
by operation, NumPy's transcendental functions and the BLAS kernel's product order included, so
every array must be equal, not close, on a machine that computes as the one that wrote the
file. Those last bits are the processor's (``tests/numerics_key.py``): each machine's copy is
``numpy_step_ea3179b.KEY.npz``, written by that commit's code on it (5e3a521's version of this
module, ``PYTHONPATH=<ea3179b tree> python test_compiled_step.py OUT.npz``); on a machine with
no copy of its own, the arrays must be within 1e-9 of the largest (another processor's last
bits, grown over 40 control periods: 2.8e-13 at most between the two machines recorded).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from numerics_key import differing, load_golden
from worlds import EARLIER_WAKE, EARLIER_WORLD

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "numpy_step_ea3179b.npz"
# (the golden file's key, the state's attribute): the generic autopilot's rate integral is
# the state's autopilot_state since the flight stacks (issue 39)
_STATE = (("p", "p"), ("v", "v"), ("R", "R"), ("w", "w"), ("rotor_speed", "rotor_speed"),
          ("rate_integral", "autopilot_state"), ("yaw_setpoint", "yaw_setpoint"),
          ("thrust_n", "thrust_n"))


GOLDEN_WORLD = EARLIER_WORLD
"""The defaults of ea3179b, where the golden file was written, that have changed since (issue
39: ArduCopter's loops with ArduPilot's inertia rule, and the wake fitted with the logged torque,
are the defaults now)."""


def fly() -> dict[str, np.ndarray]:
    """The default world with both position controllers (bench's SimLoop: the follower 0.6 m
    below the leader, 5 cm off the wake's axis), 40 control periods, batches of 1 and 3; and the
    point-mass world beside it."""
    from aerodock.bench.simulator import SimLoop
    from aerodock.config import load_config

    out: dict[str, np.ndarray] = {}
    cfg = load_config(None).with_overrides(GOLDEN_WORLD, source="test")
    for model in ("rigid-body", "point-mass"):
        for n in (1, 3):
            loop = SimLoop(cfg.with_overrides({"vehicle": {"model": model}}, source="test"), n,
                           seed=3)
            loop.run(40)
            world = loop.world
            for key, name in _STATE:
                for who, state in (("lead", world.leader), ("fol", world.follower)):
                    if hasattr(state, name):
                        out[f"{model}_{n}_{who}_{key}"] = np.asarray(getattr(state, name))
            out[f"{model}_{n}_bar_p"] = world.bar.p
            out[f"{model}_{n}_cable"] = world.cable_force_n
            if world.state.imu is not None:
                out[f"{model}_{n}_attitude"] = world.state.imu.attitude
    return out


def field_outputs() -> dict[str, np.ndarray]:
    """The jet's every output for random leader and follower states, with the default
    parameters and with exponents 1 and 2, a torque gain, no planar part and no gusts."""
    from jets import default_jet

    from aerodock.downwash.base import BodyState
    from aerodock.geometry import rpy_to_rotmat
    from aerodock.rng import TrialRNG

    out: dict[str, np.ndarray] = {}
    cases = ({}, {"ingest_exponent": 1.0}, {"ingest_exponent": 2.0, "disk_torque_gain": 3.0},
             {"planar_ratio": 0.0, "turb_lateral": 0.0})
    for case, kwargs in enumerate(cases):
        n = 4
        rng = np.random.default_rng(case)
        field = default_jet(**{**EARLIER_WAKE, **kwargs})
        field.reset(n, TrialRNG(7, n))
        for step in range(6):
            lp = rng.normal(0, 0.1, (n, 3)) + [0, 0, -2]
            lead = BodyState(lp, rng.normal(0, 0.3, (n, 3)),
                             rpy_to_rotmat(rng.normal(0, 0.1, (n, 3))),
                             np.abs(rng.normal(7, 1, n)), np.full(n, 0.7))
            fp = lp + rng.normal(0, 0.15, (n, 3)) + [0, 0, 0.4 if step % 3 else -0.1]
            fol = BodyState(fp, rng.normal(0, 0.3, (n, 3)),
                            rpy_to_rotmat(rng.normal(0, 0.2, (n, 3))), np.full(n, 7.0),
                            np.full(n, 0.7))
            force, torque = field.wrench(lead, fol, field.rotor_offsets_body_m, 0.002)
            outputs = {
                "force": force, "torque": torque, "body": field.body_force_n(lead, fol),
                "bar": field.bar_force_n(lead, lp + [0.01, 0, 0.3], rng.normal(0, 0.1, (n, 3)),
                                         0.0015, 0.002, np.tile([1.0, 0, 0], (n, 1))),
                "accel": field.acceleration(lead, fol, 0.002),
                "mean": field.mean_acceleration(lead, fol),
                "mean_torque": field.mean_disk_torque_nm(lead, fol),
                "wind": field.wind_mps(lead, fp), **field.turbulence(lead, fol)}
            for name, value in outputs.items():
                out[f"jet{case}_{step}_{name}"] = np.asarray(value)
    return out


@pytest.fixture(scope="module")
def golden() -> tuple[dict[str, np.ndarray], bool]:
    return load_golden(GOLDEN)


def test_the_world_flies_the_numpy_steps_numbers(golden):
    want, exact = golden
    now = fly()
    assert now.keys() == {k for k in want if not k.startswith("jet")}
    differ = differing(now, want, exact)
    assert not differ, f"{len(differ)} of {len(now)} arrays differ, e.g. {differ[:4]}"


def test_the_jet_gives_the_numpy_fields_numbers(golden):
    want, exact = golden
    now = field_outputs()
    assert now.keys() == {k for k in want if k.startswith("jet")}
    differ = differing(now, want, exact)
    assert not differ, f"{len(differ)} of {len(now)} arrays differ, e.g. {differ[:4]}"


def test_numpys_loops_are_called_from_compiled_code():
    """The kernels' exp, log, power and arctan2 are NumPy's own (its SIMD code rounds otherwise
    than the C library's in a few per cent of arguments)."""
    from aerodock import jit

    assert jit.NUMPY_LOOPS_OK
    x = np.linspace(-30.0, 30.0, 2001)
    y = np.linspace(1e-3, 40.0, 2001)
    out = np.empty_like(x)
    jit.np_exp(jit.NUMPY_LOOPS, x, out)
    np.testing.assert_array_equal(out, np.exp(x))
    jit.np_log(jit.NUMPY_LOOPS, y, out)
    np.testing.assert_array_equal(out, np.log(y))
    jit.np_power(jit.NUMPY_LOOPS, y, x / 11.0, out)
    np.testing.assert_array_equal(out, np.power(y, x / 11.0))
    jit.np_arctan2(jit.NUMPY_LOOPS, x, y - 20.0, out)
    np.testing.assert_array_equal(out, np.arctan2(x, y - 20.0))
    strided = np.empty((3, 2001))
    jit.np_exp(jit.NUMPY_LOOPS, x[::-1], strided[1])  # negative and row strides
    np.testing.assert_array_equal(strided[1], np.exp(x[::-1]))


if __name__ == "__main__":  # the capture on the NumPy code
    np.savez_compressed(sys.argv[1], **fly(), **field_outputs())
