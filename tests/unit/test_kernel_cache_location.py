"""Every copy of the same sources loads the same compiled kernels (aerodock.jit's cache
locator): a second clone, a reinstalled wheel or a CI checkout does not compile the world again."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import aerodock
from aerodock.jit import JIT_ENABLED, package_folder

PACKAGE = Path(aerodock.__file__).resolve().parent


def test_a_kernel_file_is_named_by_its_folder_inside_the_package():
    assert package_folder(str(PACKAGE / "world" / "vehicles" / "rigid_kernel.py")) == \
        "aerodock/world/vehicles"
    assert package_folder(str(PACKAGE / "jit.py")) == "aerodock"


def test_a_file_outside_the_package_is_left_to_numba(tmp_path):
    assert package_folder(str(tmp_path / "kernels.py")) is None
    assert package_folder(str(PACKAGE.parent / "tests" / "unit" / "kernels.py")) is None


_CALL = "import aerodock.jit as j; print(j._dot3_sum(1.0, 2.0, 3.0, 4.0, 5.0, 6.0))"


def _run_from(copy: Path, cache: Path) -> str:
    env = {**os.environ, "PYTHONPATH": str(copy), "AERODOCK_CACHE_DIR": str(cache),
           "NUMBA_DEBUG_CACHE": "1"}
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("NUMBA_CACHE_LOCATOR_CLASSES", None)
    done = subprocess.run([sys.executable, "-c", _CALL], cwd=copy, env=env, text=True,
                          capture_output=True, timeout=120, check=True)
    assert done.stdout.strip().splitlines()[-1] == "32.0"
    return done.stdout


@pytest.mark.skipif(not JIT_ENABLED, reason="kernels run as plain Python (AERODOCK_JIT=0)")
def test_a_second_copy_of_the_sources_loads_the_first_copys_machine_code(tmp_path):
    ignore = shutil.ignore_patterns("__pycache__")
    for name in ("first", "second"):
        shutil.copytree(PACKAGE, tmp_path / name / "aerodock", ignore=ignore)
    cache = tmp_path / "cache"
    compiled = _run_from(tmp_path / "first", cache)
    assert "data saved" in compiled and "data loaded" not in compiled
    loaded = _run_from(tmp_path / "second", cache)
    assert "data loaded" in loaded and "data saved" not in loaded
    saved = [p.relative_to(cache) for p in cache.rglob("*.nbc")]
    assert saved and all(p.parts[1] == "aerodock" for p in saved), saved
