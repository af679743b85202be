"""``aerodock node``: run a trained model as a ROS 2 node (rclpy is imported only when it runs).

An error's text is folded onto one line (every run of whitespace, newlines included, becomes
one space), so a message quoting a path or a ``--state-type`` value with two spaces shows one.

ROS's own arguments come last, after ``--ros-args`` (remapping, ``-p use_sim_time:=true``, the
log level), as for any ROS 2 node: the command takes the words it does not know
(:data:`CONTEXT_SETTINGS`), refuses any before ``--ros-args`` and hands the rest to rclpy.
"""

from __future__ import annotations

import os
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from aerodock.cli.common import SetOpt, TrustOpt, fail
from aerodock.fileio import one_line
from aerodock.node.core import (
    DEFAULT_MAX_AGE_S,
    DEFAULT_PUBLISH_MODE,
    DEFAULT_RATE_HZ,
    PublishMode,
)

if TYPE_CHECKING:
    from aerodock.config import Config
    from aerodock.node.ros import NodeSettings

CONTEXT_SETTINGS = {"allow_extra_args": True, "ignore_unknown_options": True}
"""How ``aerodock node`` is registered (:mod:`aerodock.cli.app`): Click keeps the words it does
not know in ``ctx.args``, where ``--ros-args ...`` is taken and anything else refused."""
OPTIONS_METAVAR = "[OPTIONS] [--ros-args ...]"
"""The usage line of ``aerodock node --help``."""


class OutputFrame(StrEnum):
    """World frame of the published f_ext."""

    auto = "auto"
    ned = "ned"
    enu = "enu"


def node_command(
    ctx: typer.Context,
    model: Annotated[Path, typer.Option("--model", help="Trained model directory.")],
    mapping: Annotated[Path | None, typer.Option(
        "--mapping", help="Topic mapping TOML (the bag reader's; default: Freyja's alpha/bravo).",
    )] = None,
    rate: Annotated[float, typer.Option(
        "--rate", help="Output rate, Hz (timer); the watchdog's rate (on-follower).",
    )] = DEFAULT_RATE_HZ,
    publish: Annotated[PublishMode, typer.Option(
        "--publish", help="on-follower: publish on each follower state message, the --rate "
                          "timer publishing only when none went out within its last 1.5 "
                          "periods (a watchdog); timer: publish at --rate only.",
    )] = DEFAULT_PUBLISH_MODE,
    max_age: Annotated[float, typer.Option(
        "--max-age", help="Oldest accepted input, s; older: publish zero, flag stale.",
    )] = DEFAULT_MAX_AGE_S,
    output_topic: Annotated[str, typer.Option(
        "--output-topic", help="f_ext topic (geometry_msgs/Vector3Stamped, m/s²).",
    )] = "/aerodock/f_ext",
    diagnostics_topic: Annotated[str, typer.Option(
        "--diagnostics-topic", help="Diagnostics topic (diagnostic_msgs/DiagnosticArray).",
    )] = "/aerodock/diagnostics",
    output_frame: Annotated[OutputFrame, typer.Option(
        "--output-frame", help="f_ext world frame; auto: from the follower's state type, "
                               "decided once it is known (--state-type, or found on the ROS "
                               "graph; no f_ext before): nav_msgs/Odometry: the mapping's "
                               "frame, ENU by default (REP 103); Freyja's CurrentState and "
                               "PX4's VehicleOdometry: NED. On the diagnostics (output_frame).",
    )] = OutputFrame.auto,
    state_type: Annotated[list[str] | None, typer.Option(
        "--state-type", help="TOPIC=TYPE (e.g. /bravo/odom=nav_msgs/msg/Odometry) instead of "
                             "discovering the type on the ROS graph; repeatable.",
    )] = None,
    duration: Annotated[float | None, typer.Option(
        "--duration", help="Stop after this many seconds (default: run until Ctrl-C).",
    )] = None,
    config: Annotated[Path | None, typer.Option(
        "--config", help="aerodock TOML: the vehicles, to check the model was trained on them; "
                         "a leader-aware model (so2-leader, so2-pair) takes its wake scales "
                         "from them "
                         "(the leader hovering) instead of its training flights'.",
    )] = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
) -> None:
    """Run a trained downwash model as a ROS 2 node next to Freyja or PX4 (the ros extra).

    ROS's own arguments go last, after --ros-args (remapping, parameters, log level), and are
    passed to rclpy: aerodock node --model DIR --ros-args -r __ns:=/bravo -p use_sim_time:=true
    """
    ros_args = list(ctx.args)
    _refuse_words_before_ros_args(ros_args)
    from aerodock.deploy.compatibility import model_warnings

    _check_numbers(rate, max_age, duration)
    types = _state_types(state_type or [])
    predictor, cfg, merged = _load_inputs(model, config, sets, trust, mapping)
    aware = getattr(predictor, "needs_wake_scales", False)  # a leader-aware kind
    if aware and config is None and predictor.default_wake_scales is None:
        fail(f"a {predictor.kind} model needs the vehicles' wake scales and its model file "
             "records none: give --config with the leader and follower")
    try:
        import rclpy  # noqa: F401
    except ImportError:
        fail("the ROS 2 node needs rclpy: pip install 'aerodock[ros]'")
    from aerodock.node.ros import NodeSettings, run_node

    _check_ros_names(ros_args, {
        "--output-topic": output_topic, "--diagnostics-topic": diagnostics_topic,
        **{f"--mapping {role}.state": merged[role]["state"] for role in ("leader", "follower")},
        **{f"--state-type {topic}": topic for topic in types}})
    notes = model_warnings(predictor, cfg)
    for note in notes:
        typer.echo(f"warning: {note}", err=True)
    scales = _wake_scales(predictor, cfg, config, aware)
    settings = NodeSettings(
        mapping=merged, rate_hz=rate, publish=publish, max_age_s=max_age, output_topic=output_topic,
        diagnostics_topic=diagnostics_topic,
        output_frame=None if output_frame == OutputFrame.auto else output_frame.value,
        state_types=types,
        wake_scales=None if scales is None else tuple(float(v) for v in scales),
    )
    _announce(predictor.kind, model, settings)
    try:
        outputs = run_node(predictor, settings, duration_s=duration, warnings_to_log=notes,
                           ros_args=ros_args)
    except RuntimeError as err:
        fail(one_line(str(err)))
    typer.echo(f"aerodock node: stopped after {outputs} outputs", err=True)


