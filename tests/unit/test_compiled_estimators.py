"""The compiled estimators and controller step (:mod:`aerodock.control.estimator_kernels`,
:mod:`aerodock.control.controller_kernel`) give the numbers their NumPy implementation gave, to
the bit.

``tests/data/numpy_controllers_04e0245.npz`` holds what the NumPy code (main at 04e0245, before
the kernels replaced it) computed for :func:`cases`' random inputs: the bias observer from a
reset prior (its gain schedule) and in the steady state, Freyja's bias estimator (its input
clipped, a stale input cleared) and state filter, the accelerometer observer (its motor lag, the
down axis alone, trials held), and 24 state messages of each controller profile (``tuned``,
``ours`` with the accelerometer, ``paper`` with its 50 Hz ticks and Freyja's filters) at batches
of 1 and 3, with and without the terminal gains and a feed-forward. Written by running this file
with that code (``PYTHONPATH=<that tree> python tests/unit/test_compiled_estimators.py OUT.npz``).
The last bits are the machine's: ``numpy_controllers_04e0245.KEY.npz`` is that code's output on
the machine ``KEY`` (``tests/numerics_key.py``; 2594ced's version of this module run with the
04e0245 tree); a machine with no copy is held to 1e-9 of each array's largest.

The inputs are writable contiguous rows, as the mission's are, so the test runs the compiled
variants the warm-up compiles.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numerics_key import differing, load_golden

from aerodock.config import load_config
from aerodock.control.accel_observer import AccelObserver
from aerodock.control.controller import PositionController, Reference
from aerodock.control.freyja_estimator import FreyjaBiasEstimator, FreyjaEstimatorParams
from aerodock.control.freyja_state_filter import FreyjaStateFilter
from aerodock.control.observer import BiasObserver
from aerodock.control.profiles import controller_config
from aerodock.geometry import rpy_to_rotmat

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "numpy_controllers_04e0245.npz"
N = 3  # trials of the estimators' cases
STEPS = 24  # messages of each case


def _rows(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    return rng.normal(0.0, scale, (n, 3))


def estimator_cases(rng: np.random.Generator) -> dict[str, np.ndarray]:
    """The estimators alone, each fed random messages; their estimates after each."""
    out: dict[str, list[np.ndarray]] = {}
    scheduled = BiasObserver(N, 0.01, 4.0, 0.002, 0.02, 0.5)
    steady = BiasObserver(N, 0.01, 2.0, 0.003, 0.01, 0.7)
    scheduled.reset(_rows(rng, N, 1.0), _rows(rng, N, 0.5), None, 2.0)
    steady.reset(_rows(rng, N, 1.0), _rows(rng, N, 0.5), _rows(rng, N, 0.3))
    freyja = FreyjaBiasEstimator(N, 0.01)
    freyja.reset(_rows(rng, N, 1.0), _rows(rng, N, 0.5))
    freyja.t_since_enable_s = 0.5  # part-way through the ramp-in
    stale = FreyjaBiasEstimator(N, 0.25, FreyjaEstimatorParams(bias_limit_mps2=(0.2, 0.3, 0.5)))
    stale.reset(_rows(rng, N, 1.0), _rows(rng, N, 0.5))  # five propagations per message
    filt = FreyjaStateFilter(N, 0.01)
    filt.reset(_rows(rng, N, 1.0), _rows(rng, N, 0.5))
    accel = AccelObserver(N, 0.01, 0.08, 0.02, 0.7, 9.81)
    down = AccelObserver(N, 0.01, 0.05, 0.0, 0.9, 9.81, axes="down")
    accel.reset(0.7 * 9.81)
    for k in range(STEPS):
        p, v, u = _rows(rng, N, 1.0), _rows(rng, N, 0.5), _rows(rng, N, 3.0)
        scheduled.update(p, v, u)
        steady.update(p, v, u)
        freyja.set_input(u)
        freyja.measure(p, v)
        stale.set_input(u)
        stale.measure(p, v)
        fp, fv = filt.measure(p)
        R = rpy_to_rotmat(_rows(rng, N, 0.2))  # noqa: N806
        thrust = rng.uniform(5.0, 9.0, N)
        hold = rng.random(N) < 0.3
        accel.update(_rows(rng, N, 2.0), R, hold if k % 2 else None)
        accel.commanded(thrust, u)
        down.commanded(thrust, u)  # its first command: no reset, the command is the start
        down.update(_rows(rng, N, 2.0), R, hold)
        for name, value in (("bias_scheduled", scheduled.state), ("bias_steady", steady.state),
                            ("freyja", freyja.state), ("freyja_bias", freyja.bias_mps2),
                            ("freyja_stale", stale.state), ("freyja_stale_input",
                                                            stale.input_mps2),
                            ("filter", filt.state), ("filter_pv", np.stack([fp, fv])),
                            ("accel", accel.residual_mps2), ("accel_down", down.residual_mps2)):
            out.setdefault(name, []).append(np.array(value, copy=True))
    return {name: np.stack(values) for name, values in out.items()}


def controller_cases(rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Each profile's controllers over ``STEPS`` messages; every output after each."""
    cfg = load_config()
    out: dict[str, np.ndarray] = {}
    for profile in ("tuned", "ours", "paper"):
        c = controller_config(cfg, profile)
        for n in (1, 3):
            ctl = PositionController(c, n, use_observer=True, has_accelerometer=True)
            ctl.reset(_rows(rng, n, 0.2), _rows(rng, n, 0.1), None, 2.0)
            rows: list[np.ndarray] = []
            for k in range(STEPS):
                ref = Reference(_rows(rng, n, 0.2), _rows(rng, n, 0.1), _rows(rng, n, 1.0),
                                rng.normal(0.0, 0.5, n), rng.normal(0.0, 0.2, n))
                res = ctl.step(_rows(rng, n, 0.2), _rows(rng, n, 0.1), _rows(rng, n, 0.1), ref,
                               rng.random(n) < 0.5 if k % 3 else None,
                               _rows(rng, n, 2.0) if k % 2 else None, _rows(rng, n, 1.0),
                               rng.random(n) < 0.3 if k % 4 == 1 else None)
                cmd = res.command
                rows.append(np.concatenate([
                    np.stack([cmd.roll_rad, cmd.pitch_rad, cmd.yaw_rate_radps, cmd.thrust_n,
                              res.saturated.astype(float)], axis=1),
                    res.applied_accel_mps2, res.feedforward_mps2, res.bias_mps2], axis=1))
            out[f"controller_{profile}_{n}"] = np.stack(rows)
    return out


def cases() -> dict[str, np.ndarray]:
    """Every output for the fixed random inputs, by name."""
    rng = np.random.default_rng(38)
    return {**estimator_cases(rng), **controller_cases(rng)}


def test_the_compiled_estimators_and_step_give_the_numpy_numbers():
    golden, exact = load_golden(GOLDEN)
    now = cases()
    assert sorted(now) == sorted(golden)
    if not exact:  # another machine's copy: its last bits (tests/numerics_key.py)
        assert not differing(now, golden, exact)
        return
    for name in golden:
        np.testing.assert_array_equal(now[name], golden[name], err_msg=name, strict=True)
        assert now[name].tobytes() == golden[name].tobytes(), name  # signed zeros too


if __name__ == "__main__":  # write the golden file with the code on the path
    np.savez_compressed(sys.argv[1], **cases())
