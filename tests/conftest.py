"""Shared fixtures: the default config, and where the shared real data lives (if present).

Also how the suite shares two cores (``make test`` runs ``pytest -n 2 --dist loadfile``): one
BLAS/OpenMP/torch thread per xdist worker, and the long ``reproduce --quick`` runs scheduled
first so that the rest of the suite runs beside them instead of after them.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

# Two xdist workers on two cores: a second BLAS/OpenMP/torch thread per worker only
# oversubscribes the cores. Set before NumPy (or torch) is imported; subprocesses inherit it.
if int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) > 1:
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import numpy as np
import pytest
from short_mission import short_config
from worlds import EARLIER_WORLD, merged

from aerodock.config import load_config
from aerodock.ingest.data_dir import find_data_dir

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
# The real flights: AERODOCK_DATA_DIR, else ../shared/data beside the clone (aerodock.ingest.
# data_dir); the tests that read them skip when the location does not hold them.
DATA_DIR = find_data_dir(cwd=Path(__file__).resolve().parents[1]).path or SHARED / "data"

# Under xdist (``--dist loadfile``: each file runs on one worker, so a module- or session-scoped
# fixture is built once per file rather than once per worker) the longest files go first, so
# that the last file a worker takes is a short one and both cores stay busy to the end (files
# are handed out in this order as workers free up). First the files with the long ``reproduce
# --smoke`` runs: each run is a subprocess, so while a worker waits for one the other worker goes
# through the rest. Then the files that took 15 s or more of a worker, longest first (their wall
# time in a clean clone's suite beside ../shared, 7 December 2026); the rest in collection order.
_FIRST = (
    "tests/protocol/test_protocol_commands.py",  # a run started as the module begins
    "tests/e2e/test_reproduce.py",
    "tests/studies/test_studies.py",  # about twenty study scripts, one after the other (104 s)
    "tests/fuzz/test_kill.py",  # 92 s
    "tests/fuzz/test_inputs.py",  # 44 s
    "tests/identify/test_wake_fit.py",  # 43 s
    "tests/fuzz/test_audit_tool.py",  # 42 s
    "tests/examples/test_examples.py",  # 36 s
    "tests/identify/test_wake_folds.py",  # 34 s
    "tests/view/test_view.py",  # 28 s
    "tests/fuzz/test_fuzz_config.py",  # 26 s
    "tests/sweep/test_sweep.py",  # 25 s
    "tests/sweep/test_ray_cleanup.py",  # 23 s
    "tests/node/test_node_ros.py",  # 23 s
    "tests/integration/test_cli.py",  # 22 s
    "tests/identify/test_field_score.py",  # 19 s
    "tests/e2e/test_real_data.py",  # 19 s
    "tests/identify/test_wake_torque.py",  # 18 s
    "tests/sweep/test_no_work_lost.py",  # 18 s
    "tests/e2e/test_sim_to_real.py",  # 16 s
    "tests/integration/test_mission.py",  # 15 s
    "tests/ingest/test_ingest_rosbag.py",  # 15 s
)


def _first_rank(item) -> int:
    path = item.nodeid.split("::", 1)[0]
    return _FIRST.index(path) if path in _FIRST else len(_FIRST)


def pytest_collection_modifyitems(config, items):
    if os.environ.get("PYTEST_XDIST_WORKER"):
        items.sort(key=_first_rank)  # stable: the order inside each file is kept


@pytest.fixture(scope="session")
def cfg():
    """The default configuration."""
    return load_config()


IDEAL_WORLD = merged(EARLIER_WORLD, {
    "imu": {"chain": "ideal"},
    "vehicle": {"mass_sd": 0.0, "inertia_sd": 0.0, "torque_coeff_sd": 0.0, "motor_tau_sd": 0.0}})
"""The idealised world of earlier releases: the autopilot and the controllers read the true
attitude, and every vehicle is exactly nominal (for tests of a mechanism's precision), on the
world before issue 39 (``worlds.EARLIER_WORLD``)."""


@pytest.fixture(scope="session")
def ideal_cfg(cfg):
    """The default configuration on the idealised world (:data:`IDEAL_WORLD`)."""
    return cfg.with_overrides(IDEAL_WORLD)


@pytest.fixture(scope="session")
def docking_cfg(cfg):
    """The world before issue 39 (``worlds.EARLIER_WORLD``), where every controller docks: for
    tests of the mission's machinery."""
    return cfg.with_overrides(EARLIER_WORLD)


@pytest.fixture(scope="session")
def short_cfg():
    """The default configuration with the mission's waiting times cut (``short_mission.py``):
    for tests of a property that holds whatever the timing."""
    return short_config()


@pytest.fixture
def rng():
    """A fixed-seed generator."""
    return np.random.default_rng(12345)


@pytest.fixture
def shared_data():
    """``shared_data(*parts)``: a path into the data location (``AERODOCK_DATA_DIR``, else
    ../shared/data); skips when absent (a user's clone without the flights)."""

    def get(*parts: str) -> Path:
        path = DATA_DIR.joinpath(*parts)
        if not path.exists():
            pytest.skip(f"shared data not present: {path}")
        return path

    return get


# The fuzz suite's case tally (``fuzz_helpers.TALLY``): counted in this process, or under xdist
# in the workers, which pass it to the controller; printed once, summed, at the end.
_WORKER_TALLIES: dict[str, int] = {}


def pytest_sessionfinish(session):
    helpers = sys.modules.get("fuzz_helpers")
    if hasattr(session.config, "workeroutput") and helpers is not None and helpers.TALLY:
        session.config.workeroutput["fuzz_tally"] = dict(helpers.TALLY)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    for family, n in getattr(node, "workeroutput", {}).get("fuzz_tally", {}).items():
        _WORKER_TALLIES[family] = _WORKER_TALLIES.get(family, 0) + n


def pytest_terminal_summary(terminalreporter):
    tally = dict(_WORKER_TALLIES)
    helpers = sys.modules.get("fuzz_helpers")
    for family, n in (helpers.TALLY.items() if helpers is not None else ()):
        tally[family] = tally.get(family, 0) + n
    if tally:
        total = sum(tally.values())
        parts = ", ".join(f"{k} {v}" for k, v in sorted(tally.items()))
        terminalreporter.write_line(f"fuzz cases: {total} ({parts}); "
                                    f"scale {os.environ.get('AERODOCK_FUZZ_SCALE', '1')}")


def _untimed_pedantic(target, args=(), kwargs=None, setup=None, rounds=1, warmup_rounds=0,
                     iterations=1):
    """``benchmark.pedantic`` without the timing: the function is called as often as the
    benchmark would call it (warm-up rounds, then rounds x iterations)."""
    result = None
    for _ in range(warmup_rounds + rounds):
        a, k = (args, kwargs or {}) if setup is None else (setup() or (args, kwargs or {}))
        for _ in range(iterations):
            result = target(*a, **k)
    return result


@pytest.fixture
def benchmark(benchmark):
    """pytest-benchmark's fixture. Under xdist it turns itself off and then calls a benchmarked
    function once; here it is called as often as when timed, so a test that checks the state
    afterwards checks the same state. Nothing is timed then: the benchmarks assert nothing about
    speed (``aerodock bench`` measures)."""
    if benchmark.disabled:
        benchmark.pedantic = _untimed_pedantic
    return benchmark
