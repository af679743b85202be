"""The heterogeneous pair at the paper's scale (examples/large_leader.toml), and ``collect``
offering the leader-aware model kind.

The large leader is the default vehicle scaled by geometric similarity to twice the mass (lengths
x 2^(1/3)); the default jet takes its thrust and rotors, so the wake on the follower at the
docking separation grows by momentum theory's ratio, not by a figure chosen for it.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from aerodock.cli.learning import COLLECTABLE
from aerodock.config import load_config
from aerodock.downwash import build_field
from aerodock.downwash.probe import probe_bodies
from aerodock.learning.features import KINDS

LARGE_LEADER = Path(__file__).resolve().parents[2] / "examples" / "large_leader.toml"
SCALE = 2.0 ** (1.0 / 3.0)  # lengths of a vehicle of twice the mass, geometric similarity


def _wake_down_mps2(cfg, separation_m: float) -> float:
    field = build_field(cfg)
    field.reset(1, np.random.default_rng(0))
    leader, follower = probe_bodies(np.array([separation_m]), np.array([0.0]), 0.0,
                                    cfg.vehicle.mass_kg, cfg.sim.gravity_mps2,
                                    leader_mass_kg=cfg.leader.mass_kg)
    return float(field.mean_acceleration(leader, follower)[0, 2])


def test_the_large_leader_loads_as_the_default_scaled():
    cfg, default = load_config(LARGE_LEADER), load_config(None)
    assert cfg.vehicle == default.vehicle  # the follower is the paper's
    lead = cfg.leader
    assert lead.mass_kg == pytest.approx(2 * default.vehicle.mass_kg)
    assert lead.rotor_radius_m == pytest.approx(default.vehicle.rotor_radius_m * SCALE, rel=0.01)
    assert lead.diagonal_m == pytest.approx(default.vehicle.diagonal_m * SCALE, rel=0.01)
    assert lead.rotor_thrust_coeff == pytest.approx(
        default.vehicle.rotor_thrust_coeff * SCALE**4, rel=0.01)
    # The follower's side of the dock is the default's.
    assert cfg.platform.cable_length_m == default.platform.cable_length_m
    assert cfg.platform.bar_length_m == default.platform.bar_length_m


def test_the_wake_at_the_docking_separation_grows_by_momentum_theory():
    """The jet's momentum flux is the leader's thrust T, spread over its width b(s) = b0 + k s,
    b0 proportional to the leader's R sqrt(n): the centreline speed w_c ~ sqrt(T) / b is
    sqrt(2) / 1.26 times the default's at the rotor plane, and at 0.36 m (the fitted spread k
    adds the same depth to both widths). On the follower the wake is stronger still: its disks,
    0.095 m off the axis, sit near the default jet's half-width and well inside the wider one."""
    cfg, default = load_config(LARGE_LEADER), load_config(None)
    params = default.data["downwash"]["params"]
    depth_m = 0.36

    def width_m(vehicle):
        return (params["width0_ratio"] * vehicle.rotor_radius_m * np.sqrt(vehicle.n_rotors)
                + params["spread_rate"] * depth_m)

    expected = (np.sqrt(cfg.leader.mass_kg / default.leader.mass_kg)
                * width_m(default.leader) / width_m(cfg.leader))
    assert 1.10 < expected < 1.14
    speeds = []
    for c in (cfg, default):
        leader, _ = probe_bodies(np.array([depth_m]), np.array([0.0]), 0.0, c.vehicle.mass_kg,
                                 c.sim.gravity_mps2, leader_mass_kg=c.leader.mass_kg)
        speeds.append(build_field(c).wind_mps(leader, np.array([[0.0, 0.0, depth_m]]))[0, 2])
    assert speeds[0] / speeds[1] == pytest.approx(expected, rel=1e-6)
    ratio = _wake_down_mps2(cfg, depth_m) / _wake_down_mps2(default, depth_m)
    assert ratio > expected ** params["ingest_exponent"]


def test_collect_offers_every_trainable_kind_but_zero():
    assert set(COLLECTABLE) == set(KINDS) - {"zero"}
    proc = subprocess.run([sys.executable, "-c", "from aerodock.cli import main; main()",
                           "collect", "--out", "unused", "--model", "nope"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0
    assert "so2-leader" in proc.stderr and "nope" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_a_config_may_name_the_leader_aware_kind_for_its_curriculum(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[curriculum]\nmodel = "so2-leader"\n')
    assert load_config(path).curriculum.model == "so2-leader"


def test_a_leader_aware_model_flies_with_the_configured_rotors():
    """A model trained under the 0.7 kg leader, flown under the large one, builds its wake
    scales with the large leader's rotors (its thrust comes from the leader's mass)."""
    from aerodock.mission.params import fly_on_configured_rotors

    class Recorder:
        needs_wake_scales = True
        geometry = None

        def set_rotor_geometry(self, *args):
            self.geometry = args

    model, plain = Recorder(), Recorder()
    plain.needs_wake_scales = False
    cfg = load_config(LARGE_LEADER)
    fly_on_configured_rotors(model, cfg)
    fly_on_configured_rotors(plain, cfg)
    fly_on_configured_rotors(None, cfg)
    assert model.geometry == (cfg.leader.rotor_radius_m, 4, cfg.vehicle.rotor_radius_m, 4)
    assert plain.geometry is None
