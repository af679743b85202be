"""aerodock against RotorPy on the same scenario and the same vehicle, both timed in one run.

Scenario: one quadrotor, aerodock's rigid-body vehicle (the default ``[vehicle]``: 0.7 kg, its
inertia, rotors, motor lag, rotor and parasitic drag) in both simulators, hovers for 1 s, then
flies a 4 s minimum-jerk move (1 m north, 0.5 m east, 0.3 m up; flat outputs from
``aerodock.planning.minjerk``) under its position controller, with 500 Hz physics.

- RotorPy: ``rotorpy.vehicles.multirotor.Multirotor`` with aerodock's vehicle translated to its
  ``quad_params`` (``aerodock.validation.peer.rotorpy_quad_params``, the mapping the peer
  validation checks to 1 cm and 1 deg), its default RK45 integrator and motor-speed commands,
  stepped sequentially with its geometric controller ``SE3Control`` at every step (as RotorPy's
  own ``simulate`` loop runs it). When its batched simulator is importable
  (``BatchedMultirotor``; needs PyTorch, ``torchdiffeq`` and ``roma``), also a batch of
  ``--batch`` vehicles on the CPU (fixed-step RK4, one torch thread).
- aerodock: the rigid body as the world steps it (``aerodock.world.vehicles.rigid_body``:
  ``rigid_targets`` once per control period, ``step_with_autopilot`` at 500 Hz: autopilot,
  rotors, rigid-body dynamics) with the LQR ``PositionController`` at 100 Hz, for a batch of 1
  and a batch of ``--batch``.

Same vehicle and same reference; the controllers differ (each simulator flies its own) and so
do the integrators (RotorPy's adaptive RK45 on every step, aerodock's fixed first-order step), so
the ratio is the cost of simulating this scenario in each. Each time is the median of several
runs after a warm-up.

Install RotorPy for this (its simulator needs only NumPy and SciPy; ``--no-deps`` keeps its
learning and plotting dependencies out)::

    .venv/bin/pip install --no-deps rotorpy               # sequential Multirotor
    .venv/bin/pip install --no-deps torchdiffeq roma      # + its batched simulator (uses torch)

Run: ``.venv/bin/python studies/compare_rotorpy.py [--quick] [--batch 256] [--json] [--smoke]``;
``--smoke`` is ``--quick`` with a batch of 2 and one timed run of each side (it checks that
both run, not their times).
"""

from __future__ import annotations

import argparse
import sys

from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.bench import compare_rotorpy, machine_info
from aerodock.config import load_config
from aerodock.fileio import dumps_json, json_ready


def main(argv: list[str] | None = None) -> int:
    """Run the comparison and print each time and the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="half the scenario, fewer runs")
    parser.add_argument("--batch", type=int, default=256, help="batch size of the batched runs")
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON")
    add_smoke_option(parser)
    args = parser.parse_args(argv)
    if args.smoke:
        args.quick, args.batch = True, 2
    if args.batch < 1:
        parser.error(f"--batch must be >= 1, got {args.batch}")

    def progress(msg: str) -> None:
        print(f"compare: {msg}", file=sys.stderr, flush=True)

    result = compare_rotorpy(load_config(), quick=args.quick, batch=args.batch,
                             progress=progress, repeats=1 if args.smoke else None)
    if args.json:
        print(dumps_json(json_ready({"machine": machine_info(), **result})))
        return 0
    sc = result["scenario"]
    m = machine_info()
    print(f"scenario: hover {sc['hover_s']:g} s + {sc['move_s']:g} s minimum-jerk move, "
          f"{sc['steps']} steps at {sc['physics_hz']:g} Hz ({sc['simulated_s']:g} s simulated)")
    print(f"machine: {m['cpu']}, {m['cores']} cores; rotorpy {m['versions']['rotorpy']}, "
          f"torch {m['versions']['torch']}")
    for key, fig in result.items():
        if not key.startswith(("aerodock_", "rotorpy_")):
            continue
        if fig.get("value") is None:
            print(f"  {key:<22} not measured: {fig['reason']}")
            continue
        print(f"  {key:<19} {fig['value']:8.3f} s (min {fig['min']:.3f}, max {fig['max']:.3f}, "
              f"x{fig['repeats']}), of which physics step {fig['physics_s']:7.3f} s; "
              f"{fig['vehicle_steps_per_s']:>11,.0f} vehicle-steps/s; "
              f"final error {fig['final_error_m'] * 100:.1f} cm")
        print(f"  {'':<19} {fig['note']}")
    ratios = result.get("ratios") or {}
    if not ratios:
        print("no ratio: RotorPy is not installed")
    for key, ratio in ratios.items():
        print(f"ratio {key.replace('_', ' ')}: {ratio:.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
