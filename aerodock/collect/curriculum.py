"""Curriculum data collection in the simulated world (the paper's "Curriculum for learning").

Stage 0 flies the follower 1.5-1.8 m below the leader with the nominal controller (bias observer
on); each stage trains a model on everything collected so far, deploys it as the follower's
feed-forward, and collects the next stage 0.3 m closer, down to about 0.5 m; deep stages
(``deep_depths_m``, beyond the paper) then go on to the docking depth, each flown with the model of
the stage before. Every flight excites
the wake: it starts in free air (so the labels' constant bias can be estimated), sweeps laterally
through the wake, holds near the axis, moves vertically, and leaves to free air again; the leader
hovers or drifts slowly so that leader speed is represented.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor
from aerodock.control.controller import PositionController, Reference
from aerodock.downwash import BodyState, build_field
from aerodock.fileio import building_dir, check_output_dir
from aerodock.flightlog import FlightLog, save_flightlogs
from aerodock.mission.params import fly_on_configured_rotors, vehicle_meta
from aerodock.mission.recorder import FlightRecorder
from aerodock.mission.settle import settle
from aerodock.planning.minjerk import minjerk
from aerodock.rng import TrialRNG
from aerodock.world import World

# (duration_s, waypoint index moved to); waypoint 0 is the start. Rest-to-rest segments.
_SEGMENTS = ((1.0, 0), (3.0, 1), (1.5, 2), (1.5, 2), (1.5, 3), (1.0, 3), (2.0, 4), (1.0, 4))
FLIGHT_S = float(sum(d for d, _ in _SEGMENTS))
OUTPUTS = ("stage*.npz", "models")
"""What a collection's folder holds (``collect --out``): replaced as a whole by the next one."""


@dataclass(frozen=True)
class Stage:
    """One curriculum stage: the depth band flown below the leader."""

    index: int
    depth_min_m: float
    depth_max_m: float
    deep: bool = False  # beyond the paper's curriculum (``deep_depths_m``)


def curriculum_stages(cfg: Config, deep: bool = True) -> list[Stage]:
    """Stages from ``[curriculum]``: ``stage_step_m`` closer each time, down to ``min_depth_m`` (the
    paper's curriculum), then, with ``deep``, one stage down to each of ``deep_depths_m`` (each
    flown with the model of the stage before it)."""
    c = cfg.curriculum
    lo, hi = c.stage0_depth_m
    stages = []
    k = 0
    while hi - k * c.stage_step_m > c.min_depth_m + 1e-9:
        top = hi - k * c.stage_step_m
        stages.append(Stage(k, max(c.min_depth_m, lo - k * c.stage_step_m), top))
        k += 1
    if deep:
        for depth in c.deep_depths_m:
            top = stages[-1].depth_min_m if stages else hi
            if depth < top - 1e-9:
                stages.append(Stage(len(stages), float(depth), top, deep=True))
    return stages


# Lengths of the flights' pattern, in proportion to ``curriculum.free_air_m`` (so a world of
# smaller vehicles, whose free-air waypoints are nearer, flies the same pattern scaled): written
# as the default world's figure times ``free_air_m / 0.9`` (exactly the figure there).
_DEFAULT_FREE_AIR_M = 0.9
_HOLD_RADIUS_M = 0.2  # near-axis holds within this radius of the leader's axis
_LABEL_FREE_AIR_M = 0.6  # labels' free air beyond this (learning.labels.FREE_AIR_RADIUS_M)


def _scaled(length_m: float, cfg: Config) -> float:
    """``length_m`` of the default world's pattern in this world's (see above)."""
    return length_m * (cfg.curriculum.free_air_m / _DEFAULT_FREE_AIR_M)


def label_free_air_radius_m(cfg: Config) -> float:
    """The free-air radius the curriculum's flights record for their labels' bias, m: 0.6 m in
    the default world (its free-air waypoints at 0.9 m), in proportion to ``free_air_m`` else."""
    return _scaled(_LABEL_FREE_AIR_M, cfg)


