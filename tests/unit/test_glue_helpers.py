"""The hot loop's shortcuts equal what they replace: ``frozen_record`` the dataclass constructor,
the IMU ring's mean ``np.mean``, the plain int codes their enums."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from aerodock.downwash.base import BodyState, frozen_record
from aerodock.mission.phases.gate_sensing import GateCode
from aerodock.mission.spec import AbortCode, AbortReason, Phase, PhaseCode
from aerodock.world.gripper import GateState
from aerodock.world.imu import ring_mean
from aerodock.world.platform import BarState
from aerodock.world.vehicles.rigid_body import RigidBodyState


@pytest.mark.parametrize("cls", [BodyState, BarState, RigidBodyState])
def test_frozen_record_is_the_constructors_object(cls):
    """Every class built with ``frozen_record`` stays one its constructor only fills: frozen, no
    ``__post_init__``, no defaults to fill in; the record then equals the constructor's."""
    assert cls.__dataclass_params__.frozen
    assert not hasattr(cls, "__post_init__")
    fields = dataclasses.fields(cls)
    assert all(f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
               for f in fields)
    values = {f.name: np.arange(3.0) + i for i, f in enumerate(fields)}
    quick, slow = frozen_record(cls, **values), cls(**values)
    assert type(quick) is cls and vars(quick).keys() == vars(slow).keys()
    assert all(vars(quick)[k] is vars(slow)[k] for k in values)
    with pytest.raises(dataclasses.FrozenInstanceError):
        quick.p = None


def test_ring_mean_is_numpys_mean_bit_for_bit():
    rng = np.random.default_rng(0)
    for count in range(1, 8):
        for rows in (1, 2, 7, 64):
            ring = [rng.normal(size=(rows, 3)) for _ in range(count + 2)]
            ring[0][0, 0] = -0.0
            if count > 1:
                ring[1][0, 0] = -0.0  # -0.0 + -0.0 onto +0.0 stays +0.0, as in np.mean
            want = np.mean(ring[:count], axis=0)
            oldest = int(rng.integers(len(ring)))  # the ring's head anywhere
            stored = np.stack(ring[-oldest:] + ring[:-oldest]) if oldest else np.stack(ring)
            got = ring_mean(stored, oldest, count)
            assert want.tobytes() == got.tobytes(), (count, rows)


@pytest.mark.parametrize("codes, enum", [(PhaseCode, Phase), (AbortCode, AbortReason),
                                         (GateCode, GateState)])
def test_each_plain_code_is_its_enum_members_value(codes, enum):
    plain = {k: v for k, v in vars(codes).items() if k.isupper()}
    assert plain == {m.name: int(m) for m in enum}
    assert all(type(v) is int for v in plain.values())
