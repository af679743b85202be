"""Animations of a docking trial (or any two-vehicle FlightLog), drawn with matplotlib.

A :class:`Track` holds what is drawn, from a FlightLog (:func:`track_from_flightlog`: simulated
with ``dock --save-logs`` or ingested from real logs) or from a campaign trace
(:func:`track_from_trace`). Each frame has a side view along the approach (the horizontal
direction from the follower's start to the bar, :func:`approach_direction`, against altitude) and
a top view (east against north): both vehicles with their arms (attitude from the log), the bar
and its two cables, the gate's state (colour of the follower's gripper) and the predicted-force
arrow, with a legend naming each of them. What a log lacks is left out and said on the frame (a
real log has no bar, gate or prediction).

GIFs are written with Pillow (always available with matplotlib), each frame shown for
``1000 / fps`` ms on average (GIF delays are whole centiseconds: :func:`gif_durations_ms`);
``.mp4`` needs ffmpeg on PATH.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.config import Config, load_config
from aerodock.fileio import atomic_open
from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.mission import Phase
from aerodock.plots import _plt
from aerodock.world.gripper import GateState

GATE_COLOURS = {GateState.OPEN: "tab:green", GateState.CLOSING: "tab:orange",
                GateState.CAPTURED: "tab:blue", GateState.MISSED: "tab:red"}
FORCE_SCALE_M_PER_MPS2 = 0.05  # a 10 m/s² predicted force is drawn 0.5 m long
CRAZYFLIE_DIAGONAL_M = 0.092  # motor-to-motor (real Crazyflie logs carry no size)


@cache
def _shipped() -> Config:
    """The shipped defaults (``defaults.toml``): the sizes a log or trace does not carry."""
    return load_config()
FIGSIZE_IN = (10.0, 5.6)
"""Size of an animation's frame, inches (800 x 448 pixels at the default 80 dpi)."""
LEADER_COLOUR, FOLLOWER_COLOUR, BAR_COLOUR, CABLE_COLOUR, FORCE_COLOUR = (
    "black", "tab:purple", "tab:brown", "0.5", "tab:red")
COMPASS = ("north", "north-east", "east", "south-east", "south", "south-west", "west",
           "north-west")


@dataclass
class Track:
    """What an animation draws, T samples, NED, SI units (optional parts may be None)."""

    t_s: np.ndarray
    leader_p: np.ndarray
    follower_p: np.ndarray
    leader_R: np.ndarray | None = None  # (T, 3, 3) body to world
    follower_R: np.ndarray | None = None
    bar_p: np.ndarray | None = None
    gate: np.ndarray | None = None  # (T,) GateState values
    force_mps2: np.ndarray | None = None  # (T, 3) predicted external acceleration
    diagonal_m: float = field(default_factory=lambda: _shipped().vehicle.diagonal_m)
    anchor_below_leader_m: float = field(
        default_factory=lambda: _shipped().platform.anchor_below_leader_m)
    cable_spacing_m: float = field(default_factory=lambda: _shipped().platform.cable_spacing_m)
    title: str = "trial"
    notes: list[str] = field(default_factory=list)

    @property
    def n_samples(self) -> int:
        """Number of time samples."""
        return int(self.t_s.shape[0])


def track_from_flightlog(log: FlightLog, cfg: Any | None = None) -> Track:
    """A Track from one FlightLog; the bar, gate and predicted force where the log has them.

    The gate state is the log's ``gate`` extra if it has one, else it comes from the mission
    phase the simulator logs (captured, missed, or open while approaching; a closing gate is then
    not shown).
    """
    extra = log.extra
    bar = extra.get("bar_pos_m")
    gate = None
    if "gate" in extra:  # a log that records the gate itself (GateState values)
        gate = np.asarray(extra["gate"]).astype(int)
    elif "phase" in extra:
        phase = np.asarray(extra["phase"])
        gate = np.full(phase.shape, int(GateState.OPEN))
        gate[phase == Phase.CAPTURED] = GateState.CAPTURED
        gate[phase == Phase.MISSED] = GateState.MISSED
        # After the follower is done the gate keeps the state it resolved to.
        for k in range(1, len(gate)):
            if phase[k] == Phase.DONE:
                gate[k] = gate[k - 1]
    force = extra.get("feedforward_mps2")
    if force is not None and not np.any(force):
        force = None  # flown without a feed-forward model: nothing predicted
    shipped = _shipped()
    mass = float(log.meta.get("follower_mass_kg", shipped.vehicle.mass_kg))
    diagonal = float(log.meta.get("diagonal_m", CRAZYFLIE_DIAGONAL_M if mass < 0.1
                                  else shipped.vehicle.diagonal_m))
    notes = []
    if bar is None:
        notes.append("no bar in this log")
    if gate is None:
        notes.append("no gate state in this log")
    if force is None:
        notes.append("no predicted force in this log")
    plat = (cfg if cfg is not None else shipped).platform
    return Track(
        t_s=log.t_s - log.t_s[0], leader_p=log.leader_pos_m, follower_p=log.follower_pos_m,
        leader_R=quat_to_rotmat(log.leader_quat), follower_R=quat_to_rotmat(log.follower_quat),
        bar_p=bar, gate=gate, force_mps2=force, diagonal_m=diagonal,
        anchor_below_leader_m=plat.anchor_below_leader_m, cable_spacing_m=plat.cable_spacing_m,
        title=f"{log.name} ({log.meta.get('source', 'log')})", notes=notes)


