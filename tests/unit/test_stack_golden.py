"""The flight stacks' loops keep their numbers: 40 control periods of the default world
(ArduCopter's attitude loops) and of the Crazyflie world (the firmware's SJC controller), batches
of 1 and 3, against the arrays the code wrote before the loops' helpers took numbers instead of
arrays (``2f2c2c6``: ``PYTHONPATH=<that tree> python tests/unit/test_stack_golden.py OUT.npz``,
run from ``tests/unit``), on the wake the worlds flew then (``worlds.UNSETTLED_WAKE``). Bit for
bit on the machine that wrote the file (its ``numerics_key`` entry, ``tests/numerics_key.py``),
within 1e-9 of each array's largest elsewhere."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numerics_key import KEY_ENTRY, differing, load_golden, numerics_key
from worlds import UNSETTLED_WAKE

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
GOLDEN = Path(__file__).resolve().parents[1] / "data" / "stack_world_2f2c2c6.npz"
_STATE = ("p", "v", "R", "w", "rotor_speed", "autopilot_state", "yaw_setpoint", "thrust_n")


def fly() -> dict[str, np.ndarray]:
    """Both worlds with both position controllers (bench's SimLoop: the follower 0.6 m below
    the leader, 5 cm off the wake's axis), 40 control periods, batches of 1 and 3."""
    from aerodock.bench.simulator import SimLoop
    from aerodock.config import load_config

    out: dict[str, np.ndarray] = {}
    for name, path in (("arducopter", None), ("crazyflie", EXAMPLES / "crazyflie.toml")):
        for n in (1, 3):
            # the wake the file was written with (the worlds' defaults then)
            cfg = load_config(path).with_overrides({"downwash": {"params": UNSETTLED_WAKE}})
            loop = SimLoop(cfg, n, seed=3)
            loop.run(40)
            world = loop.world
            for key in _STATE:
                for who, state in (("lead", world.leader), ("fol", world.follower)):
                    out[f"{name}_{n}_{who}_{key}"] = np.asarray(getattr(state, key))
            out[f"{name}_{n}_bar_p"] = world.bar.p
            out[f"{name}_{n}_attitude"] = world.state.imu.attitude
    return out


def test_the_stacks_fly_their_numbers():
    want, exact = load_golden(GOLDEN)
    now = fly()
    assert now.keys() == want.keys()
    assert any(k.endswith("autopilot_state") and v.shape[1] == 23 for k, v in now.items())
    differ = differing(now, want, exact)
    assert not differ, f"{len(differ)} of {len(now)} arrays differ, e.g. {differ[:4]}"


if __name__ == "__main__":  # the capture, on the code on the path
    np.savez_compressed(sys.argv[1], **fly(), **{KEY_ENTRY: np.array(numerics_key())})
