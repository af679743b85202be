"""Every script in studies/ runs, at its ``--smoke`` size, as a user runs it (a separate process,
from the repository's folder), exits 0 and prints what it claims: the row, table or figure its
docstring names, in the form the docs' tables were read from.

The scripts that read the real flights take them from the data location
(``aerodock.ingest.data_dir``: ``AERODOCK_DATA_DIR``, else ``../shared/data``) and skip without
them; those that read data files get them from ``aerodock ingest`` of a few of those flights. The
mission studies that need a model fly ``tests/learning/data/kind_pins/so2`` (a small ``so2``
model of random weights: the smoke run checks that the study runs, not a docking rate). The
studies that fly a curriculum or time two simulators are ``slow``. ``sample_efficiency.py`` runs
its real-flight part only: its simulated part is ``reproduce``'s first step, which
``tests/e2e/test_reproduce.py`` crosses at the same smoke size. ``sim_to_real.py``'s smoke run is
``tests/e2e/test_sim_to_real.py`` (:data:`RUN_ELSEWHERE`): it checks the printed line as here,
and the numbers of the same run.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from cli_process import aerodock

from aerodock.ingest.data_dir import find_data_dir

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "studies"
MODEL = ROOT / "tests" / "learning" / "data" / "kind_pins" / "so2"
DATA_DIR = find_data_dir(cwd=ROOT).path or ROOT.parent / "shared" / "data"
SWARM = DATA_DIR / "neural-swarm"
NUMBER = r"[+-]?\d+(?:\.\d+)?"


@dataclass(frozen=True)
class Study:
    """How one script is smoke-run: its arguments (``{model}``, ``{data}``, ``{files}``,
    ``{tmp}`` filled in), the lines its output must hold (regular expressions, each matched
    against some line), and what it needs."""

    script: str
    args: tuple[str, ...] = ()
    lines: tuple[str, ...] = ()
    needs: frozenset[str] = field(default_factory=frozenset)  # "data", "files", "rotorpy"
    slow: bool = False
    check: Callable[[str, Path], None] | None = None


def _label_floor_rows(out: str, tmp: Path) -> None:
    rows = [line.split() for line in out.splitlines() if line.rstrip().endswith("%")]
    assert {(Path(r[0]).name, r[1]) for r in rows} == {
        (f, who) for f in ("sl_train.npz", "sl_test.npz") for who in ("cf51", "cf101")}
    for r in rows:  # the ceiling 1 - rms_out / rms_wake, in (0, 100) % when rms_out < rms_wake
        rms_wake, rms_out, ceiling = float(r[3]), float(r[5]), float(r[7].rstrip("%"))
        assert 0 < rms_out < rms_wake
        assert ceiling == pytest.approx(100 * (1 - rms_out / rms_wake), abs=0.15)


def _peer_within_tolerance(out: str, tmp: Path) -> None:
    m = re.search(r"max position difference (\S+) mm \(tolerance (\S+) mm\), max attitude "
                  r"difference (\S+) deg \(tolerance (\S+) deg\)", out)
    assert m, out
    assert float(m[1]) < float(m[2]) and float(m[3]) < float(m[4])


def _png(path: Path) -> None:
    """A figure was drawn there: a PNG of some size."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000, path


def _sample_efficiency_json(out: str, tmp: Path) -> None:
    record = json.loads((tmp / "se" / "sample_efficiency_real.json").read_text())
    se = record["sample_efficiency"]
    assert se["minutes"] == [0.5] and set(se["models"]) == {"so2", "so2-ext", "mlp"}