def _refuse_words_before_ros_args(ros_args: list[str]) -> None:
    """Refuse (a one-line error) a word Click did not know that is not ``--ros-args`` and
    what follows it: an unknown option or a stray argument."""
    if ros_args and ros_args[0] != "--ros-args":
        word = ros_args[0]
        what = "no such option" if word.startswith("-") else "unexpected argument"
        fail(one_line(f"{what}: {word!r} (ROS's own arguments go last, after --ros-args; "
                      "see 'aerodock node --help')"))


def _check_numbers(rate_hz: float, max_age_s: float, duration_s: float | None) -> None:
    """Refuse (a one-line error) a --rate outside (0, 1000] Hz, a --max-age outside (0, 10) s
    or a --duration that is not positive."""
    if not (rate_hz > 0 and rate_hz <= 1000):
        fail(f"--rate must be in (0, 1000] Hz, got {rate_hz}")
    if not (max_age_s > 0 and max_age_s < 10):
        fail(f"--max-age must be in (0, 10) s, got {max_age_s}")
    if duration_s is not None and not duration_s > 0:
        fail(f"--duration must be positive, got {duration_s}")


def _load_inputs(model: Path, config: Path | None, sets: list[str] | None,
                 trust: list[str] | None, mapping: Path | None,
                 ) -> tuple[Any, Config, dict[str, Any]]:
    """The model, the config and the merged topic mapping; one that cannot be read is a
    one-line error (its text only, no type name).

    Returns:
        ``(predictor, cfg, mapping)``.
    """
    from aerodock.config import ConfigError, load_config
    from aerodock.ingest.errors import IngestError
    from aerodock.ingest.rosbag import load_mapping
    from aerodock.learning.modelfile import ModelFileError
    from aerodock.learning.runtime import Predictor

    try:
        predictor = Predictor.load(model)
        cfg = load_config(config, sets or (), trust or ())
        merged, _ = load_mapping(mapping)
    except (ModelFileError, ConfigError, IngestError) as err:
        fail(one_line(str(err)))  # str(): an empty text stays empty, no type name
    return predictor, cfg, merged


