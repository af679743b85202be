"""Inspecting a field: mean and spread at a point (on the follower, or on the docking bar), and a
vertical slice through the wake. A field without ``mean_acceleration`` is shown through
:func:`aerodock.downwash.mean.mean_acceleration_fn` (an estimate, said so in the output)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from aerodock.downwash.base import BodyState, DownwashField
from aerodock.downwash.mean import mean_acceleration_fn, mean_source
from aerodock.downwash.wrench import bar_wake_force_n


def probe_bodies(separation_m: np.ndarray, radial_m: np.ndarray, leader_speed_mps: float,
                 mass_kg: float, gravity_mps2: float, azimuth_rad: float = 0.0,
                 leader_mass_kg: float | None = None) -> tuple[BodyState, BodyState]:
    """A hovering (or north-moving) leader at the origin and followers at the given points.

    The follower is ``separation_m`` below and ``radial_m`` to the side (direction ``azimuth_rad``
    from north) and moves with the leader, so only the geometry changes between points. Both
    hover at their weight: the follower's ``mass_kg``, the leader's ``leader_mass_kg`` (None:
    the follower's).
    """
    sep = np.atleast_1d(np.asarray(separation_m, float))
    rad = np.atleast_1d(np.asarray(radial_m, float))
    sep, rad = np.broadcast_arrays(sep, rad)
    n = sep.shape[0]
    eye = np.repeat(np.eye(3)[None], n, 0)
    vel = np.zeros((n, 3))
    vel[:, 0] = leader_speed_mps
    mass = np.full(n, mass_kg)
    lead_mass = mass.copy() if leader_mass_kg is None else np.full(n, leader_mass_kg)
    leader = BodyState(np.zeros((n, 3)), vel, eye, lead_mass * gravity_mps2, lead_mass)
    pos = np.stack([rad * np.cos(azimuth_rad), rad * np.sin(azimuth_rad), sep], axis=1)
    follower = BodyState(pos, vel.copy(), eye.copy(), mass * gravity_mps2, mass.copy())
    return leader, follower


def probe_field(field: DownwashField, separation_m: float, radial_m: float,
                leader_speed_mps: float, samples: int, dt_s: float, rng: np.random.Generator,
                mass_kg: float, gravity_mps2: float, azimuth_rad: float = 0.0,
                leader_mass_kg: float | None = None) -> dict[str, Any]:
    """Mean and standard deviation of the acceleration (m/s², NED) a field exerts at a point.

    Draws ``samples`` consecutive values of the field at the physics step ``dt_s`` (so turbulence
    is time-correlated, as in flight) and also reports the field's noise-free mean
    (``field_mean_mps2``): its own ``mean_acceleration`` or, without one, an estimate on a copy
    of the field (``field_mean_source`` says which). The leader hovers at ``leader_mass_kg``'s
    weight (None: the follower's).
    """
    if samples < 2:
        raise ValueError(f"--samples must be >= 2, got {samples}")
    leader, follower = probe_bodies(separation_m, radial_m, leader_speed_mps, mass_kg,
                                    gravity_mps2, azimuth_rad, leader_mass_kg)
    mean_fn = mean_acceleration_fn(field, samples=samples, dt_s=dt_s)  # copies it before reset
    field.reset(1, rng)
    draws = np.empty((samples, 3))
    for k in range(samples):
        draws[k] = field.acceleration(leader, follower, dt_s)[0]
    out: dict[str, Any] = {
        "separation_m": separation_m, "radial_m": radial_m, "leader_speed_mps": leader_speed_mps,
        "samples": samples, "frame": "NED", "unit": "m/s^2",
        "mean_mps2": draws.mean(0).tolist(), "sd_mps2": draws.std(0, ddof=1).tolist(),
    }
    out["field_mean_mps2"] = np.asarray(mean_fn(leader, follower))[0].tolist()
    out["field_mean_source"] = mean_source(mean_fn)
    return out


def probe_bar(field: DownwashField, separation_m: float, radial_m: float, samples: int,
              dt_s: float, rng: np.random.Generator, bar_area_m2: float, mass_kg: float,
              gravity_mps2: float, bar_yaw_rad: float = 0.0,
              leader_mass_kg: float | None = None) -> dict[str, Any] | None:
    """Mean and sd of the wake's force on a bar held still at a point below a hovering leader.

    Draws ``samples`` consecutive values at the physics step ``dt_s``, as the world calls the
    field (one ``acceleration`` for the follower, then ``bar_force_n``, per step; the follower
    is placed 1 m to the side, out of the way). The bar lies horizontal at ``bar_yaw_rad``;
    ``lateral_sd_over_vertical_mean`` is the sd of the horizontal force across the bar (the
    direction that pushes it through a gripper's gate; along its length a cylinder feels no
    drag) over the mean vertical drag.
    The leader hovers at ``leader_mass_kg``'s weight (None: ``mass_kg``'s).
    Returns None if the field has no ``bar_force_n``.
    """
    if getattr(field, "bar_force_n", None) is None:
        return None
    if samples < 2:
        raise ValueError(f"--samples must be >= 2, got {samples}")
    leader, follower = probe_bodies(1.0, 1.0, 0.0, mass_kg, gravity_mps2,
                                    leader_mass_kg=leader_mass_kg)
    bar_p = np.array([[radial_m, 0.0, separation_m]])
    still = np.zeros((1, 3))
    axis = np.array([[np.cos(bar_yaw_rad), np.sin(bar_yaw_rad), 0.0]])
    field.reset(1, rng)
    draws = np.empty((samples, 3))
    for k in range(samples):
        field.acceleration(leader, follower, dt_s)
        draws[k] = bar_wake_force_n(field, leader, bar_p, still, bar_area_m2, dt_s, axis)[0]
    mean, sd = draws.mean(0), draws.std(0, ddof=1)
    vertical = abs(float(mean[2]))
    across = draws[:, 1] * np.cos(bar_yaw_rad) - draws[:, 0] * np.sin(bar_yaw_rad)
    lateral_sd = float(across.std(ddof=1))
    return {
        "separation_m": separation_m, "radial_m": radial_m, "samples": samples, "frame": "NED",
        "unit": "N", "bar_area_m2": bar_area_m2, "bar_yaw_rad": bar_yaw_rad,
        "mean_n": mean.tolist(), "sd_n": sd.tolist(),
        "vertical_sd_over_mean": float(sd[2]) / vertical if vertical > 0 else None,
        "lateral_sd_over_vertical_mean": lateral_sd / vertical if vertical > 0 else None,
    }


def half_magnitude_radius_m(mean_fn, separation_m: float, mass_kg: float, gravity_mps2: float,
                            max_radius_m: float = 1.0) -> float:
    """Radius at which the mean downward acceleration falls to half its on-axis value."""
    radii = np.linspace(0.0, max_radius_m, 2001)
    leader, follower = probe_bodies(np.full_like(radii, separation_m), radii, 0.0, mass_kg,
                                    gravity_mps2)
    down = mean_fn(leader, follower)[:, 2]
    below = np.nonzero(down <= 0.5 * down[0])[0]
    return float(radii[below[0]]) if below.size else float("nan")


def plot_field_slice(mean_fn, path: Path, mass_kg: float, gravity_mps2: float,
                     leader_speed_mps: float = 0.0, title: str = "downwash field") -> Path:
    """Draw a vertical north-down slice through the wake (PNG) with radial profiles."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    xs = np.linspace(-0.6, 0.6, 121)
    zs = np.linspace(0.05, 2.0, 140)
    gx, gz = np.meshgrid(xs, zs)
    leader, follower = probe_bodies(gz.ravel(), gx.ravel(), leader_speed_mps, mass_kg,
                                    gravity_mps2)
    acc = mean_fn(leader, follower)
    down = acc[:, 2].reshape(gz.shape)
    north = acc[:, 0].reshape(gz.shape)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 5), gridspec_kw={"width_ratios": [1.3, 1]})
    im = ax.pcolormesh(gx, gz, down, shading="auto", cmap="viridis")
    fig.colorbar(im, ax=ax, label="mean downward acceleration on follower [m/s²]")
    step = (slice(None, None, 10), slice(None, None, 10))
    ax.quiver(gx[step], gz[step], north[step], np.zeros_like(north[step]), color="w",
              scale=10, width=0.004)
    ax.invert_yaxis()
    ax.set_xlabel("north offset from leader [m] (arrows: planar force)")
    ax.set_ylabel("depth below leader [m]")
    ax.set_title(f"{title}, leader speed {leader_speed_mps:g} m/s north")
    for sep in (0.36, 0.64, 1.35):
        lead, fol = probe_bodies(np.full_like(xs, sep), xs, leader_speed_mps, mass_kg,
                                 gravity_mps2)
        prof = mean_fn(lead, fol)
        ax2.plot(xs, prof[:, 2], label=f"down, {sep} m")
        ax2.plot(xs, prof[:, 0], "--", label=f"north, {sep} m")
    ax2.set_xlabel("north offset [m]")
    ax2.set_ylabel("acceleration [m/s²]")
    ax2.set_title("profiles at the calibration depths")
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
