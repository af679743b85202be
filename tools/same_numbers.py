"""Same numbers before and after a change: capture a run's outputs, then compare two captures.

A restructuring that "changes no number" is checked with this script, not by eye::

    python tools/same_numbers.py capture /tmp/before          # on the old code
    python tools/same_numbers.py capture /tmp/after           # on the new code
    python tools/same_numbers.py compare /tmp/before /tmp/after

``capture`` runs ``aerodock reproduce --quick --seed 0`` (its ``results.json``) and four docking
campaigns that between them cross every path of the world and the mission (the paper's
controller, ours with a learnt model, the oracle under a moving leader with faults, the
point-mass vehicle on a stand), each printed with ``dock --json``. ``compare`` says, file by
file, whether the bytes are identical; the exit status is 0 only when all are.

Without ``--quick-only`` the campaigns fly the model that ``reproduce --quick`` trained.
"""

from __future__ import annotations

import argparse
import filecmp
import subprocess
import sys
import tempfile
from pathlib import Path

# Each campaign: a name and its `aerodock dock` arguments ({model} is the trained model's dir).
CAMPAIGNS: dict[str, list[str]] = {
    "paper_observer_hover": ["--controller", "paper", "--compensation", "observer",
                             "--trials", "24", "--seed", "3"],
    "ours_model_hover_027": ["--controller", "ours", "--compensation", "model",
                             "--model", "{model}", "--offset", "0.27", "--trials", "24",
                             "--seed", "5"],
    "tuned_oracle_moving_faults": ["--controller", "tuned", "--compensation", "oracle",
                                   "--leader-speed", "0.25", "--faults",
                                   "examples/faults.toml", "--trials", "16", "--seed", "7"],
    "pointmass_fixed_leader": ["--controller", "tuned", "--compensation", "none",
                               "--leader-fixed", "--offset", "0.64", "--trials", "16",
                               "--seed", "11", "--config", "{pointmass}"],
}

_POINT_MASS_TOML = '[vehicle]\nmodel = "point-mass"\n'


def _aerodock() -> str:
    exe = Path(sys.executable).with_name("aerodock")
    return str(exe) if exe.exists() else "aerodock"


def capture(out: Path) -> None:
    """Run the reproduction and the campaigns; write their outputs below ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    run_dir = out / "reproduce"
    subprocess.run([_aerodock(), "reproduce", "--quick", "--seed", "0", "--out", str(run_dir)],
                   check=True, stdout=subprocess.DEVNULL)
    model = run_dir / "data" / "models" / "final"
    with tempfile.TemporaryDirectory() as tmp:
        pointmass = Path(tmp) / "pointmass.toml"
        pointmass.write_text(_POINT_MASS_TOML)
        for name, args in CAMPAIGNS.items():
            argv = [a.format(model=model, pointmass=pointmass) for a in args]
            done = subprocess.run([_aerodock(), "dock", *argv, "--json"], check=True,
                                  capture_output=True)
            (out / f"dock_{name}.json").write_bytes(done.stdout)
    print(f"captured in {out}")


def _files(root: Path) -> list[Path]:
    names = [Path("reproduce/results.json")]
    names += sorted(p.relative_to(root) for p in root.glob("dock_*.json"))
    return names


def compare(a: Path, b: Path) -> bool:
    """Print, per file, whether ``a`` and ``b`` hold the same bytes; True when all do."""
    same = True
    for rel in _files(a):
        fa, fb = a / rel, b / rel
        if not fb.exists():
            print(f"MISSING  {rel}")
            same = False
            continue
        ok = filecmp.cmp(fa, fb, shallow=False)
        same &= ok
        print(f"{'same' if ok else 'DIFFERS':8} {rel}")
    return same


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="verb", required=True)
    sub.add_parser("capture").add_argument("out", type=Path)
    cmp_ = sub.add_parser("compare")
    cmp_.add_argument("a", type=Path)
    cmp_.add_argument("b", type=Path)
    args = parser.parse_args()
    if args.verb == "capture":
        capture(args.out)
        return 0
    return 0 if compare(args.a, args.b) else 1


if __name__ == "__main__":
    sys.exit(main())