def _waypoints(n: int, rng: TrialRNG, depth_min: float, depth_max: float,
               free_air_m: float, hold_radius_m: float) -> np.ndarray:
    """(5, n, 3) waypoints relative to the leader: free air, sweep across, near-axis hold at two
    depths (within ``hold_radius_m`` of the axis), exit to free air."""
    theta = rng.uniform(0.0, 2 * np.pi, size=n)
    depths = rng.uniform(depth_min, depth_max, size=(n, 3))
    r_hold = rng.uniform(0.0, hold_radius_m, size=n)
    phi = rng.uniform(0.0, 2 * np.pi, size=n)

    def at(r, ang, depth):
        return np.stack([r * np.cos(ang), r * np.sin(ang), depth], axis=1)

    return np.stack([
        at(np.full(n, free_air_m), theta, depths[:, 0]),
        at(np.full(n, free_air_m), theta + np.pi, depths[:, 0]),
        at(r_hold, phi, depths[:, 1]),
        at(r_hold, phi, depths[:, 2]),
        at(np.full(n, free_air_m), theta + np.pi / 2, depths[:, 2]),
    ])


# Gap kept between the hanging bar and the top of the follower's gate in the curriculum flights.
_BAR_GAP_M = 0.0
# Shortest cable the curriculum hangs the bar on: a third of the bifilar spacing (0.05 m on the
# default platform's 0.15 m), written so that it is exactly that there.
_MIN_CABLE_M = 0.05
_DEFAULT_CABLE_SPACING_M = 0.15


def bar_out_of_the_way(cfg: Config, depth_min_m: float) -> Config:
    """``cfg`` with the leader's cables shortened, if needed, so that the bar hangs above the
    follower's gate at the shallowest depth flown (the deep stages fly the follower above where
    the bar would hang at full length; nobody collects data with the bar through the vehicle)."""
    p, gp = cfg.platform, cfg.gripper
    room = (depth_min_m - p.anchor_below_leader_m - gp.mount_height_m - gp.gate_height_m
            - p.bar_diameter_m / 2 - _BAR_GAP_M)
    if p.cable_length_m <= room:
        return cfg
    min_cable_m = _MIN_CABLE_M * (p.cable_spacing_m / _DEFAULT_CABLE_SPACING_M)
    return cfg.with_overrides({"platform": {"cable_length_m": max(min_cable_m, room)}},
                              source=f"{cfg.source} + cables shortened for the curriculum")


