"""The report: the machine the figures were measured on, the issue's targets, and the rows of
``aerodock bench``'s table."""

from __future__ import annotations

import os
import platform
from pathlib import Path
from typing import Any

import numpy as np

TARGETS = {
    "vehicle_steps_per_s_at_256": 500_000.0,  # rigid-body world (issue 10)
    "point_mass_vehicle_steps_per_s_at_256": 1_000_000.0,
    "rotorpy_sequential_speedup": 20.0,
    "predictor_single_call_us": 50.0,
    "reproduce_quick_s": 300.0,
    "env_reset_s": 0.5,  # DockingEnv.reset, mean over a training loop's resets (issue 25)
    # issue 38 (the compiled step): rigid-body world with controllers, wall time
    "compiled_steps_per_s_at_1": 200_000.0,
    "compiled_steps_per_s_at_256": 3_000_000.0,
    "compiled_steps_per_s_at_1024": 5_000_000.0,
    "compiled_reproduce_quick_s": 90.0,
    "env_steps_per_s_single": 5_000.0,
    "env_steps_per_s_at_128": 200_000.0,
}


def machine_info() -> dict[str, Any]:
    """The machine and software the figures were measured with."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem_gib = None
    try:
        mem_gib = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    except (ValueError, OSError, AttributeError):
        pass
    versions = {"python": platform.python_version(), "numpy": np.__version__}
    for mod in ("scipy", "torch", "onnxruntime", "rotorpy"):
        try:
            from importlib.metadata import version

            versions[mod] = version(mod)
        except Exception:  # noqa: BLE001 - not installed
            versions[mod] = None
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except (OSError, AttributeError):
        load = None
    return {"cpu": cpu, "cores": os.cpu_count(), "load_average_1_5_15_min": load,
            "memory_gib": None if mem_gib is None else round(mem_gib, 1),
            "os": f"{platform.system()} {platform.release()}", "versions": versions}


def _value(fig: Any) -> float | None:
    return fig.get("value") if isinstance(fig, dict) else None


def targets(figs: dict[str, Any]) -> list[dict[str, Any]]:
    """The issue's targets (benchmarks, not tests): measured value, threshold, met or not."""
    sim = figs.get("simulator", {}).get("256", {})
    point_mass = figs.get("simulator_point_mass", {}).get("256", {})
    numpy_pred = figs.get("predictor", {}).get("numpy", {})
    peer = figs.get("peer") or {}
    ratios = peer.get("ratios") or {}
    rows = [
        ("vehicle-steps/s at a batch of 256, rigid-body, physics (World.step)", ">=",
         TARGETS["vehicle_steps_per_s_at_256"], _value(sim.get("physics_only"))),
        ("vehicle-steps/s at a batch of 256, rigid-body, with controllers at 100 Hz", ">=",
         TARGETS["vehicle_steps_per_s_at_256"], _value(sim.get("with_controllers"))),
        ("vehicle-steps/s at a batch of 256, point-mass, with controllers at 100 Hz", ">=",
         TARGETS["point_mass_vehicle_steps_per_s_at_256"],
         _value(point_mass.get("with_controllers"))),
        ("speed-up over RotorPy sequential, single trial", ">=",
         TARGETS["rotorpy_sequential_speedup"], ratios.get("single_trial")),
        ("NumPy predictor, single call (us)", "<", TARGETS["predictor_single_call_us"],
         _value(numpy_pred.get("single_call_us") if isinstance(numpy_pred, dict) else None)),
        ("aerodock reproduce --quick (s)", "<", TARGETS["reproduce_quick_s"],
         _value(figs.get("reproduce_quick_s"))),
        ("DockingEnv.reset, mean over a training loop's resets (s)", "<", TARGETS["env_reset_s"],
         _value(figs.get("gym_env_reset", {}).get("block_mean_reset"))),
    ]
    simulator = figs.get("simulator", {})
    vector_env = figs.get("gym_vector_env", {})
    rows += [  # issue 38
        (f"vehicle-steps/s at a batch of {n}, rigid-body, with controllers (issue 38)", ">=",
         TARGETS[f"compiled_steps_per_s_at_{n}"],
         _value(simulator.get(str(n), {}).get("with_controllers")))
        for n in (1, 256, 1024)]
    rows += [
        ("aerodock reproduce --quick (s, issue 38)", "<", TARGETS["compiled_reproduce_quick_s"],
         _value(figs.get("reproduce_quick_s"))),
        ("env-steps/s, one DockingEnv (issue 38)", ">=", TARGETS["env_steps_per_s_single"],
         _value(vector_env.get("1"))),
        ("env-steps/s, the vector env at 128 (issue 38)", ">=", TARGETS["env_steps_per_s_at_128"],
         _value(vector_env.get("128"))),
    ]
    out = []
    for name, op, threshold, measured in rows:
        met = None if measured is None else (measured >= threshold if op == ">="
                                             else measured < threshold)
        out.append({"target": name, "threshold": f"{op} {threshold:g}", "measured": measured,
                    "met": met})
    return out