def track_from_trace(trace: dict[str, np.ndarray], trial: int, cfg: Any,
                     title: str = "docking") -> Track:
    """A Track from a ``run_campaign(record="trace")`` trace, one trial (attitudes not traced:
    the vehicles are drawn level)."""
    ff = trace["ff"][:, trial]
    return Track(t_s=np.asarray(trace["t_s"]), leader_p=trace["leader_p"][:, trial],
                 follower_p=trace["follower_p"][:, trial], bar_p=trace["bar_p"][:, trial],
                 gate=trace["gate"][:, trial], force_mps2=ff if np.any(ff) else None,
                 diagonal_m=cfg.vehicle.diagonal_m,
                 anchor_below_leader_m=cfg.platform.anchor_below_leader_m,
                 cable_spacing_m=cfg.platform.cable_spacing_m, title=title)


# -- drawing -------------------------------------------------------------------------------------
def _arms(p: np.ndarray, R: np.ndarray | None, diagonal_m: float) -> np.ndarray:
    """(2, 2, 3) the two motor-to-motor arms (X frame) as segments, world NED."""
    half = diagonal_m / 2.0
    c = half / np.sqrt(2.0)
    body = np.array([[[c, c, 0.0], [-c, -c, 0.0]], [[c, -c, 0.0], [-c, c, 0.0]]])
    rot = np.eye(3) if R is None else R
    return p + body @ rot.T


def approach_direction(track: Track) -> np.ndarray:
    """(2,) unit horizontal direction (north, east) from the follower's first position to the
    bar's (the leader's when the log has no bar): the side view looks across it, so the approach
    runs left to right. North when the two start stacked (closer than 1 cm horizontally)."""
    target = track.bar_p if track.bar_p is not None else track.leader_p
    d = np.asarray(target[0][:2] - track.follower_p[0][:2], dtype=float)
    dist = float(np.hypot(d[0], d[1]))
    return d / dist if dist > 0.01 else np.array([1.0, 0.0])


def heading_name(direction: np.ndarray) -> str:
    """``direction`` (north, east) as a compass heading: ``"90° (east)"``."""
    deg = float(np.degrees(np.arctan2(direction[1], direction[0]))) % 360.0
    return f"{deg:.0f}° ({COMPASS[int(round(deg / 45.0)) % 8]})"


