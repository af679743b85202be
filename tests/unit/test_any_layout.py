"""A kernel marked ``any_layout`` (:mod:`aerodock.jit`) compiles once more after its first call,
then takes arrays of any layout and either writability without compiling again, and gives the
numbers its exact signature gives."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from aerodock.jit import JIT_ENABLED, any_layout, general_signature, njit, seal
from aerodock.world.vehicles import rigid_kernel
from aerodock.world.vehicles.rigid_body import RigidBodyParams, hover_rigid_state, step_rigid_body

pytestmark = pytest.mark.skipif(not JIT_ENABLED, reason="plain Python compiles nothing")


@any_layout("out")
@njit
def _weighted_rows(a: np.ndarray, w: np.ndarray, out: np.ndarray) -> None:
    for i in range(a.shape[0]):
        out[i] = a[i, 0] * w[0] + a[i, 1] * w[1] - a[i, 2] / w[2]


def _read_only(a: np.ndarray) -> np.ndarray:
    a = np.array(a)
    a.flags.writeable = False
    return a


def test_a_sealed_kernel_takes_other_layouts_without_compiling_and_gives_the_same_numbers():
    rng = np.random.default_rng(4)
    a, w = rng.normal(size=(7, 3)), np.array([0.3, -1.7, 2.9])
    exact = np.empty(7)
    _weighted_rows(a, w, exact)
    seal(_weighted_rows)
    assert len(_weighted_rows.signatures) == 2  # the first, and the general one
    for a2, w2 in ((np.asfortranarray(a), w), (_read_only(a), _read_only(w)),
                   (np.repeat(a, 2, axis=0)[::2], np.repeat(w, 2)[::2])):
        out = np.empty(7)
        _weighted_rows(a2, w2, out)
        np.testing.assert_array_equal(out, exact)
    strided_out = np.empty((7, 2))[:, 0]
    _weighted_rows(a, w, strided_out)
    np.testing.assert_array_equal(strided_out, exact)
    assert len(_weighted_rows.signatures) == 2
    seal(_weighted_rows)  # sealing again changes nothing
    assert len(_weighted_rows.signatures) == 2


def test_the_general_signature_keeps_written_arrays_writable():
    first = _weighted_rows.signatures[0] if _weighted_rows.signatures else None
    if first is None:
        _weighted_rows(np.ones((2, 3)), np.ones(3), np.empty(2))
        first = _weighted_rows.signatures[0]
    general = general_signature(first, ((False, False), (False, False), (True, False)))
    assert [t.layout for t in general] == ["A", "A", "A"]
    assert [t.mutable for t in general] == [False, False, True]


def test_a_name_that_is_not_an_argument_is_refused():
    def kernel(a, out):
        out[0] = a[0]

    with pytest.raises(ValueError, match="no argument"):
        any_layout("result")(njit(kernel))


def test_the_vehicles_step_with_frozen_and_transposed_arrays_compiles_nothing_new(cfg):
    params = RigidBodyParams.from_config(cfg)
    n = 3
    state = hover_rigid_state(params, np.zeros((n, 3)), 0.0, np.array([1.0, 0.95, 1.05]))
    command = np.array(state.rotor_speed) * np.array([[1.02], [0.99], [1.01]])
    force = np.array([[0.1, 0.0, -0.2], [0.0, 0.05, 0.0], [-0.1, 0.1, 0.3]])
    first, accel = step_rigid_body(state, command, force, None, params, 0.002)
    count = len(rigid_kernel.step_vehicles.signatures)
    frozen = replace(state, p=_read_only(state.p), v=_read_only(state.v),
                     R=np.asfortranarray(state.R), w=_read_only(state.w))
    second, accel2 = step_rigid_body(frozen, np.asfortranarray(command), _read_only(force), None,
                                     params, 0.002)
    assert len(rigid_kernel.step_vehicles.signatures) == count
    for a, b in ((first.p, second.p), (first.v, second.v), (first.R, second.R),
                 (first.w, second.w), (first.rotor_speed, second.rotor_speed), (accel, accel2)):
        np.testing.assert_array_equal(a, b)
