"""Typed records of ``aerodock reproduce`` and ``aerodock targets``.

The reproduction and the targets return these frozen dataclasses; ``report.md``, the CLI and
``results.json`` (``targets.json``) read them. Each record's :meth:`~Record.to_json` gives the
JSON object those files have always held, key for key and in the same order, so the files'
bytes do not change (:class:`aerodock.records.Record`).

The parts another module computes and records in its own shape (a campaign's
:meth:`~aerodock.mission.CampaignResult.summary`, the curriculum's summary, the held-out
evaluation, the sample-efficiency, cable, real-data and compensation studies, the controller
costs and the paper's counts) are held here as the JSON-ready mappings those modules return.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from aerodock.records import Json, Record


# -- docking -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class HoverDocking(Record):
    """Docking with the leader hovering: each compensation's campaign summary (with its
    ``arrival_s``), and the error reduction the model brings."""

    offset_m: float
    aperture_m: float
    trials: int
    without_model: Json
    with_model: Json
    oracle: Json
    terminal_error_reduction_x: float | None
    oracle_mean_source: str

    def mode(self, name: str) -> Json:
        """The campaign summary of ``"without_model"``, ``"with_model"`` or ``"oracle"``."""
        return {"without_model": self.without_model, "with_model": self.with_model,
                "oracle": self.oracle}[name]


@dataclass(frozen=True)
class AltitudeWindow(Record):
    """Mean |vertical error| over a time window of the approaching trials (m)."""

    window_s: list[float]
    mean_abs_err_down_m: float | None
    sd_m: float | None
    trials: int


@dataclass(frozen=True)
class MovingMode(Record):
    """One compensation with the leader moving: the docking campaign's summary (with its
    ``arrival_s``) and the formation flights' altitude errors."""

    summary: Json
    altitude_error_approach: AltitudeWindow
    altitude_error_hold: AltitudeWindow
    _SPLICE: ClassVar[tuple[str, ...]] = ("summary",)


@dataclass(frozen=True)
class MovingLeader(Record):
    """The leader in motion: docking and formation tracking with and without the model."""

    leader_speed_mps: float
    meet_s: float
    hold_s: float
    trials: int
    without_model: MovingMode
    with_model: MovingMode

    def mode(self, name: str) -> MovingMode:
        """``"without_model"`` or ``"with_model"``."""
        return {"without_model": self.without_model, "with_model": self.with_model}[name]


@dataclass(frozen=True)
class DockingRecord(Record):
    """The cable-length study, hover docking and the moving leader, flown by one controller."""

    cable_study: Json
    hover_docking: HoverDocking
    moving_leader: MovingLeader


# -- controllers -------------------------------------------------------------------------------
@dataclass(frozen=True)
class PaperController(Record):
    """The paper's controller as its flight stack publishes it (it flies the reproduction)."""

    source: str
    q_diag: list[float]
    terminal_q_diag: list[float]
    bias_estimator: str
    command_rate_hz: float
    reference_ff_factor: float
    observer_rise_63_s: float


@dataclass(frozen=True)
class TunedController(Record):
    """The configuration's controller and its docking experiments."""

    source: str
    q_diag: list[float]
    terminal_q_diag: list[float]
    observer_bias_tau_s: float
    docking: DockingRecord
    _SPLICE: ClassVar[tuple[str, ...]] = ("docking",)


@dataclass(frozen=True)
class OursController(Record):
    """Tuned + the accelerometer observer, with the deep model, and its docking experiments."""

    source: str
    accel_observer_tau_s: float
    terminal_q_diag: list[float]
    docking: DockingRecord
    _SPLICE: ClassVar[tuple[str, ...]] = ("docking",)


@dataclass(frozen=True)
class ControllersRecord(Record):
    """The controllers flown (``tuned`` is not flown by a smoke run)."""

    paper: PaperController
    tuned: TunedController | None
    ours: OursController
    _OMIT_NONE: ClassVar[tuple[str, ...]] = ("tuned",)


# -- targets -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class ScenarioSpec(Record):
    """A target scenario: d_p (m), the leader's speed (m/s) and the success rate to reach."""

    name: str
    offset_m: float
    leader_speed_mps: float
    target_success: float