def _limits(pts: np.ndarray, diagonal_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half-span of every point in ``pts`` (..., d), padded for the vehicles."""
    allp = pts.reshape(-1, pts.shape[-1])
    lo, hi = allp.min(0), allp.max(0)
    pad = 0.15 + 0.6 * diagonal_m
    return (lo + hi) / 2, (hi - lo) / 2 + pad


def _legend_handles(track: Track, gate: GateState | None) -> tuple[list[Any], list[str]]:
    """Legend entries for what a frame of ``track`` draws (the gripper's entry in the colour
    and with the name of the gate's state ``gate``)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=LEADER_COLOUR, lw=2.5, marker="o", ms=4),
               Line2D([], [], color=FOLLOWER_COLOUR, lw=2.5, marker="o", ms=4),
               Line2D([], [], color=FOLLOWER_COLOUR, lw=0.8, alpha=0.6)]
    labels = ["leader", "follower", "follower's path"]
    if track.bar_p is not None:
        handles += [Line2D([], [], color=BAR_COLOUR, lw=3),
                    Line2D([], [], color=CABLE_COLOUR, lw=0.8)]
        labels += ["bar", "bar's cables"]
    if gate is not None:
        handles.append(Line2D([], [], color=GATE_COLOURS[gate], lw=2, marker="s", ms=6))
        labels.append(f"gripper (gate {gate.name.lower()})")
    if track.force_mps2 is not None:
        handles.append(Line2D([], [], color=FORCE_COLOUR, lw=1.5, marker=">", ms=6))
        labels.append("predicted wake force (0.5 m = 10 m/s²)")
    return handles, labels


class FrameDrawer:
    """Draws frame ``k`` of a Track on a side and a top axis (artists re-created per frame)."""

    def __init__(self, track: Track, figsize: tuple[float, float] = FIGSIZE_IN, dpi: int = 80):
        plt = _plt()
        from matplotlib.layout_engine import TightLayoutEngine
        self.track = track
        self.direction = approach_direction(track)
        self.fig, (self.ax_side, self.ax_top) = plt.subplots(1, 2, figsize=figsize, dpi=dpi)
        pts = np.concatenate([track.leader_p, track.follower_p]
                             + ([track.bar_p] if track.bar_p is not None else []))
        centre, half = _limits(np.stack(self._side(pts), axis=-1), track.diagonal_m)
        span_side = half.max()
        self.ax_side.set_xlim(centre[0] - span_side, centre[0] + span_side)
        self.ax_side.set_ylim(centre[1] - span_side, centre[1] + span_side)
        centre, half = _limits(pts[:, :2], track.diagonal_m)
        span_top = half.max()
        self.ax_top.set_xlim(centre[1] - span_top, centre[1] + span_top)
        self.ax_top.set_ylim(centre[0] - span_top, centre[0] + span_top)
        self.ax_side.set_xlabel(f"along the approach, heading {heading_name(self.direction)} [m]")
        self.ax_side.set_ylabel("altitude [m]")
        self.ax_top.set_xlabel("east [m]")
        self.ax_top.set_ylabel("north [m]")
        for ax in (self.ax_side, self.ax_top):
            ax.set_aspect("equal")
            ax.grid(alpha=0.3)
        self.ax_side.set_title("side view (the approach runs left to right)")
        self.ax_top.set_title("top view")
        self._artists: list[Any] = []
        self._background: Any = None  # the still parts, once drawn (blitted_rgba)
        self._footer: tuple[GateState | None, list[Any]] = (None, [])  # legend, gate caption
        self._footer_pixels: dict[GateState | None, Any] = {}  # drawn once per gate state
        # The tight layout placed once, not kept as the figure's layout engine: with an engine
        # (even the placeholder ``tight_layout`` leaves), every saved frame is drawn twice
        # (layout, then pixels); the axes do not move between frames, so the same pixels
        TightLayoutEngine(rect=(0, 0.15, 1, 0.88)).execute(self.fig)

    # Views: side (along the approach, up), top (east, north).
    def _side(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points ``p`` (..., 3) NED in the side view: distance along the approach, altitude."""
        return p[..., 0] * self.direction[0] + p[..., 1] * self.direction[1], -p[..., 2]

    @staticmethod
    def _top(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return p[..., 1], p[..., 0]

    def draw(self, k: int) -> None:
        """Replace the frame's artists with those of sample ``k``."""
        for art in self._artists:
            art.remove()
        self._artists = []
        tr = self.track
        lp, fp = tr.leader_p[k], tr.follower_p[k]
        lR = None if tr.leader_R is None else tr.leader_R[k]
        fR = None if tr.follower_R is None else tr.follower_R[k]
        gate = None if tr.gate is None else GateState(int(tr.gate[k]))
        for ax, view in ((self.ax_side, self._side), (self.ax_top, self._top)):
            add = self._artists.extend
            add(ax.plot(*view(tr.follower_p[:k + 1]), color=FOLLOWER_COLOUR, lw=0.8, alpha=0.6))
            for p, R, colour in ((lp, lR, LEADER_COLOUR), (fp, fR, FOLLOWER_COLOUR)):
                for seg in _arms(p, R, tr.diagonal_m):
                    add(ax.plot(*view(seg), color=colour, lw=2.5, solid_capstyle="round"))
                add(ax.plot(*view(p), "o", color=colour, ms=4))
            if tr.bar_p is not None:
                self._draw_bar(ax, view, lp, lR, tr.bar_p[k])
            if gate is not None:
                up = -(np.eye(3) if fR is None else fR)[:, 2]
                arm = fp + up * 0.05
                add(ax.plot(*view(np.stack([fp, arm])), color=GATE_COLOURS[gate], lw=2))
                add(ax.plot(*view(arm), "s", color=GATE_COLOURS[gate], ms=6))
            if tr.force_mps2 is not None:
                f = tr.force_mps2[k] * FORCE_SCALE_M_PER_MPS2
                (x0, y0), (dx, dy) = view(fp), view(f)
                if np.hypot(dx, dy) > 1e-4:
                    self._artists.append(ax.arrow(x0, y0, dx, dy, color=FORCE_COLOUR, width=0.004,
                                                  head_width=0.025, length_includes_head=True))
        status = [f"t = {tr.t_s[k]:5.2f} s"]
        if gate is not None:
            status.append(f"gate {gate.name.lower()}")
        sep = np.linalg.norm(fp - lp)
        status.append(f"separation {sep:.2f} m")
        lines = [tr.title, "   ".join(status)]
        if tr.notes:
            lines[-1] += "   (" + "; ".join(tr.notes) + ")"
        self._artists.append(self.fig.text(0.5, 0.97, "\n".join(lines), ha="center", va="top",
                                           fontsize=9))
        handles, labels = _legend_handles(tr, gate)
        footer = [self.fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8,
                                  frameon=False, bbox_to_anchor=(0.5, 0.03))]
        if gate is not None:
            footer.append(self.fig.text(
                0.5, 0.01, "gripper colour: green open, orange closing, blue captured, red missed",
                ha="center", va="bottom", fontsize=8))
        self._artists.extend(footer)
        self._footer = (gate, footer)  # (what it depends on: the track and the gate's state)

    def _draw_bar(self, ax, view, lp, lR, bar_p) -> None:
        tr = self.track
        rot = np.eye(3) if lR is None else lR
        along = rot[:, 1] * tr.cable_spacing_m / 2  # cables attached along the leader's y axis
        anchor = lp + rot[:, 2] * tr.anchor_below_leader_m
        ends = np.stack([bar_p - along, bar_p + along])
        add = self._artists.extend
        for sign, end in zip((-1, 1), ends, strict=True):
            add(ax.plot(*view(np.stack([anchor + sign * along, end])), color=CABLE_COLOUR,
                        lw=0.8))
        add(ax.plot(*view(ends), color=BAR_COLOUR, lw=3, zorder=4))
        add(ax.plot(*view(bar_p), "o", color=BAR_COLOUR, ms=4, zorder=4))  # seen end-on too

    def rgb(self) -> np.ndarray:
        """The current frame as an (H, W, 3) uint8 array."""
        self.fig.canvas.draw()
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def blitted_rgba(self, k: int) -> np.ndarray:
        """Frame ``k`` as an (H, W, 4) uint8 array, drawn over the figure's still parts (axes,
        ticks, grid, titles) rendered once and kept: a frame redraws only what moves, about a
        quarter of a whole figure's drawing. What moves is drawn above the still parts (the force
        arrow above the grid, where a whole-figure draw puts it below)."""
        from matplotlib.transforms import Bbox

        canvas = self.fig.canvas
        if self._background is None:
            for art in self._artists:
                art.remove()
            self._artists = []
            canvas.draw()
            self._background = canvas.copy_from_bbox(self.fig.bbox)
        self.draw(k)
        canvas.restore_region(self._background)
        gate, footer = self._footer
        for art in sorted(self._artists, key=lambda a: a.get_zorder()):
            art.set_animated(True)  # (kept out of any later whole-figure draw)
            if not any(art is f for f in footer):
                (art.axes or self.fig).draw_artist(art)
        # The legend and the gate's caption, below the axes where nothing else draws, change
        # only with the gate's state: their pixels are drawn once a state and kept
        pixels = self._footer_pixels.get(gate)
        if pixels is None:
            for art in footer:
                self.fig.draw_artist(art)
            renderer = canvas.get_renderer()
            box = Bbox.union([art.get_window_extent(renderer) for art in footer]).padded(2)
            pixels = self._footer_pixels[gate] = canvas.copy_from_bbox(box)
        else:
            canvas.restore_region(pixels)
        return np.asarray(canvas.buffer_rgba()).copy()

    def close(self) -> None:
        """Free the figure."""
        _plt().close(self.fig)


def frame_indices(t_s: np.ndarray, fps: float, speed: float = 1.0,
                  max_frames: int | None = None) -> np.ndarray:
    """Sample indices for frames every ``speed / fps`` seconds of flight (at most ``max_frames``,
    evenly spread)."""
    t = t_s - t_s[0]
    wanted = np.arange(0.0, t[-1] + 1e-9, speed / fps)
    idx = np.unique(np.clip(np.searchsorted(t, wanted), 0, len(t) - 1))
    if max_frames is not None and len(idx) > max_frames:
        idx = idx[np.linspace(0, len(idx) - 1, max_frames).round().astype(int)]
    return idx


def gif_durations_ms(n_frames: int, fps: float) -> list[int]:
    """How long each of ``n_frames`` GIF frames shows, ms, so that frame ``j`` starts at
    ``j * 1000 / fps`` ms rounded to the GIF's centiseconds: every delay is within 10 ms of
    ``1000 / fps`` and the whole animation lasts ``n_frames * 1000 / fps`` ms (to 5 ms)."""
    starts_cs = np.round(np.arange(n_frames + 1) * 100.0 / fps).astype(int)
    return [int(d) * 10 for d in np.maximum(np.diff(starts_cs), 1)]


def _write_gif(drawer: FrameDrawer, frames: Iterable[int], fps: float, path: Path) -> None:
    """The GIF of ``frames`` (samples), each drawn over the still parts
    (:meth:`FrameDrawer.blitted_rgba`) and converted as matplotlib's ``PillowWriter`` converts
    its frames, with each frame's delay from :func:`gif_durations_ms` (``PillowWriter`` writes
    ``int(1000 / fps)`` ms, which the GIF truncates: 60 ms at 15 fps)."""
    from PIL import Image

    images = []
    for k in frames:
        rgba = drawer.blitted_rgba(k)
        im = Image.frombuffer("RGBA", (rgba.shape[1], rgba.shape[0]), rgba, "raw", "RGBA", 0, 1)
        images.append(im if im.getextrema()[3][0] < 255 else im.convert("RGB"))
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=gif_durations_ms(len(images), fps), loop=0)


