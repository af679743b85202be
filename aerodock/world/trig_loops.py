"""NumPy's float64 cos and sin loops, called from compiled code: the bar's axis in the compiled
period (``np.cos(yaw)``, ``np.sin(yaw)``) and the autopilots' attitude targets
(:func:`aerodock.world.vehicles.targets_kernel.attitude_targets`), with NumPy's numbers to the
bit (the loops of :data:`aerodock.jit.NUMPY_LOOPS` are exp's and its kin; these two live here,
beside the world that reads them)."""

from __future__ import annotations

import ctypes

import numpy as np

from aerodock.jit import JIT_ENABLED, NUMPY_LOOPS_OK, _ufunc_loop

TRIG_COS, TRIG_SIN = 0, 1


def _trig_loops() -> np.ndarray:
    """The addresses of NumPy's float64 cos and sin loops (as :data:`aerodock.jit.NUMPY_LOOPS`
    reads exp's), checked against the ufuncs themselves; zeros when they cannot be read or do
    not give NumPy's numbers (the compiled period is then not used)."""
    loops = np.array([_ufunc_loop(np.cos, "dd"), _ufunc_loop(np.sin, "dd")], dtype=np.int64)
    if not loops.all() or not JIT_ENABLED or not NUMPY_LOOPS_OK:
        return np.zeros(2, dtype=np.int64)
    proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_void_p)
    for size in (1, 3, 7, 64, 257):  # the tails of the SIMD loop too
        x = np.linspace(-40.0, 40.0, size) + 0.1234
        for addr, ufunc in ((loops[TRIG_COS], np.cos), (loops[TRIG_SIN], np.sin)):
            out = np.empty_like(x)
            ptrs = np.array([x.ctypes.data, out.ctypes.data], dtype=np.intp)
            dims = np.array([size], dtype=np.intp)
            steps = np.array([8, 8], dtype=np.intp)
            proto(int(addr))(ptrs.ctypes.data, dims.ctypes.data, steps.ctypes.data, None)
            if not np.array_equal(out, ufunc(x)):
                return np.zeros(2, dtype=np.int64)
    return loops


TRIG_LOOPS = _trig_loops()
TRIG_LOOPS.flags.writeable = False
"""(2,) int64: cos's and sin's loops (``TRIG_COS``, ``TRIG_SIN`` index them); zeros when they
cannot be used (the compiled period then does not run; the attitude targets use the C
library's functions, the same numbers to the last bit or two)."""
