"""``aerodock view``: animations of simulated and real FlightLogs, and the report's GIF."""

from __future__ import annotations

import numpy as np
import pytest
from cli_process import aerodock
from PIL import Image

from aerodock.flightlog import load_flightlogs, save_flightlogs
from aerodock.mission import MissionSpec, run_campaign
from aerodock.view import (
    FrameDrawer,
    Track,
    approach_direction,
    frame_indices,
    gif_durations_ms,
    render_animation,
    track_from_flightlog,
)

BROWN = np.array([140, 86, 75])  # matplotlib tab:brown: the bar
PURPLE = np.array([148, 103, 189])  # tab:purple: the follower


def frames(path):
    im = Image.open(path)
    out = []
    for k in range(im.n_frames):
        im.seek(k)
        out.append(np.asarray(im.convert("RGB")).astype(int))
    return out


def has_colour(img, rgb, tol=14):
    return bool(np.any(np.all(np.abs(img - rgb) <= tol, axis=-1)))


def has_blue(img):
    """Gate captured (tab:blue, whatever the GIF palette made of it)."""
    return bool(np.any((img[..., 2] - img[..., 0] > 80) & (img[..., 2] > 140)))


def has_green(img):
    """Gate open (tab:green)."""
    return bool(np.any((img[..., 1] - img[..., 0] > 70) & (img[..., 1] - img[..., 2] > 70)))


@pytest.fixture(scope="module")
def docked(short_cfg):
    """One docked oracle trial, its trace and its FlightLog: what the views draw (whatever the
    mission's timing: the short one, tests/short_mission.py)."""
    res = run_campaign(short_cfg, MissionSpec(trials=1, compensation="oracle", seed=0),
                       record="full")
    assert res.success[0]
    return res


@pytest.fixture(scope="module")
def sim_log(tmp_path_factory, docked):
    return save_flightlogs(tmp_path_factory.mktemp("sim") / "dock.npz", docked.logs)


def test_view_simulated_log_draws_vehicles_bar_and_gate(sim_log, tmp_path):
    out = tmp_path / "dock.gif"
    proc = aerodock("view", str(sim_log), "--out", str(out), "--fps", "5", "--start", "3",
                    "--duration", "3")
    assert proc.returncode == 0, proc.stderr
    imgs = frames(out)
    log = load_flightlogs(sim_log)[0]
    t = log.t_s - log.t_s[0]
    keep = (t >= 3) & (t <= 6)
    assert len(imgs) == len(frame_indices(t[keep], 5.0))
    assert all(has_colour(f, PURPLE) and has_colour(f, BROWN) for f in imgs)
    # The gate is drawn open (green) before the capture and captured (blue) after it.
    assert has_green(imgs[0]) and not has_blue(imgs[0])
    assert has_blue(imgs[-1]) and not has_green(imgs[-1])


def test_view_real_log_degrades_without_bar(shared_data, tmp_path):
    from aerodock.ingest import read_logs

    d = shared_data("neural-swarm", "swap_ss")
    logs = read_logs("neural-swarm", [d / "cf50_00.csv", d / "cf51_00.csv"])
    path = save_flightlogs(tmp_path / "real.npz", logs)
    track = track_from_flightlog(logs[0])
    assert track.bar_p is None and track.gate is None and track.force_mps2 is None
    assert "no bar in this log" in track.notes
    out = tmp_path / "real.gif"
    proc = aerodock("view", str(path), "--out", str(out), "--duration", "2", "--fps", "4")
    assert proc.returncode == 0, proc.stderr
    imgs = frames(out)
    assert len(imgs) >= 8
    assert all(has_colour(f, PURPLE) and not has_colour(f, BROWN, tol=6) for f in imgs)
    # The vehicles move: consecutive frames differ.
    assert np.abs(imgs[0] - imgs[-1]).sum() > 0


def test_view_refuses_bad_input_in_one_line(sim_log, tmp_path):
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    for args, text in (([str(junk)], "corrupt or unreadable"),
                       ([str(sim_log), "--out", str(tmp_path / "v.avi")], ".gif or .mp4"),
                       ([str(sim_log), "--flight", "3"], "out of range"),
                       ([str(sim_log), "--start", "99"], "no samples"),
                       ([str(sim_log), "--max-frames", "0"], "--max-frames must be at least 1")):
        proc = aerodock("view", *args)
        assert proc.returncode == 2, proc.stderr
        assert text in proc.stderr and proc.stderr.strip().count("\n") == 0


def test_mp4_needs_ffmpeg_or_writes_one(sim_log, tmp_path, monkeypatch):
    import shutil

    track = track_from_flightlog(load_flightlogs(sim_log)[0])
    if shutil.which("ffmpeg") is None:
        with pytest.raises(ValueError, match="ffmpeg"):
            render_animation(track, tmp_path / "v.mp4")
    else:
        path = render_animation(track, tmp_path / "v.mp4", max_frames=5)
        assert path.stat().st_size > 0


def test_rerun_stream_saves_a_recording(sim_log, tmp_path):
    pytest.importorskip("rerun")
    from aerodock.view.rerun_stream import stream_to_rerun

    track = track_from_flightlog(load_flightlogs(sim_log)[0].slice(0, 50))
    path = stream_to_rerun(track, save=tmp_path / "dock.rrd")
    assert path.stat().st_size > 1000


