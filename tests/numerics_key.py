"""A key for the machine's floating-point numerics, so that a golden file is held bit for bit only
on a machine that computes as the one that wrote it.

The last bit of NumPy's transcendental functions (its SIMD code for the processor's features),
of ``np.matmul``'s small products (the BLAS kernel OpenBLAS picks for the processor), of SciPy's
Riccati solution and of PyTorch's kernels depends on the processor, not on our code. The key is
a digest of those operations' results on fixed inputs: two machines with the same key compute
them to the same bits. This module imports nothing of aerodock (the goldens are written by
running old commits' code beside it).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np


def _numpy_results() -> list[np.ndarray]:
    x = np.linspace(-20.0, 20.0, 4001)
    y = np.abs(x) + 1e-3
    u = np.linspace(-1.0, 1.0, 4001)
    rng = np.random.default_rng(7)
    a, m1, m2 = rng.normal(size=(64, 3)), rng.normal(size=(64, 3, 3)), rng.normal(size=(64, 3, 3))
    w, z = rng.normal(size=(48, 9)), rng.normal(size=(9, 8))
    out = [np.exp(x), np.log(y), np.sin(x), np.cos(x), np.tan(u), np.tanh(x),
           np.arctan2(x, x[::-1] + 0.5), np.power(y, x / 10.0), np.arcsin(u), np.arccos(u),
           np.sqrt(y), np.expm1(x / 10.0), np.log1p(y),
           np.matmul(a[:, None, :], m1), np.matmul(m1, a[:, :, None]), np.matmul(m1, m2),
           np.matmul(m1.transpose(0, 2, 1), m2), w @ z, w[0] @ z, np.einsum("ij,jk->ik", w, z),
           np.sum(w, axis=1), np.linalg.norm(m1, axis=2)]
    from scipy.linalg import solve_discrete_are

    a2 = np.eye(4) + 0.01 * rng.normal(size=(4, 4))
    b2 = rng.normal(size=(4, 2)) * 0.1
    out.append(solve_discrete_are(a2, b2, np.diag([1.0, 2.0, 3.0, 4.0]), np.eye(2) * 0.5))
    return out


def _torch_results() -> list[np.ndarray]:
    import torch

    g = torch.Generator().manual_seed(7)
    x = torch.randn(48, 9, generator=g, dtype=torch.float64)
    lin = torch.randn(8, 9, generator=g, dtype=torch.float64)
    r = torch.randn(48, 3, 3, generator=g, dtype=torch.float64)
    v = torch.randn(48, 3, generator=g, dtype=torch.float64)
    t = torch.linspace(-20.0, 20.0, 4001, dtype=torch.float64)
    outs = [torch.nn.functional.linear(x, lin), torch.tanh(x @ lin.T), torch.matmul(r, r),
            torch.einsum("nij,nj->ni", r, v), torch.matmul(v[:, None, :], r), torch.sin(t),
            torch.cos(t), torch.atan2(t, t.flip(0) + 0.5), torch.exp(t / 2.0),
            torch.nn.functional.softplus(t), torch.nn.functional.silu(t)]
    return [o.numpy() for o in outs]


def numerics_key(torch: bool = False) -> str:
    """12 hex digits naming this machine's numerics (NumPy and SciPy; PyTorch's too when
    ``torch``)."""
    digest = hashlib.sha256()
    for arr in _numpy_results() + (_torch_results() if torch else []):
        digest.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    return digest.hexdigest()[:12]


def keyed(path: Path, key: str) -> Path:
    """The golden ``path`` as written on the machine ``key`` (``name.KEY.npz``)."""
    return path.with_name(f"{path.stem}.{key}{path.suffix}")


def recorded_goldens(path: Path) -> list[Path]:
    """Every machine's copy of the golden ``path``: the file itself (the first machine it was
    written on) and its keyed copies."""
    return [p for p in [path, *sorted(path.parent.glob(f"{path.stem}.*{path.suffix}"))]
            if p.exists()]


def load_golden(path: Path, torch: bool = False) -> tuple[dict[str, np.ndarray], bool]:
    """(the golden's arrays, whether they were written on a machine with these numerics): the
    keyed copy for this machine's :func:`numerics_key` if there is one, else ``path`` itself
    (written on this machine if it holds a :data:`KEY_ENTRY` equal to this machine's key;
    that entry is not among the arrays returned)."""
    key = numerics_key(torch)
    mine = keyed(path, key)
    with np.load(mine if mine.exists() else path) as data:
        arrays = {k: data[k] for k in data.files if k != KEY_ENTRY}
        written_on = str(data[KEY_ENTRY]) if KEY_ENTRY in data.files else None
    return arrays, mine.exists() or written_on == key


KEY_ENTRY = "numerics_key"
"""A golden's entry naming the machine it was written on (goldens written since the key)."""


def differing(now: dict[str, np.ndarray], golden: dict[str, np.ndarray], exact: bool,
              rtol: float = 1e-9) -> list[str]:
    """The names whose arrays differ from the golden's: bit for bit (NaN equal to NaN) when
    ``exact``, else beyond ``rtol`` of the array's largest magnitude (another machine's last
    bits, grown through the steps that followed)."""
    out = []
    for name, value in now.items():
        want = golden[name]
        if exact:
            same = np.array_equal(value, want, equal_nan=True)
        else:
            scale = float(np.nanmax(np.abs(want))) if np.size(want) else 0.0
            same = (np.shape(value) == np.shape(want) and bool(np.all(
                np.isclose(value, want, rtol=0.0, atol=rtol * max(scale, 1e-300),
                           equal_nan=True))))
        if not same:
            out.append(name)
    return out


if __name__ == "__main__":
    import sys

    print(numerics_key(torch="--torch" in sys.argv))