@dataclass(frozen=True)
class ScenarioOutcome(Record):
    """One scenario flown: the campaign's figures and whether the target was met."""

    trials: int
    docked: int
    success_rate: float
    success_wilson95: list[float]
    terminal_err_down_median_m: float
    terminal_err_3d_median_m: float
    terminal_tilt_rms_deg_median: float
    slip_throughs: int
    missed: int
    aborts: int
    rotor_strikes: int
    clearance_violations: int
    offset_m: float
    leader_speed_mps: float
    target_success: float
    met: bool


@dataclass(frozen=True)
class TargetRow(Record):
    """One (controller, model) row: its outcome per scenario name."""

    scenarios: dict[str, ScenarioOutcome]
    err_down_met: bool


@dataclass(frozen=True)
class LearntMean(Record):
    """The learnt model's vertical force against the field's mean at one depth (m/s²)."""

    where: str
    depth_m: float
    field_mean_down_mps2: float
    learnt_down_mps2: float
    relative_error: float | None
    met: bool


@dataclass(frozen=True)
class TargetsProvenance(Record):
    """What ``aerodock targets`` flew: the model folder, the config's source and the field."""

    model: str
    config: str | None
    field: str


@dataclass(frozen=True)
class TargetsResult(Record):
    """The targets beyond the paper for each row, and the learnt-mean checks."""

    trials: int
    scenarios: list[ScenarioSpec]
    err_down_target_m: float
    mean_rel_target: float
    rows: dict[str, TargetRow]
    learnt_mean: list[LearntMean]
    learnt_mean_paper_model: list[LearntMean] | None = None
    learnt_mean_wrench_model: list[LearntMean] | None = None
    provenance: TargetsProvenance | None = None
    _OMIT_NONE: ClassVar[tuple[str, ...]] = (
        "learnt_mean_paper_model", "learnt_mean_wrench_model", "provenance")
    _SPLICE: ClassVar[tuple[str, ...]] = ("provenance",)

    def learnt_means(self) -> list[tuple[str, list[LearntMean]]]:
        """Each model's learnt-mean check that ran, labelled for the report."""
        labelled = (("deep curriculum", self.learnt_mean),
                    ("paper's curriculum", self.learnt_mean_paper_model),
                    ("learnt wrench (thrust basis)", self.learnt_mean_wrench_model))
        return [(label, rows) for label, rows in labelled if rows is not None]


# -- the reproduction --------------------------------------------------------------------------
@dataclass(frozen=True)
class RunHeader(Record):
    """How the reproduction ran: its size, seed, provenance and machine."""

    quick: bool
    smoke: bool
    seed: int
    provenance: Json  # aerodock.experiments.provenance.provenance(): config, version, git
    size_overrides: Json
    machine: str
    _SPLICE: ClassVar[tuple[str, ...]] = ("provenance",)

    @property
    def config_source(self) -> str:
        """Where the configuration came from (the resolved config if it names none)."""
        return self.provenance.get("config_source", self.provenance.get("config"))


@dataclass(frozen=True)
class LearningRecord(Record):
    """Step 1: the curriculum, the held-out evaluations and the error floor."""

    curriculum: Json
    heldout: Json
    heldout_paper_model: Json
    rmse_ratio_to_floor: dict[str, float | None]
    error_floor_source: str
    wrench_curriculum: Json | None = None
    _OMIT_NONE: ClassVar[tuple[str, ...]] = ("wrench_curriculum",)


UNITS: Json = {"errors": "m", "integrals_over_0.5s": "m*s (errors), m/s (force)",
               "accelerations": "m/s^2, NED (down positive)", "rates": "fraction"}
"""The units ``results.json`` states."""


@dataclass(frozen=True)
class ReproduceResults(Record):
    """Everything ``aerodock reproduce`` measured (``results.json``)."""

    aerodock_reproduce: RunHeader
    units: Json
    learning: LearningRecord
    sample_efficiency: Json
    docking: DockingRecord  # the paper's controller (the reproduction)
    paper_counts: Json
    controllers: ControllersRecord
    targets: TargetsResult
    controller_costs: Json
    real_data: Json | None
    compensation: Json | None
    timings_s: dict[str, float]
    figures: list[str] | None = None
    _OMIT_NONE: ClassVar[tuple[str, ...]] = ("figures",)
    _SPLICE: ClassVar[tuple[str, ...]] = ("docking",)

    @property
    def total_s(self) -> float:
        """The run's wall-clock time (s)."""
        return self.timings_s["total_s"]
