"""The Crazyflie world's autopilot gains: fitted to the Crazyflie's identified closed-loop attitude
response, for a given motor time constant.

    .venv/bin/python studies/crazyflie_autopilot_fit.py [--config examples/crazyflie.toml]
        [--motor-tau 0.03] [--json] [--smoke]

drone-models (utiasDSL, ``so_rpy_rotor/params.toml``, ``[cf2x_L250]``) identifies the stock
Crazyflie's attitude response to a commanded angle as ``th'' = -257.2 th - 20.2 th' + 207.1
th_cmd`` (16 rad/s, damping 0.63). This finds the roll/pitch angle and rate gains of our autopilot
(rate integral gain at the default's ratio to the rate gain) whose response to a 5 deg roll step
comes nearest to that model's, normalised to its steady state: the RMS difference over 0.6 s,
minimised by Nelder-Mead from the best point of a small grid. One vehicle, exactly nominal, the
ideal IMU chain, commands held over the control period as the world does. ``--smoke``: one motor
time constant, one grid point, two Nelder-Mead iterations.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from _smoke import add_smoke_option  # studies/, on sys.path
from scipy.optimize import minimize

from aerodock.config import Config, load_config
from aerodock.downwash import build_field
from aerodock.rng import TrialRNG
from aerodock.world import World
from aerodock.world.world import hover_command

ROOT = Path(__file__).resolve().parents[1]
IDENTIFIED = (-257.2, -20.2)  # th'' = a th + b th' + ... (drone-models, cf2x_L250, roll)
STEP_RAD = np.radians(5.0)
SECONDS = 0.6
GRID = [(a, r) for a in (6.0, 9.0, 12.7, 18.0) for r in (10.0, 15.0, 20.2, 30.0, 45.0)]
"""The (attitude, rate) gains tried before Nelder-Mead starts from the best."""


def step_response(cfg: Config) -> tuple[np.ndarray, np.ndarray]:
    """(t, roll / step) of a hovering vehicle after a roll step command."""
    cfg = cfg.with_overrides({
        "vehicle": {"mass_sd": 0.0, "inertia_sd": 0.0, "torque_coeff_sd": 0.0,
                    "motor_tau_sd": 0.0, "thrust_gain_sd": 0.0},
        "imu": {"chain": "ideal", "attitude_noise_rad": 0.0, "gyro_noise_radps": 0.0}})
    world = World(cfg, 1, TrialRNG(0, 1), field=build_field(cfg))
    world.reset(np.array([[0.0, 0.0, -2.5]]), np.array([[5.0, 0.0, -2.5]]))  # far apart
    hover = hover_command(world.vehicle, 1)
    command = replace(hover, roll_rad=np.full(1, STEP_RAD))
    t, roll = [], []
    for k in range(int(round(SECONDS / world.dt_control_s))):
        world.advance(hover, command if k > 0 else hover)
        R = world.follower.R[0]  # noqa: N806
        t.append(world.t_s)
        roll.append(np.arctan2(R[2, 1], R[2, 2]) / STEP_RAD)
    return np.asarray(t) - t[0], np.asarray(roll)


def identified_response(t: np.ndarray, dt: float = 1e-4) -> np.ndarray:
    """The identified second-order model's unit step response at ``t``."""
    a, b = IDENTIFIED
    th = rate = now = 0.0
    out = []
    for target in t:
        while now < target:
            rate += (a * th + b * rate - a) * dt
            th += rate * dt
            now += dt
        out.append(th)
    return np.asarray(out)


def fit(cfg: Config, motor_tau_s: float, grid: list[tuple[float, float]] = GRID,
        maxiter: int = 80) -> dict:
    """The fitted roll/pitch gains and their RMS difference from the identified response."""
    ratio = cfg.autopilot.rate_i[0] / cfg.autopilot.rate_p[0]
    yaw = (cfg.autopilot.attitude_p[2], cfg.autopilot.rate_p[2], cfg.autopilot.rate_i[2])

    def cost(gains: np.ndarray) -> float:
        att, rate = (float(g) for g in gains)
        if att <= 0 or rate <= 0:
            return 10.0
        trial = cfg.with_overrides({
            "vehicle": {"motor_tau_s": motor_tau_s},
            "autopilot": {"attitude_p": [att, att, yaw[0]], "rate_p": [rate, rate, yaw[1]],
                          "rate_i": [rate * ratio, rate * ratio, yaw[2]]}})
        t, roll = step_response(trial)
        if not np.all(np.isfinite(roll)):
            return 10.0
        return float(np.sqrt(np.mean((roll - identified_response(t)) ** 2)))

    best = min((cost(np.array([a, r])), a, r) for a, r in grid)
    res = minimize(cost, np.array(best[1:]), method="Nelder-Mead",
                   options={"xatol": 0.05, "fatol": 1e-4, "maxiter": maxiter})
    return {"motor_tau_s": motor_tau_s, "attitude_p": float(res.x[0]),
            "rate_p": float(res.x[1]), "rate_i": float(res.x[1] * ratio),
            "rms_difference": float(res.fun)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, default=ROOT / "examples" / "crazyflie.toml")
    parser.add_argument("--motor-tau", type=float, action="append",
                        help="motor time constant(s), s (default: 0.03 and 0.072)")
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    cfg = load_config(args.config)
    taus = args.motor_tau or [0.03, 0.072]
    rows = ([fit(cfg, taus[0], GRID[:1], maxiter=2)] if args.smoke
            else [fit(cfg, tau) for tau in taus])
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    for r in rows:
        print(f"motor {r['motor_tau_s']:.3f} s: attitude_p {r['attitude_p']:.2f}, rate_p "
              f"{r['rate_p']:.2f}, rate_i {r['rate_i']:.2f} 1/s; RMS difference "
              f"{r['rms_difference']:.3f} of the step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