def render_animation(track: Track, out: str | Path, fps: float = 15.0, speed: float = 1.0,
                     max_frames: int | None = 300, dpi: int = 80,
                     progress: Any = None) -> Path:
    """Write the animation of ``track`` to ``out`` (``.gif``, or ``.mp4`` with ffmpeg).

    Args:
        track: what to draw.
        out: output file; the suffix picks the format.
        fps: frames per second of the video.
        speed: seconds of flight per second of video.
        max_frames: cap on the number of frames (evenly spread over the flight).
        dpi: resolution (the frame is :data:`FIGSIZE_IN` inches: 800 px wide at 80 dpi).
        progress: called as ``progress(done, total)`` after every frame.

    Raises:
        ValueError: unknown suffix, or ``.mp4`` without ffmpeg.
    """
    from matplotlib.animation import FFMpegWriter

    out = Path(out)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"{out}: the video must be .gif or .mp4")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ValueError(f"{out}: writing MP4 needs ffmpeg on PATH; write a .gif instead")
    if not fps > 0 or not speed > 0:
        raise ValueError("fps and speed must be > 0")
    idx = frame_indices(track.t_s, fps, speed, max_frames)
    drawer = FrameDrawer(track, dpi=dpi)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.stem}.partial{suffix}")

    def frames() -> Iterator[int]:
        for j, k in enumerate(idx):
            yield int(k)
            if progress is not None:
                progress(j + 1, len(idx))

    try:
        if suffix == ".gif":
            _write_gif(drawer, frames(), fps, tmp)
        else:
            writer = FFMpegWriter(fps=fps)
            with writer.saving(drawer.fig, str(tmp), dpi):
                for k in frames():
                    drawer.draw(k)
                    writer.grab_frame()
        with atomic_open(out, "wb") as fh:  # never a half-written video under the final name
            fh.write(tmp.read_bytes())
        umask = os.umask(0)
        os.umask(umask)
        out.chmod(0o666 & ~umask)  # readable like any figure (the temporary file was private)
    finally:
        tmp.unlink(missing_ok=True)
        drawer.close()
    return out


def render_env_frame(history: list[dict[str, Any]], cfg: Any) -> np.ndarray:
    """One RGB frame of a :class:`aerodock.envs.DockingEnv` episode so far (its ``render``)."""
    if not history:
        raise ValueError("nothing to render before reset()")
    t = np.arange(len(history)) * cfg.timing.control_dt_s
    track = Track(t_s=t, leader_p=np.array([h["leader"] for h in history]),
                  follower_p=np.array([h["follower"] for h in history]),
                  bar_p=np.array([h["bar"] for h in history]),
                  gate=np.array([h["gate"] for h in history]),
                  diagonal_m=cfg.vehicle.diagonal_m,
                  anchor_below_leader_m=cfg.platform.anchor_below_leader_m,
                  cable_spacing_m=cfg.platform.cable_spacing_m, title="aerodock/Docking-v0")
    drawer = FrameDrawer(track, dpi=64)
    try:
        drawer.draw(len(history) - 1)
        return drawer.rgb()
    finally:
        drawer.close()
