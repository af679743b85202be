"""A kernel marked ``any_layout`` (:mod:`aerodock.jit`) compiles its first signature; a call
that meets a second one seals it to one general signature, after which it takes arrays of any
layout and either writability without compiling again, and gives the numbers its exact signature
gives."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from numba.core import types

from aerodock.jit import JIT_ENABLED, any_layout, general_signature, njit
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


def test_a_second_layout_seals_the_kernel_and_gives_the_same_numbers():
    rng = np.random.default_rng(4)
    a, w = rng.normal(size=(7, 3)), np.array([0.3, -1.7, 2.9])
    exact = np.empty(7)
    _weighted_rows(a, w, exact)
    assert len(_weighted_rows.signatures) == 1  # the first call: its own signature only
    for a2, w2 in ((np.asfortranarray(a), w), (_read_only(a), _read_only(w)),
                   (np.repeat(a, 2, axis=0)[::2], np.repeat(w, 2)[::2])):
        out = np.empty(7)
        _weighted_rows(a2, w2, out)
        np.testing.assert_array_equal(out, exact)
        assert len(_weighted_rows.signatures) == 2  # the first, and the general one
    strided_out = np.empty((7, 2))[:, 0]
    _weighted_rows(a, w, strided_out)
    np.testing.assert_array_equal(strided_out, exact)
    assert len(_weighted_rows.signatures) == 2


def test_the_general_signature_keeps_written_arrays_writable():
    first = (types.Array(types.float64, 2, "C"), types.Array(types.float64, 1, "C", readonly=True),
             types.Array(types.float64, 1, "F"), types.BooleanLiteral(True))
    general = general_signature(first, ((False, False), (False, False), (True, False),
                                        (False, False)))
    assert [t.layout for t in general[:3]] == ["A", "A", "A"]
    assert [t.mutable for t in general[:3]] == [False, False, True]
    assert general[3] == types.boolean


@any_layout("out")
@njit
def _scaled_rows(a: np.ndarray, scale: float, out: np.ndarray) -> None:
    for i in range(a.shape[0]):
        out[i] = a[i] * scale


def test_a_second_signature_that_would_lose_a_value_compiles_instead_of_sealing():
    a = np.arange(4.0)
    out = np.empty(4)
    _scaled_rows(a, 2, out)  # the first call: an integer scale
    _scaled_rows(a, 2.5, out)  # a float: sealing to the integer signature would truncate it
    np.testing.assert_array_equal(out, a * 2.5)
    assert len(_scaled_rows.signatures) == 2 and _scaled_rows._can_compile  # compiled, unsealed
    _scaled_rows(a[::-1], 3, out)  # strided, an integer again: converts, so it seals
    np.testing.assert_array_equal(out, a[::-1] * 3)
    assert not _scaled_rows._can_compile


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
    first = step_rigid_body(state, command, force, None, params, 0.002)
    frozen = replace(state, p=_read_only(state.p), v=_read_only(state.v), w=_read_only(state.w))
    second = step_rigid_body(frozen, command, _read_only(force), None, params, 0.002)
    count = len(rigid_kernel.step_vehicles.signatures)  # sealed by now
    transposed = replace(frozen, R=np.asfortranarray(state.R))
    third = step_rigid_body(transposed, np.asfortranarray(command), force.T.copy().T, None,
                            params, 0.002)
    assert len(rigid_kernel.step_vehicles.signatures) == count
    for other in (second, third):
        for a, b in ((first[0].p, other[0].p), (first[0].v, other[0].v),
                     (first[0].R, other[0].R), (first[0].w, other[0].w),
                     (first[0].rotor_speed, other[0].rotor_speed), (first[1], other[1])):
            np.testing.assert_array_equal(a, b)


_MODULE = '''
import numpy as np
from aerodock.jit import any_layout, njit

@any_layout("out")
@njit
def weighted_rows(a, w, out):
    for i in range(a.shape[0]):
        out[i] = a[i, 0] * w[0] + a[i, 1] * w[1] - a[i, 2] / w[2]
'''
_CALLS = {  # each process's calls, in order
    "c-then-fortran": "a = np.arange(21.0).reshape(7, 3)\nfor x in (a, np.asfortranarray(a)):\n"
                      "    out = np.empty(7); m.weighted_rows(x, np.ones(3), out)\n",
    "read-only": "a = np.arange(21.0).reshape(7, 3); a.flags.writeable = False\n"
                 "out = np.empty(7); m.weighted_rows(a, np.ones(3), out)\n",
    "c": "a = np.arange(21.0).reshape(7, 3)\n"
         "out = np.empty(7); m.weighted_rows(a, np.ones(3), out)\n",
}


def _process(folder, cache, calls: str) -> str:
    import os
    import subprocess
    import sys

    code = f"import numpy as np\nimport layout_kernel as m\n{calls}print(out.tolist())\n"
    env = {**os.environ, "PYTHONPATH": str(folder), "AERODOCK_CACHE_DIR": str(cache),
           "NUMBA_DEBUG_CACHE": "1"}
    env.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run([sys.executable, "-c", code], env=env, cwd=folder, text=True,
                          capture_output=True, timeout=120, check=True)
    return done.stdout


def test_a_process_whose_first_call_meets_new_layouts_loads_the_general_code(tmp_path):
    (tmp_path / "layout_kernel.py").write_text(_MODULE)
    cache = tmp_path / "cache"
    first = _process(tmp_path, cache, _CALLS["c-then-fortran"])
    assert first.count("data saved") == 2  # its exact signature, then the general one
    # another process meets a layout no process has met first: it loads the general code
    later = _process(tmp_path, cache, _CALLS["read-only"])
    assert "data saved" not in later and later.count("data loaded") == 1
    assert later.strip().splitlines()[-1] == first.strip().splitlines()[-1]
    # and one whose first call is the exact signature cached loads that one
    exact = _process(tmp_path, cache, _CALLS["c"])
    assert "data saved" not in exact and exact.count("data loaded") == 1


_CONTIGUOUS_MODULE = '''
import numpy as np
from aerodock.jit import any_layout, njit

@any_layout("out", contiguous=("a",))
@njit
def flat_sum(a, w, out):
    flat = a.reshape(-1)  # C order only: a Fortran array must not reach this code
    for i in range(out.shape[0]):
        out[i] = flat[i] * w[i % w.shape[0]]
'''


def test_a_first_call_loads_the_general_code_only_where_its_arguments_convert(tmp_path):
    """Not where an argument wants C order and comes in Fortran order (the general code would
    read it in the wrong order), nor a read-only one where the kernel writes; and a later call
    of another dtype still compiles (the first call seals nothing)."""
    (tmp_path / "layout_kernel.py").write_text(_CONTIGUOUS_MODULE)
    cache = tmp_path / "cache"
    setup = ("a = np.arange(6.0).reshape(2, 3)\nout = np.empty(6)\n"
             "m.flat_sum(a, np.ones(3), out)\nm.flat_sum(a, np.ones(6)[::2], out)\n")
    assert _process(tmp_path, cache, setup).count("data saved") == 2  # exact, general
    fortran = ("a = np.asfortranarray(np.arange(6.0).reshape(2, 3))\nout = np.empty(6)\n"
               "try:\n    m.flat_sum(a, np.ones(3), out)\n    print('ran', out.tolist())\n"
               "except Exception as err:\n    print('refused', type(err).__name__)\n")
    run = _process(tmp_path, cache, fortran)
    # numba refuses to compile the reshape of a Fortran array, as it did before; the general
    # code (C order assumed) is not borrowed to read it in the wrong order
    assert "refused" in run and "ran" not in run, run
    strided = ("a = np.arange(6.0).reshape(2, 3)\nout = np.empty(6)\n"
               "m.flat_sum(a, np.ones(6)[::2], out)\n"
               "m.flat_sum(a.astype(np.float32), np.ones(3, np.float32), out)\n")
    run = _process(tmp_path, cache, strided)
    assert run.strip().splitlines()[-1] == str([0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    assert run.count("data saved") == 1  # only the float32 call's signature