def _state_types(items: list[str]) -> dict[str, str]:
    """``--state-type`` TOPIC=TYPE items as topic -> ROS type name (a one-line error for an
    item that is not TOPIC=TYPE with TYPE a known state type)."""
    from aerodock.node.core import STATE_TYPES

    types: dict[str, str] = {}
    for item in items:
        topic, sep, type_name = item.partition("=")
        if not sep or type_name not in STATE_TYPES:
            fail(one_line(f"--state-type {item!r}: expected TOPIC=TYPE with TYPE one of "
                          f"{', '.join(STATE_TYPES)}"))
        types[topic] = type_name
    return types


def _check_ros_names(ros_args: list[str], topics: dict[str, str]) -> None:
    """Refuse (a one-line error) ROS arguments rclpy would refuse, then any topic name it would.

    Args:
        ros_args: ``--ros-args`` and what follows it (empty: none).
        topics: the option that named each topic -> the topic.
    """
    from aerodock.node.ros import ros_args_error, topic_name_error

    why_not = ros_args_error(ros_args) if ros_args else None
    if why_not is not None:
        fail(one_line(f"--ros-args: {why_not}"))
    for option, topic in topics.items():
        why = topic_name_error(topic)
        if why is not None:
            fail(one_line(f"{option} {topic!r}: {why}"))


def _wake_scales(predictor: Any, cfg: Config, config: Path | None,
                 aware: bool) -> Any | None:
    """The wake scales a leader-aware model flies with, said on stderr.

    Only a config the user names says which vehicles fly (the defaults need not be them): with
    ``--config``, its leader's and vehicle's scales; without, None (the model file's training
    scales).

    Args:
        predictor: the loaded model.
        cfg: the loaded config.
        config: the ``--config`` path (None: not given).
        aware: the model is leader-aware (it takes wake scales).

    Returns:
        The configured scales, or None.
    """
    from aerodock.node.core import configured_wake_scales

    scales = None if config is None else configured_wake_scales(predictor, cfg.leader,
                                                                 cfg.vehicle)
    if aware:
        shown = predictor.default_wake_scales if scales is None else scales
        typer.echo(f"aerodock node: wake scales v_hA {shown[0]:.3g} m/s, leader size "
                   f"{shown[1]:.3g} m, v_hB {shown[2]:.3g} m/s, "
                   + (f"follower size {shown[3]:.3g} m, " if len(shown) > 3 else "") + "from "
                   + ("the training flights" if scales is None else str(config)), err=True)
    return scales


def _announce(kind: str, model: Path, settings: NodeSettings) -> None:
    """Say on stderr what the node runs (model, trigger, topics, ROS domain) and its output
    frame (or that it is decided once the follower's state type is found)."""
    from aerodock.node.core import output_frame_choice

    merged, types, publish = settings.mapping, settings.state_types, settings.publish
    typer.echo(f"aerodock node: {kind} model {model}, publish {publish.value} "
               f"({settings.rate_hz:g} Hz "
               f"{'watchdog' if publish == PublishMode.ON_FOLLOWER else 'timer'}), "
               f"{merged['leader']['state']} + {merged['follower']['state']} -> "
               f"{settings.output_topic} "
               f"(ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID', '0')})", err=True)
    frame, rule = output_frame_choice(settings.output_frame, merged["frame"],
                                      types.get(merged["follower"]["state"]))
    typer.echo(f"aerodock node: f_ext in {frame.upper()}: {rule}" if frame else
               "aerodock node: f_ext frame decided when the follower's state type is found on "
               f"the graph (nav_msgs/Odometry: {merged['frame'].upper()}, the mapping's frame; "
               "Freyja, PX4: NED); no f_ext before", err=True)