def test_report_embeds_an_animated_docking(docked, short_cfg, tmp_path):
    from aerodock.experiments.report import fig_docking_animation

    tr = dict(docked.trace, success=docked.success, arrival_s=docked.arrival_s)
    path = fig_docking_animation(tr, tmp_path, short_cfg)
    imgs = frames(path)
    assert path.name == "hover_docking.gif" and 10 <= len(imgs) <= 60
    assert Image.open(path).size[0] >= 800  # readable in the report
    assert has_green(imgs[0]) and has_blue(imgs[-1])  # open, then captured


def east_approach(n=40):
    """A follower flying west at constant altitude onto a bar under a hovering leader."""
    t = np.linspace(0.0, 3.9, n)
    east = np.linspace(1.0, 0.0, n)
    follower = np.stack([np.zeros(n), east, np.full(n, -1.6)], axis=1)
    leader = np.tile([0.0, 0.0, -2.5], (n, 1))
    bar = np.tile([0.0, 0.0, -2.1], (n, 1))
    gate = np.full(n, 0)
    return Track(t_s=t, leader_p=leader, follower_p=follower, bar_p=bar, gate=gate,
                 force_mps2=np.tile([0.0, 0.0, 3.0], (n, 1)), title="east approach")


def legend_texts(drawer):
    return [t.get_text() for t in drawer.fig.legends[0].get_texts()]


def test_frame_has_a_legend_of_what_it_draws():
    track = east_approach()
    drawer = FrameDrawer(track)
    try:
        drawer.draw(5)
        texts = legend_texts(drawer)
        assert texts[:3] == ["leader", "follower", "follower's path"]
        assert "bar" in texts and "bar's cables" in texts
        assert "gripper (gate open)" in texts
        assert any(t.startswith("predicted wake force") for t in texts)
        assert len(drawer.fig.legends) == 1  # redrawn, not stacked, frame after frame
    finally:
        drawer.close()
    bare = Track(t_s=track.t_s, leader_p=track.leader_p, follower_p=track.follower_p)
    drawer = FrameDrawer(bare)
    try:
        drawer.draw(0)
        assert legend_texts(drawer) == ["leader", "follower", "follower's path"]
    finally:
        drawer.close()


def test_side_view_looks_along_the_approach():
    """An approach from the east is drawn left to right in the side view, not as a rise."""
    track = east_approach()
    np.testing.assert_allclose(approach_direction(track), [0.0, -1.0])
    drawer = FrameDrawer(track)
    try:
        x, alt = drawer._side(track.follower_p)
        np.testing.assert_allclose(x, np.linspace(-1.0, 0.0, len(x)), atol=1e-12)
        np.testing.assert_allclose(alt, 1.6)
        assert "(west)" in drawer.ax_side.get_xlabel()
        lo, hi = drawer.ax_side.get_xlim()
        assert lo < -1.0 and hi > 0.0  # the whole approach is in view
    finally:
        drawer.close()
    # Stacked starts fall back to north.
    stacked = Track(t_s=track.t_s, leader_p=track.leader_p, follower_p=track.leader_p + 0.5)
    stacked.follower_p[:, :2] = track.leader_p[:, :2]
    np.testing.assert_allclose(approach_direction(stacked), [1.0, 0.0])


@pytest.mark.parametrize("fps", [15.0, 10.0, 7.0])
def test_gif_frames_play_at_the_stated_rate(tmp_path, fps):
    track = east_approach()
    path = render_animation(track, tmp_path / "v.gif", fps=fps, max_frames=12, dpi=40)
    im = Image.open(path)
    durations = []
    for k in range(im.n_frames):
        im.seek(k)
        durations.append(im.info["duration"])
    assert im.n_frames == 12 and durations == gif_durations_ms(12, fps)
    period = 1000.0 / fps
    assert all(abs(d - period) <= 10 for d in durations)
    assert sum(durations) == pytest.approx(12 * period, abs=5)
    if fps == 10.0:
        assert set(durations) == {100}


def test_a_blitted_frame_is_the_whole_figure_drawn():
    """A GIF's frames are drawn over the still parts kept from the first (and the legend kept
    per gate state): each is the frame a whole-figure draw makes, but for the force arrow drawn
    above the grid, and a frame drawn after others is the frame drawn first."""
    track = east_approach()
    track.gate[20:], track.gate[30:] = 1, 2
    drawer = FrameDrawer(track, dpi=40)
    try:
        frames = {k: drawer.blitted_rgba(k) for k in range(40)}
    finally:
        drawer.close()
    for k in (0, 5, 21, 25, 31, 39):
        whole, fresh = FrameDrawer(track, dpi=40), FrameDrawer(track, dpi=40)
        try:
            whole.draw(k)
            expected = whole.rgb()
            first = fresh.blitted_rgba(k)
        finally:
            whole.close()
            fresh.close()
        np.testing.assert_array_equal(frames[k], first)
        differ = np.any(frames[k][..., :3] != expected, axis=2)
        assert differ.mean() < 1e-3, (k, differ.mean())