def excitation_flights(cfg: Config, n_flights: int, depth_min_m: float, depth_max_m: float,
                       seed: int, predictor: AccelPredictor | None = None,
                       name: str = "flight", first_trial: int = 0) -> list[FlightLog]:
    """Fly ``n_flights`` wake-excitation flights at once and return their FlightLogs.

    Args:
        cfg: configuration.
        n_flights: flights (a batch).
        depth_min_m, depth_max_m: depth band below the leader.
        seed: random seed (each flight has its own stream).
        predictor: feed-forward model (None: bias observer only, the nominal controller).
        name: prefix of the flights' names.
        first_trial: index of the first flight (for per-flight random streams).
    """
    n = n_flights
    cfg = bar_out_of_the_way(cfg, depth_min_m)
    rng = TrialRNG(seed, n, first_trial)
    c = cfg.curriculum
    world = World(cfg, n, rng, field=build_field(cfg))
    wps = _waypoints(n, rng, depth_min_m, depth_max_m, c.free_air_m,
                     _scaled(_HOLD_RADIUS_M, cfg))
    drifting = rng.random(n) < c.drift_fraction
    speed = np.where(drifting, rng.uniform(0.0, c.leader_drift_max_mps, size=n), 0.0)
    heading = rng.uniform(0.0, 2 * np.pi, size=n)
    lead_v = np.stack([speed * np.cos(heading), speed * np.sin(heading), np.zeros(n)], axis=1)
    lead_p0 = np.tile([0.0, 0.0, -cfg.mission.leader_altitude_m], (n, 1))
    settle_s = cfg.mission.settle_s
    world.reset(lead_p0 - lead_v * settle_s, lead_p0 + wps[0] - lead_v * settle_s)
    world.set_velocities(lead_v, lead_v)
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    lead_mass = cfg.leader.mass_kg  # the follower's unless [leader] says otherwise
    fly_on_configured_rotors(predictor, cfg)
    lead_ctl = PositionController(cfg, n, use_observer=True, vehicle=cfg.leader)
    fol_ctl = PositionController(cfg, n, use_observer=True, has_accelerometer=True)
    z = np.zeros((n, 3))
    zero_n = np.zeros(n)

    def feedforward(obs_l, obs_f):
        if predictor is None:
            return None
        return predictor.predict_bodies(
            BodyState(obs_l.p, obs_l.v, obs_l.R, np.full(n, lead_mass * g),
                      np.full(n, lead_mass)),
            BodyState(obs_f.p, obs_f.v, obs_f.R, np.full(n, mass * g), np.full(n, mass)))

    # Settled start: leader (drifting if it drifts) and follower in formation at the first
    # waypoint until the observers converge.
    settle(world, lead_ctl, fol_ctl,
           lambda t: Reference(lead_p0 + lead_v * t, lead_v, z, zero_n, zero_n),
           lambda t: Reference(lead_p0 + lead_v * t + wps[0], lead_v, z, zero_n, zero_n),
           settle_s, feedforward)
    # Segment plans (shared timing, per-flight waypoints).
    plans, t0 = [], 0.0
    prev = 0
    for duration, target in _SEGMENTS:
        plans.append((t0, t0 + duration, minjerk(wps[prev], z, z, wps[target], z, z, duration,
                                                 t0)))
        t0 += duration
        prev = target
    recorder = FlightRecorder(cfg.curriculum.label_basis, mass)
    world.observed_accel()
    steps = int(round(FLIGHT_S / world.dt_control_s))
    seg = 0
    for k in range(steps):
        t = k * world.dt_control_s
        while seg < len(plans) - 1 and t >= plans[seg][1]:
            seg += 1
        obs_l, obs_f = world.observe()
        lout = lead_ctl.step(obs_l.p, obs_l.v, obs_l.rpy,
                             Reference(lead_p0 + lead_v * t, lead_v, z, zero_n, zero_n))
        rel_p, rel_v, rel_a = plans[seg][2].sample(t)
        ref = Reference(lead_p0 + lead_v * t + rel_p, lead_v + rel_v, rel_a, zero_n, zero_n)
        ff = feedforward(obs_l, obs_f)
        accel = world.observed_accel() if fol_ctl.uses_accelerometer else None
        fout = fol_ctl.step(obs_f.p, obs_f.v, obs_f.rpy, ref, None, ff, accel)
        recorder.before_step(t, world, obs_l, obs_f, fout, ref.p, np.full(n, seg))
        world.advance(lout.command, fout.command)
        recorder.after_step(world)
    return recorder.flightlogs(lambda i: {
        "name": f"{name}-{first_trial + i:03d}", "source": "aerodock-sim", "frame": "NED",
        "label_basis": recorder.label_basis, "leader_mass_kg": lead_mass,
        "follower_mass_kg": mass, **vehicle_meta(cfg),
        "free_air_radius_m": label_free_air_radius_m(cfg),
        "depth_band_m": [depth_min_m, depth_max_m], "leader_speed_mps": float(speed[i]),
        "cable_length_m": cfg.platform.cable_length_m,
        "compensation": "observer" if predictor is None else "observer+model", "seed": seed,
    })