STUDY_CASES = (
    Study("attitude_stacks.py", ("--data", "{data}"),
          (rf"^  arducopter\s+paper\s+{NUMBER} / {NUMBER} / {NUMBER}, peak {NUMBER}$",
           r"^  crazyflie-pid\s+as configured: \d+$",
           r"^32 g under 32 g: inward torque mN m, lean deg, mN m per rad, per offset bin$",
           rf"^  real\s+4-6 cm {NUMBER} / {NUMBER} / {NUMBER}; 6-8 cm",
           rf"^  crazyflie-pid\s+4-6 cm {NUMBER} / {NUMBER} / {NUMBER}; 6-8 cm",
           rf"^  crazyflie-pid, swaps\s+4-6 cm {NUMBER} / {NUMBER} / {NUMBER}; 6-8 cm",
           r"^32 g under 32 g, 0\.15-0\.45 m below: inward torque mN m moving in / moving out",
           rf"^  real\s+0-2 cm {NUMBER} / {NUMBER}; 2-4 cm {NUMBER} / {NUMBER};",
           r"^32 g under 32 g: the follower's attitude loop, 2-6 Hz",
           rf"^  real\s+{NUMBER} / {NUMBER} / {NUMBER} \({NUMBER}\); {NUMBER} / {NUMBER}",
           rf"^  the SJC law, its gains {NUMBER} / {NUMBER} / {NUMBER}; {NUMBER}",
           rf"^  crazyflie-pid, swaps\s+{NUMBER} / {NUMBER} / {NUMBER} \({NUMBER}\); "),
          frozenset({"data"})),
    Study("baseline_ladder.py", ("--model", "{model}"),
          (r"^\s*\d/2 with,\s+\d/2 without\s+\(slips \d, err \d+\.\d{3} m\)\s+"
           r"then: the estimator",)),
    Study("compare_rotorpy.py", (), (r"^ratio single trial: \d+\.\dx$|^no ratio: RotorPy",),
          slow=True),
    Study("crazyflie_autopilot_fit.py", (),
          (rf"^motor 0\.030 s: attitude_p {NUMBER}, rate_p {NUMBER}, rate_i {NUMBER} 1/s; RMS "
           rf"difference {NUMBER} of the step$",)),
    Study("crazyflie_docking.py", ("--models", "{tmp}/curriculum"),
          (r"^ours\s+model\s+\d/2 \(\d+%-\d+%\) slips \d missed \d aborts \d .* tilt "
           r"\d+\.\d deg$",)),
    Study("crazyflie_tilt.py", ("--data", "{data}/swap_ss"),
          (rf"^real, below \(0\.25-0\.35 m, < 3 cm off axis\): {NUMBER} deg RMS \(\d+ samples\); "
           rf"free air {NUMBER} deg$",
           rf"^simulated, 0\.3 m below, jet \(force on the rotor disks\): {NUMBER} deg RMS$",
           rf"^simulated, 0\.3 m below, jet at the centre of mass: {NUMBER} deg RMS$",
           rf"^simulated, free air: {NUMBER} deg RMS$"), frozenset({"data"})),
    Study("fast_leader.py", ("--model", "{model}"),
          (r"^0\.5 m/s turn 0\.0 rad/s model\s+\d/2 \(\d+%-\d+%\) slips\s+\d aborts\s+\d err "
           r"\d\.\d{4} m tilt \d+\.\d deg$",)),
    Study("label_floor.py", ("{files}/sl_train.npz", "{files}/sl_test.npz"),
          (r"^data\s+follower\s+n_wake\s+rms_wake\s+n_out\s+rms_out\s+mean_out\s+ceiling$",),
          frozenset({"files"}), check=_label_floor_rows),
    Study("label_noise_speed.py", ("--data", "{data}"),
          (r"^cf51 free-air label noise sd, lateral/vertical m/s\^2, by speed m/s: ",
           rf"^  32 g under 32 g \(\d+ samples, \d+ flights, median speed {NUMBER} m/s\)",
           r"^held out flights, ", r"^fitted on flights, "), frozenset({"data"})),
    Study("learnt_mean_seeds.py", ("--dock", "4"),
          (rf"^seed 0: so2 model {NUMBER}%, paper's {NUMBER}%; labels minus the mean field"
           rf".*; docked of 4: ours [0-4], paper [0-4]$",
           rf"^so2 model over 1 seeds: {NUMBER}% mean$",
           r"^docked of 4 over the seeds: ours [0-4]-[0-4], paper [0-4]-[0-4]$"), slow=True),
    Study("pairing_heldout.py", ("{files}/ss_train.npz", "{files}/sl_train.npz",
                                 "{files}/ss_test.npz", "{files}/sl_test.npz", "so2-pair", "so2"),
          (r"^\| model, seeds 0 \| ss 05-06 \| small under large \| large under small \|$",
           *(rf"^HELDOUT {kind} {who}: {NUMBER} % \({NUMBER}-{NUMBER}\)$"
             for kind in ("so2-pair", "so2")
             for who in ("ss 05-06", "small under large", "large under small"))),
          frozenset({"files"})),
    Study("pairing_validation.py", ("{files}/ss_train.npz", "{files}/sl_train.npz"),
          tuple(rf"^VAL so2 {who}: {NUMBER} % \({NUMBER}, {NUMBER}-{NUMBER}\)$"
                for who in ("cf51", "cf101")), frozenset({"files"})),
    Study("size_transfer.py", ("{files}/ss_train.npz", "{files}/sl_test.npz", "so2",
                               "so2-leader", "--large-rotor-radius", "0.0239", "--footprint"),
          (r"^\| model, trained on the small pair, seeds 0 \| small under large \| large under "
           r"small \|$",
           *(rf"^SIZE {name} {who}: {NUMBER} % \({NUMBER}-{NUMBER}\)$"
             for name in ("so2", "so2-leader", "so2-leader, large rotor 0.0239 m",
                          "so2, rotor footprint", "so2-leader, rotor footprint")
             for who in ("small under large", "large under small"))),
          frozenset({"files"})),
    Study("slip_throughs.py", (),
          (r"^hover_0\.36: [0-2]/2 docked, [0-2] slipped through, [0-2] missed, [0-2] aborted, "
           r"[0-2] never closed the gate \(mouth \+-4\.5 cm\)$",)),
    Study("peer_rotorpy.py", (), (r"^rotor \+ parasitic drag on : over 0\.2 s at 500 Hz",),
          frozenset({"rotorpy"}), check=_peer_within_tolerance),
    Study("post_dock.py", (),
          (r"^ours controller, compensation observer, leader 0 m/s, 2 trials; the campaign flew "
           r"\d+ of \d+ control periods$",
           r"^  docked: \d \(captured: \d\); collisions before the trials' own end: \d rotor "
           r"strikes, \d ground contacts; ground contacts after it \(not counted\): \d$")),
    Study("sample_efficiency.py", ("--part", "real", "--real-folder", "{data}/swap_ss",
                                   "--out", "{tmp}/se"),
          tuple(rf"^{k}\s+0\.5\s+{NUMBER} \({NUMBER}\)\s+{NUMBER} \({NUMBER}\)$"
                for k in ("so2", "so2-ext", "mlp")) + (rf"^zero\s+{NUMBER}\s+{NUMBER}$",),
          frozenset({"data"}), check=_sample_efficiency_json),
    Study("torque_pairing.py", ("{model}",),
          (r"^torque feed-forward on : docked \d/2, aborts \d, terminal tilt \d+\.\d\d deg$",
           rf"^  last second: off axis {NUMBER} m; outward: model {NUMBER}, true wake {NUMBER}, "
           rf"lean {NUMBER} m/s\^2$")),
    Study("torque_sensitivity.py", (),
          (r"^gain 1 paper oracle\s+\d/2 \(\d+%-\d+%\) slips\s+\d missed\s+\d aborts\s+\d err "
           r"\d\.\d{4} m tilt \d+\.\d deg$",)),
    Study("wake_paper_scale.py", (),
          (*(rf"^\| {sep} m \| {NUMBER} \| {NUMBER} \| {NUMBER} \| {NUMBER} \| {NUMBER} \|$"
             for sep in (r"0\.36", r"0\.64", r"1\.35")),
           rf"^the disks' mean torque 0\.36 m below, N m: 5 cm off the axis {NUMBER}, "
           rf"10 cm off the axis {NUMBER}, 15 cm off the axis {NUMBER}$")),
    Study("headline_table.py", ("tests/data/headline_results_quick.json",),
          (r"^\| hover docking, d_p 0\.36 m \| 8/10 with model \| 5/24 \(9%-40%\) \| "
           r"13/24 \(35%-72%\) \| "
           r"21/24 \(69%-96%\) \| 21/24 \(69%-96%\) \|$",
           r"^\| cable study \(leader on a stand\), offsets docked \| 6/6 with vs 0/6 without \| "
           r"0/3 \| 0/3 \| 3/3 \| 3/3 \|$",
           r"^\| ours \+ deep model \| 4/4 \(51%-100%\) met \|")),
    Study("wake_torque.py", ("--data", "{data}", "--figure", "{tmp}/wake_torque.png"),
          (r"^cf51's motor commands: \d\.\d\d median in free air",
           rf"^  cf101: 12 flights, residual sd up to {NUMBER} mN; \d+ motor samples at the "
           rf"ceiling \(commands up to {NUMBER}\), {NUMBER} mN asked beyond the map there$",
           rf"^  32 g under 32 g +4-6 +{NUMBER} / +{NUMBER} / +{NUMBER} +{NUMBER} +{NUMBER}$",
           rf"^  sent, 67 g under 32 g: 0-15 deg: {NUMBER} \({NUMBER}\) / {NUMBER}, 15-30 deg: ",
           rf"^the small Crazyflie world's attitude loop as a spring .*: {NUMBER} mN m/rad$",
           rf"^  32 g under 32 g: .*4-6: {NUMBER} \({NUMBER} %, real {NUMBER}x\)"),
          frozenset({"data"}), check=lambda out, tmp: _png(tmp / "wake_torque.png")),
)
RUN_ELSEWHERE = {"sim_to_real.py": "tests/e2e/test_sim_to_real.py"}
"""Scripts whose ``--smoke`` run (exit code, printed line) is checked by another test, which
also checks the numbers the run computes: run there once, not once in each file."""