def _fmt(value: float | None, unit: str) -> str:
    if value is None:
        return "-"
    if unit == "vehicle-steps/s":
        return f"{value:,.0f}"
    if abs(value) >= 100:
        return f"{value:,.0f}"
    return f"{value:.3g}"


def table_rows(doc: dict[str, Any]) -> list[tuple[str, str, str, str, str]]:
    """(figure, median, spread, unit, note or reason) for every figure of ``doc``."""
    rows: list[tuple[str, str, str, str, str]] = []

    def add(name: str, fig: Any) -> None:
        if not isinstance(fig, dict) or "unit" not in fig:
            return
        unit = fig["unit"]
        if fig.get("value") is None:
            rows.append((name, "null", "", unit, fig.get("reason", "")))
            return
        spread = (f"{_fmt(fig['min'], unit)} - {_fmt(fig['max'], unit)} (x{fig['repeats']})"
                  if fig.get("repeats", 1) > 1 else "one run")
        note = fig.get("note", "")
        if "per_cpu_s" in fig:
            note = f"{note}; {_fmt(fig['per_cpu_s'], unit)} per CPU-second".lstrip("; ")
        if "cpu_s" in fig:
            note = f"{note}; {_fmt(fig['cpu_s'], unit)} s of CPU".lstrip("; ")
        rows.append((name, _fmt(fig["value"], unit), spread, unit, note))

    figs = doc["figures"]
    for key, model in (("simulator", "rigid-body"), ("simulator_point_mass", "point-mass"),
                       ("simulator_python_field", "rigid-body, Python plug-in field")):
        for n, row in figs.get(key, {}).items():
            add(f"simulator {model}, batch {n}, with controllers", row.get("with_controllers"))
            add(f"simulator {model}, batch {n}, physics only", row.get("physics_only"))
    kernels = figs.get("kernels", {})
    add("kernels: fresh process, import + first steps (cached)", kernels.get("cached_s"))
    add("kernels: fresh process, import + first steps (compiling all)", kernels.get("cold_s"))
    for model, row in figs.get("vehicle_step", {}).items():
        for n, fig in row.items():
            add(f"vehicle step {model}, batch {n} (Fleet.step alone)", fig)
    for n, fig in figs.get("gym_vector_env", {}).items():
        add(f"gym vector env, {n} envs", fig)
    for key, label in (("settle_alone", "its trial settled alone"),
                       ("block_first_reset", "settling a block"),
                       ("block_served_reset", "served from the block"),
                       ("block_mean_reset", "mean over a training loop")):
        add(f"gym env reset, {label}", figs.get("gym_env_reset", {}).get(key))
    for key, label in (("trial_1", "docking trial (1)"),
                       ("campaign_100", "docking campaign (100)")):
        add(label, figs.get("docking", {}).get(key))
    for rt in ("numpy", "onnx", "torch"):
        part = figs.get("predictor", {}).get(rt, {})
        if part.get("value", 0) is None:
            add(f"predictor {rt}", part)
            continue
        add(f"predictor {rt}, single call", part.get("single_call_us"))
        add(f"predictor {rt}, controller call", part.get("controller_call_us"))
        add(f"predictor {rt}, per sample in 1024", part.get("batch1024_per_sample_us"))
    add("training so2, 5 min of data", figs.get("training"))
    add("reproduce --quick", figs.get("reproduce_quick_s"))
    mem = figs.get("memory", {})
    add("peak memory, 1024-trial campaign (process)", mem.get("peak_rss_mib"))
    add("memory before the campaign (process)", mem.get("rss_after_imports_mib"))
    add("peak memory, 1024-trial campaign (its arrays)", mem.get("traced_peak_mib"))
    add("1024-trial campaign", mem.get("campaign_wall_s"))
    peer = figs.get("peer") or {}
    for key, fig in peer.items():
        if key.startswith(("aerodock_", "rotorpy_")):
            add(f"peer scenario: {key.replace('_', ' ')}", fig)
    for key, ratio in (peer.get("ratios") or {}).items():
        rows.append((f"ratio: {key.replace('_', ' ')}", f"{ratio:.1f}x", "", "", ""))
    batches = figs.get("peer_crazyflow") or {}
    for key in ("crazyflow", "aerodock_rigid_body", "aerodock_world"):
        part = batches.get(key)
        if isinstance(part, dict) and "unit" in part:  # not measured: its reason
            add(f"peer batches: {key.replace('_', ' ')}", part)
            continue
        for n, fig in (part or {}).items():
            add(f"peer batches: {key.replace('_', ' ')}, batch {n}", fig)
    for n, row in (batches.get("ratios") or {}).items():
        for key, ratio in row.items():
            rows.append((f"ratio at batch {n}: {key.replace('_', ' ')}", f"{ratio:.2g}x", "",
                         "", ""))
    return rows
