"""Same numbers before and after a change: capture a run's outputs, then compare two captures.

A restructuring that "changes no number" is checked with this script, not by eye::

    python tools/same_numbers.py capture /tmp/before          # on the old code
    python tools/same_numbers.py capture /tmp/after           # on the new code
    python tools/same_numbers.py compare /tmp/before /tmp/after

``capture`` runs ``aerodock reproduce --quick --seed 0`` (its ``results.json``) and four docking
campaigns that between them cross every path of the world and the mission (the paper's
controller, ours with the model ``reproduce`` trained, the oracle under a moving leader with
faults, the point-mass vehicle on a stand), each printed with ``dock --json``, and, where
gymnasium is installed, a rollout of the vector environment (``env_rollout.json``: four
environments, 800 steps of seeded random actions through an autoreset; every observation,
reward and end flag). ``capture --env-only`` runs the rollout alone. ``compare`` says, file by
file, whether the bytes are identical; the exit status is 0 only when all are.

``results.json`` records how long each stage took (wall-clock seconds) and where it wrote its
files: the reproduction always runs in the same folder (``RUN_DIR``), and the comparison blanks
the wall-clock fields (``WALL_CLOCK_KEYS``, and everything under ``timings_s``) and that folder's
name in both files before comparing the bytes of the rest. It also leaves out the run's
provenance (``PROVENANCE_KEYS`` of ``aerodock_reproduce``: the resolved config, aerodock's
version and git commit), which differs between two versions by design: only numbers are compared.
"""

from __future__ import annotations

import argparse
import json
import shutil
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
RUN_DIR = Path(tempfile.gettempdir()) / "aerodock-same-numbers" / "reproduce"
WALL_CLOCK_KEYS = frozenset({"fly_s", "train_s", "wall_s", "train_time_s"})
# Under "aerodock_reproduce": where the run came from, not what it computed (older files hold
# "config": "defaults"; newer ones the resolved values, the version and the commit).
PROVENANCE_KEYS = frozenset({"config", "config_source", "version", "git_commit", "git_dirty"})


def _aerodock() -> str:
    exe = Path(sys.executable).with_name("aerodock")
    return str(exe) if exe.exists() else "aerodock"


# The rollout, run in a fresh process (the aerodock on its path): JSON of every step's outputs.
_ENV_ROLLOUT = """
import json, numpy as np
from aerodock.envs import DockingVectorEnv
env = DockingVectorEnv(num_envs=4)
obs, _ = env.reset(seed=0)
steps = [obs.tolist()]
for a in np.random.default_rng(0).uniform(-1.0, 1.0, (800, 4, 3)).astype(np.float32):
    obs, reward, terminated, truncated, _ = env.step(a)
    steps.append([obs.tolist(), reward.tolist(), terminated.tolist(), truncated.tolist()])
print(json.dumps(steps))
"""


def capture_env(out: Path) -> None:
    """The vector environment's rollout into ``out/env_rollout.json`` (nothing without
    gymnasium: the file is then left out, and ``compare`` skips what the first capture lacks)."""
    out.mkdir(parents=True, exist_ok=True)
    done = subprocess.run([sys.executable, "-c", _ENV_ROLLOUT], capture_output=True)
    if done.returncode != 0:
        print("no env rollout:", done.stderr.decode().strip().splitlines()[-1:])
        return
    (out / "env_rollout.json").write_bytes(done.stdout)


def capture(out: Path) -> None:
    """Run the reproduction, the campaigns and the env rollout; write their outputs below
    ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    capture_env(out)
    shutil.rmtree(RUN_DIR, ignore_errors=True)
    subprocess.run([_aerodock(), "reproduce", "--quick", "--seed", "0", "--out", str(RUN_DIR)],
                   check=True, stdout=subprocess.DEVNULL)
    (out / "reproduce").mkdir(exist_ok=True)
    shutil.copy(RUN_DIR / "results.json", out / "reproduce" / "results.json")
    model = RUN_DIR / "data" / "models" / "final"
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
    names = [Path("reproduce/results.json")] if (root / "reproduce").exists() else []
    names += sorted(p.relative_to(root) for p in root.glob("dock_*.json"))
    names += sorted(p.relative_to(root) for p in root.glob("env_*.json"))
    return names


def _blank(node: object, folders: tuple[str, ...], key: str = "") -> object:
    if key == "timings_s" or key in WALL_CLOCK_KEYS:
        return None
    if isinstance(node, dict):
        return {k: _blank(v, folders, k) for k, v in node.items()}
    if isinstance(node, list):
        return [_blank(v, folders) for v in node]
    if isinstance(node, str):
        for folder in folders:
            node = node.replace(folder, "<run>")
    return node


def _masked(path: Path) -> bytes:
    """The file's bytes; for results.json, re-serialised with the wall-clock fields blanked."""
    data = path.read_bytes()
    if path.name != "results.json":
        return data
    folders = (str(RUN_DIR), str(path.parent))  # where the run wrote (older captures: in place)
    doc = json.loads(data)
    meta = doc.get("aerodock_reproduce") if isinstance(doc, dict) else None
    if isinstance(meta, dict):
        for key in PROVENANCE_KEYS:
            meta.pop(key, None)
    return json.dumps(_blank(doc, folders), indent=2).encode()


def compare(a: Path, b: Path) -> bool:
    """Print, per file, whether ``a`` and ``b`` hold the same bytes; True when all do."""
    same = True
    for rel in _files(a):
        fa, fb = a / rel, b / rel
        if not fb.exists():
            print(f"MISSING  {rel}")
            same = False
            continue
        ok = _masked(fa) == _masked(fb)
        same &= ok
        print(f"{'same' if ok else 'DIFFERS':8} {rel}")
    return same


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="verb", required=True)
    cap = sub.add_parser("capture")
    cap.add_argument("out", type=Path)
    cap.add_argument("--env-only", action="store_true", help="the env rollout alone")
    cmp_ = sub.add_parser("compare")
    cmp_.add_argument("a", type=Path)
    cmp_.add_argument("b", type=Path)
    args = parser.parse_args()
    if args.verb == "capture":
        (capture_env if args.env_only else capture)(args.out)
        return 0
    return 0 if compare(args.a, args.b) else 1


if __name__ == "__main__":
    sys.exit(main())