def _have_rotorpy() -> bool:
    try:
        import rotorpy  # noqa: F401
    except ImportError:
        return False
    return True


@pytest.fixture(scope="module")
def data_files(tmp_path_factory) -> Path:
    """``aerodock ingest`` of a few real flights, named as the studies' docstrings name them:
    swap_ss 00 (train) and 05 (test); swap_sl 04-07 (train: 04 fitted, 05-07 the validation
    split) and 08-11 (test), each follower apart."""
    if not (SWARM / "swap_ss").is_dir() or not (SWARM / "swap_sl_2020-06-19").is_dir():
        pytest.skip(f"the Neural-Swarm flights are not at {SWARM}")
    where = tmp_path_factory.mktemp("ingested")
    sl, vehicles = SWARM / "swap_sl_2020-06-19", "cf51=small,cf101=large"
    for name, files, extra in (
            ("ss_train", sorted((SWARM / "swap_ss").glob("cf5?_00.csv")), ()),
            ("ss_test", sorted((SWARM / "swap_ss").glob("cf5?_05.csv")), ()),
            ("sl_train", sorted(sl.glob("cf*_0[4-7].csv")), ("--vehicle", vehicles)),
            ("sl_test", sorted([*sl.glob("cf*_0[89].csv"), *sl.glob("cf*_1[01].csv")]),
             ("--vehicle", vehicles))):
        aerodock("ingest", "--format", "neural-swarm", *files, *extra,
                 "--out", where / f"{name}.npz", check=True)
    return where


