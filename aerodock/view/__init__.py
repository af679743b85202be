"""Watching a trial: animations of FlightLogs (``aerodock view``) and an optional rerun stream."""

from aerodock.view.render import (
    FrameDrawer,
    Track,
    approach_direction,
    frame_indices,
    gif_durations_ms,
    render_animation,
    track_from_flightlog,
    track_from_trace,
)

__all__ = ["FrameDrawer", "Track", "approach_direction", "frame_indices", "gif_durations_ms",
           "render_animation", "track_from_flightlog", "track_from_trace"]