def run_curriculum(cfg: Config, out_dir: Path, seed: int = 0, model_kind: str | None = None,
                   progress: Callable[[str], None] | None = None,
                   train_kwargs: dict[str, Any] | None = None,
                   name_as: Path | None = None) -> dict[str, Any]:
    """Collect the curriculum into ``out_dir`` (``stageK.npz`` FlightLogs and
    ``models/stageK`` model dirs, plus ``models/final`` trained on everything). With deep stages
    configured, ``models/paper`` is the model of the paper's curriculum (down to
    ``min_depth_m``), trained before the deep stages were flown.

    The folder is written as a whole (:func:`aerodock.fileio.building_dir`): it is built beside
    ``out_dir`` and swapped in when the last model is saved, so a kill leaves the old
    collection or the new one, never stages and models of two seeds; ``out_dir`` may hold only
    what a collection writes (:data:`OUTPUTS`). Progress goes to ``progress`` meanwhile.

    Args:
        name_as: the folder the summary's paths name (default ``out_dir``), for a caller that
            builds ``out_dir`` itself in a temporary folder and moves it there afterwards.

    Returns a JSON-ready summary (stages, minutes, per-stage validation loss, timings).
    """
    from aerodock.learning.dataset import build_dataset
    from aerodock.learning.train import train_model
    from aerodock.mission.limits import check_flight_steps

    c = cfg.curriculum
    kind = model_kind or c.model
    out_dir = Path(out_dir)
    named = Path(name_as) if name_as is not None else out_dir
    check_flight_steps(cfg, cfg.mission.settle_s + FLIGHT_S, "curriculum flight")
    check_output_dir(out_dir, OUTPUTS)
    logs: list[FlightLog] = []
    predictor = None
    summary: dict[str, Any] = {"stages": [], "model": kind, "seed": seed}
    started = time.perf_counter()
    kwargs = dict(train_kwargs or {})
    # The curriculum keeps the flight split (train_model's rule before split="auto"): a stage's
    # flights are random excitations of one depth band, alike enough that a held-out flight is a
    # fair sample, and the docking results were measured with the models this split gave.
    kwargs.setdefault("split", "flight")
    stages = curriculum_stages(cfg)
    trained = None
    paper_stages = len(curriculum_stages(cfg, deep=False))
    with building_dir(out_dir, OUTPUTS) as work:
        (work / "models").mkdir()
        for stage in stages:
            t0 = time.perf_counter()
            flights = int(c.deep_flights_per_stage if stage.deep else c.flights_per_stage)
            if progress:
                progress(f"stage {stage.index}: flying {flights} flights at "
                         f"{stage.depth_min_m:.2f}-{stage.depth_max_m:.2f} m"
                         + (" with the stage model" if predictor is not None else ""))
            stage_logs = excitation_flights(
                cfg, flights, stage.depth_min_m, stage.depth_max_m,
                seed + 1000 * stage.index, predictor, name=f"stage{stage.index}",
            )
            save_flightlogs(work / f"stage{stage.index}.npz", stage_logs)
            logs.extend(stage_logs)
            fly_s = time.perf_counter() - t0
            if progress:
                progress(f"stage {stage.index}: training {kind} on {len(logs)} flights")
            t1 = time.perf_counter()
            trained = train_model(kind, build_dataset(logs), seed=seed, **kwargs)
            trained.save(work / "models" / f"stage{stage.index}")
            predictor = trained.predictor()
            if stage.index == paper_stages - 1:
                trained.save(work / "models" / "paper")
                summary["paper_model"] = str(named / "models" / "paper")
            summary["stages"].append({
                "stage": stage.index, "depth_band_m": [stage.depth_min_m, stage.depth_max_m],
                "flights": len(stage_logs),
                "minutes": sum(lg.duration_s for lg in stage_logs) / 60,
                "fly_s": fly_s, "train_s": time.perf_counter() - t1,
                "val_rmse_mps2": trained.info.get("val_rmse_mps2"),
            })
        if trained is not None:
            trained.save(work / "models" / "final")
    summary["minutes"] = sum(lg.duration_s for lg in logs) / 60
    summary["flights"] = len(logs)
    summary["wall_s"] = time.perf_counter() - started
    summary["final_model"] = str(named / "models" / "final")
    return summary