def _run(study: Study, tmp: Path, files: Path | None) -> str:
    if "data" in study.needs and not SWARM.is_dir():
        pytest.skip(f"the Neural-Swarm flights are not at {SWARM}")
    if "rotorpy" in study.needs and not _have_rotorpy():
        pytest.skip("RotorPy is not installed")
    if study.script == "crazyflie_docking.py":  # a curriculum's folder: its two models
        for name in ("paper", "final"):
            shutil.copytree(MODEL, tmp / "curriculum" / "models" / name)
    fill = {"model": str(MODEL), "data": str(SWARM), "tmp": str(tmp), "files": str(files)}
    args = [a.format(**fill) for a in study.args]
    proc = subprocess.run([sys.executable, str(STUDIES / study.script), *args, "--smoke"],
                          capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = proc.stdout
    for pattern in study.lines:
        assert re.search(pattern, out, re.MULTILINE), f"no line matching {pattern!r} in:\n{out}"
    if study.check is not None:
        study.check(out, tmp)
    return out


def _param(study: Study):
    marks = [pytest.mark.slow] if study.slow else []
    return pytest.param(study, id=study.script.removesuffix(".py"), marks=marks)


@pytest.mark.parametrize("study", [_param(s) for s in STUDY_CASES if "files" not in s.needs])
def test_study_runs_at_its_smoke_size(study: Study, tmp_path: Path) -> None:
    _run(study, tmp_path, None)


@pytest.mark.parametrize("study", [_param(s) for s in STUDY_CASES if "files" in s.needs])
def test_study_on_ingested_flights_runs_at_its_smoke_size(study: Study, tmp_path: Path,
                                                          data_files: Path) -> None:
    _run(study, tmp_path, data_files)


def test_every_study_is_run_by_a_test() -> None:
    scripts = {p.name for p in STUDIES.glob("*.py") if not p.name.startswith("_")}
    assert scripts == {s.script for s in STUDY_CASES} | set(RUN_ELSEWHERE)
    assert not {s.script for s in STUDY_CASES} & set(RUN_ELSEWHERE)
    for script, where in RUN_ELSEWHERE.items():
        assert f"studies/{script}" in (ROOT / where).read_text()

