"""Helpers for the log-reader tests: the shared real data, and inputs built with real writers.

Synthetic inputs share one known flight (:func:`synthetic_flight`): a follower on a smooth
trajectory with a known constant disturbance ``f``, so every reader must give ``a_obs - cmd = f``.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.geometry import E3, euler_to_rotmat, rotmat_to_quat
from aerodock.ingest.data_dir import find_data_dir

SHARED = Path(__file__).resolve().parents[2].parent / "shared"
# The data location: AERODOCK_DATA_DIR, else ../shared/data beside the clone.
DATA_DIR = find_data_dir(cwd=Path(__file__).resolve().parents[2]).path or SHARED / "data"
NEURAL_SWARM_DIR = DATA_DIR / "neural-swarm" / "swap_ss"
ULOG_SAMPLE = DATA_DIR / "px4-ulog" / "sample_log_small.ulg"
G = 9.81
MASS_KG = 0.7
DISTURBANCE = np.array([0.1, -0.2, 0.5])

NS_HEADER = (
    "# time[ms],x[m],y[m],z[m],vx[m/s],vy[m/s],vz[m/s],ax[m/s^2],ay[m/s^2],az[m/s^2],qx,qy,qz,qw,"
    "u1[N],u2[N],u3[N],u4[N],u1[PWM],u2[PWM],u3[PWM],u4[PWM],Vbat[V],thrust_des[g],torquex[Nm],"
    "torquey[Nm],torquez[Nm],wx[rad/s],wy[rad/s],wz[rad/s]"
)


# --------------------------------------------------------------------------------------------
# A known synthetic flight, NED / FRD
# --------------------------------------------------------------------------------------------


def synthetic_flight(t: np.ndarray, mass_kg: float = MASS_KG) -> dict[str, np.ndarray]:
    """Follower on a smooth loop 0.6 m below a hovering leader; disturbance ``DISTURBANCE``.

    Returns NED arrays: ``p, v, a`` (kinematic), ``u`` (commanded, ``a - f``), ``R`` (attitude
    realising ``u``, Freyja convention: roll/pitch relative to a slowly turning heading),
    ``roll, pitch, yaw``, ``thrust_n`` and the leader's ``leader_p``.
    """
    w = 1.0
    p = np.stack([0.5 * np.sin(w * t), 0.5 * np.cos(w * t) - 0.5,
                  -1.4 + 0.1 * np.sin(2 * w * t)], axis=1)
    v = np.stack([0.5 * w * np.cos(w * t), -0.5 * w * np.sin(w * t),
                  0.2 * w * np.cos(2 * w * t)], axis=1)
    a = np.stack([-0.5 * w**2 * np.sin(w * t), -0.5 * w**2 * np.cos(w * t),
                  -0.4 * w**2 * np.sin(2 * w * t)], axis=1)
    u = a - DISTURBANCE
    yaw = 0.3 * t
    total = u - G * E3  # what thrust must provide: -R e3 T / m
    thrust = mass_kg * np.linalg.norm(total, axis=1)
    c, s = np.cos(yaw), np.sin(yaw)
    # Z = Rz(yaw)^T R e3, with R e3 = -total / |total| (Freyja's inversion map).
    body_z = -total / np.linalg.norm(total, axis=1, keepdims=True)
    zx = c * body_z[:, 0] + s * body_z[:, 1]
    zy = -s * body_z[:, 0] + c * body_z[:, 1]
    roll = np.arcsin(-zy)
    pitch = np.arctan2(zx, body_z[:, 2])
    rot = euler_to_rotmat(roll, pitch, yaw)
    n = len(t)
    return {
        "t": t, "p": p, "v": v, "a": a, "u": u, "R": rot, "quat": rotmat_to_quat(rot),
        "roll": roll, "pitch": pitch, "yaw": yaw, "thrust_n": thrust,
        "leader_p": np.tile([0.0, 0.0, -2.0], (n, 1)), "leader_v": np.zeros((n, 3)),
        "leader_R": np.tile(np.eye(3), (n, 1, 1)),
    }


# --------------------------------------------------------------------------------------------
# Neural-Swarm-format files
# --------------------------------------------------------------------------------------------


def write_ns_file(path: Path, *, t_us: np.ndarray, pos_zup: np.ndarray | None = None,
                  quat_xyzw: np.ndarray | None = None, accel_zup: np.ndarray | None = None,
                  thrust_n: np.ndarray | None = None, mass_kg: float = 0.032,
                  torque_flu: np.ndarray | None = None, pwm: np.ndarray | None = None,
                  header: str = NS_HEADER) -> Path:
    """Write a Neural-Swarm-format file; defaults: level hover at (0, 0, 0.5) m z-up, no
    torque, every motor at 0.6 PWM."""
    n = len(t_us)
    pos = np.tile([0.0, 0.0, 0.5], (n, 1)) if pos_zup is None else pos_zup
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)) if quat_xyzw is None else quat_xyzw
    thrust = np.full(n, mass_kg * G) if thrust_n is None else thrust_n
    if accel_zup is None:  # consistent physics, no disturbance: a_meas = R e3 T / m
        from aerodock.geometry import quat_to_rotmat
        accel_zup = quat_to_rotmat(quat[:, [3, 0, 1, 2]])[:, :, 2] * (thrust / mass_kg)[:, None]
    vel = np.zeros((n, 3))
    rows = np.column_stack([
        t_us, pos, vel, accel_zup, quat, np.tile(thrust[:, None] / 4, (1, 4)),
        np.full((n, 4), 0.6) if pwm is None else pwm, np.full(n, 3.7), thrust / G * 1000,
        np.zeros((n, 3)) if torque_flu is None else torque_flu, np.zeros((n, 3)),
    ])
    lines = [header] + [",".join(f"{x:.17g}" for x in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


# --------------------------------------------------------------------------------------------
# ULog files, built to the ULog specification (docs.px4.io, "ULog File Format")
# --------------------------------------------------------------------------------------------


def _msg(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_ulog(path: Path, topics: dict[str, dict[str, np.ndarray]],
               params: dict[str, float] | None = None, start_us: int = 0) -> Path:
    """Write a minimal ULog v1 file: header, flag bits, info, parameters, formats, data.

    Args:
        path: Output file.
        topics: Topic name -> field name -> values; ``timestamp`` (µs, uint64) is required,
            other fields are float32; a 2-D field ``(T, k)`` becomes ``float[k] name``.
        params: Float parameters (``MPC_THR_HOVER`` ...).
        start_us: The header's start time stamp.
    """
    out = bytearray(b"ULog\x01\x12\x35" + bytes([1]) + struct.pack("<Q", start_us))
    out += _msg(b"B", bytes(16) + struct.pack("<3Q", 0, 0, 0))
    key = b"char[3] sys_name"
    out += _msg(b"I", bytes([len(key)]) + key + b"PX4")
    for name, value in (params or {}).items():
        pkey = f"float {name}".encode()
        out += _msg(b"P", bytes([len(pkey)]) + pkey + struct.pack("<f", value))
    layouts = {}
    for msg_id, (topic, fields) in enumerate(topics.items()):
        parts, layout = ["uint64_t timestamp"], []
        for name, values in fields.items():
            if name == "timestamp":
                continue
            arr = np.asarray(values, dtype=np.float32)
            width = 1 if arr.ndim == 1 else arr.shape[1]
            parts.append(f"float {name}" if arr.ndim == 1 else f"float[{width}] {name}")
            layout.append(arr.reshape(len(arr), -1))
        out += _msg(b"F", f"{topic}:{';'.join(parts)};".encode())
        layouts[topic] = (msg_id, np.asarray(fields["timestamp"], dtype=np.uint64),
                          np.hstack(layout) if layout else np.zeros((len(fields["timestamp"]),
                                                                     0), np.float32))
    for topic, (msg_id, _, _) in layouts.items():
        out += _msg(b"A", struct.pack("<BH", 0, msg_id) + topic.encode())
    # Interleave topics sample by sample, keeping each topic's own order (as PX4's logger does).
    longest = max(len(stamps) for _, stamps, _ in layouts.values())
    for i in range(longest):
        for msg_id, stamps, values in layouts.values():
            if i < len(stamps):
                payload = struct.pack("<HQ", msg_id, int(stamps[i])) + values[i].astype(
                    "<f4").tobytes()
                out += _msg(b"D", payload)
    path.write_bytes(bytes(out))
    return path


def ulog_topics(t_s: np.ndarray, fl: dict[str, np.ndarray], *, hover: float = 0.5,
                role: str = "follower") -> dict[str, dict[str, np.ndarray]]:
    """PX4 topics of one vehicle of :func:`synthetic_flight` (the follower, or the leader)."""
    stamps = np.round(t_s * 1e6).astype(np.uint64)
    n = len(t_s)
    if role == "follower":
        p, v, rot, a, u = fl["p"], fl["v"], fl["R"], fl["a"], fl["u"]
    else:
        p, v, rot = fl["leader_p"], fl["leader_v"], fl["leader_R"]
        a, u = np.zeros((n, 3)), np.zeros((n, 3))
    quat = rotmat_to_quat(rot)
    thrust_norm = np.linalg.norm(G * E3 - u, axis=1) * hover / G
    force_body = np.einsum("tji,tj->ti", rot, a - G * E3)  # R^T (a - g e3)
    return {
        "vehicle_local_position": {
            "timestamp": stamps, "x": p[:, 0], "y": p[:, 1], "z": p[:, 2], "vx": v[:, 0],
            "vy": v[:, 1], "vz": v[:, 2], "ax": a[:, 0], "ay": a[:, 1], "az": a[:, 2],
        },
        "vehicle_attitude": {"timestamp": stamps, "q": quat},
        "vehicle_thrust_setpoint": {
            "timestamp": stamps, "xyz": np.column_stack([np.zeros((n, 2)), -thrust_norm]),
        },
        "vehicle_acceleration": {"timestamp": stamps, "xyz": force_body},
    }


# --------------------------------------------------------------------------------------------
# ROS 2 bags, written with rosbags' Writer
# --------------------------------------------------------------------------------------------


class RosMessages:
    """Builders of the ROS 2 messages the tests write (standard types and Freyja's)."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        from aerodock.ingest.rosbag import FREYJA_MSGS, PX4_MSGS

        self.store = get_typestore(Stores.ROS2_HUMBLE)
        for name, text in {**FREYJA_MSGS, **PX4_MSGS}.items():
            self.store.register(get_types_from_msg(text, name))
        self.types = self.store.types

    def make(self, msgtype: str, **values: Any) -> Any:
        """A message of a flat type (base fields and fixed arrays), unset fields zero."""
        for name, (node, spec) in self.store.fielddefs[msgtype][1]:
            if name in values:
                continue
            if node == 1:  # base type
                values[name] = False if spec[0] == "bool" else 0.0 if "float" in spec[0] else 0
            elif node == 3:  # fixed array
                values[name] = np.zeros(spec[1], dtype=spec[0][1][0])
        for name, (node, spec) in self.store.fielddefs[msgtype][1]:
            if node == 3:
                values[name] = np.asarray(values[name], dtype=spec[0][1][0])
            elif node == 1 and "float" in spec[0]:
                values[name] = float(values[name])
            elif node == 1 and spec[0] != "bool":
                values[name] = int(values[name])
        return self._t(msgtype)(**values)

    def _t(self, name: str) -> Any:
        return self.types[name]

    def header(self, stamp_ns: int, frame: str = "map") -> Any:
        time = self._t("builtin_interfaces/msg/Time")(sec=int(stamp_ns // 10**9),
                                                      nanosec=int(stamp_ns % 10**9))
        return self._t("std_msgs/msg/Header")(stamp=time, frame_id=frame)

    def vector3(self, v: np.ndarray) -> Any:
        return self._t("geometry_msgs/msg/Vector3")(x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def point(self, v: np.ndarray) -> Any:
        return self._t("geometry_msgs/msg/Point")(x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quaternion(self, q_wxyz: np.ndarray) -> Any:
        return self._t("geometry_msgs/msg/Quaternion")(
            x=float(q_wxyz[1]), y=float(q_wxyz[2]), z=float(q_wxyz[3]), w=float(q_wxyz[0]))

    def current_state(self, stamp_ns: int, p: np.ndarray, v: np.ndarray,
                      rpy: np.ndarray) -> Any:
        vector = np.concatenate([p, v, rpy, np.zeros(4)])
        return self._t("freyja_msgs/msg/CurrentState")(
            header=self.header(stamp_ns), state_vector=vector, state_valid=1)

    def controller_debug(self, stamp_ns: int, u: np.ndarray) -> Any:
        lqr_u = np.array([u[0], u[1], u[2] - G, 0.0], dtype=np.float32)
        return self._t("freyja_msgs/msg/ControllerDebug")(
            header=self.header(stamp_ns), lqr_u=lqr_u, biasv=np.zeros(4, np.float32),
            errv=np.zeros(7, np.float32), flags=1)

    def ctrl_command(self, roll: float, pitch: float, thrust: float) -> Any:
        return self._t("freyja_msgs/msg/CtrlCommand")(
            roll=float(roll), pitch=float(pitch), yaw=0.0, thrust=float(thrust), ctrl_mode=15)

    def reference_state(self, stamp_ns: int, p: np.ndarray, v: np.ndarray, yaw: float,
                        a: np.ndarray) -> Any:
        return self._t("freyja_msgs/msg/ReferenceState")(
            header=self.header(stamp_ns), pn=p[0], pe=p[1], pd=p[2], vn=v[0], ve=v[1], vd=v[2],
            yaw=float(yaw), an=a[0], ae=a[1], ad=a[2])

    def odometry(self, stamp_ns: int, p: np.ndarray, q_wxyz: np.ndarray,
                 v_body: np.ndarray) -> Any:
        pose = self._t("geometry_msgs/msg/Pose")(position=self.point(p),
                                                 orientation=self.quaternion(q_wxyz))
        twist = self._t("geometry_msgs/msg/Twist")(linear=self.vector3(v_body),
                                                   angular=self.vector3(np.zeros(3)))
        return self._t("nav_msgs/msg/Odometry")(
            header=self.header(stamp_ns), child_frame_id="base_link",
            pose=self._t("geometry_msgs/msg/PoseWithCovariance")(pose=pose,
                                                                 covariance=np.zeros(36)),
            twist=self._t("geometry_msgs/msg/TwistWithCovariance")(twist=twist,
                                                                   covariance=np.zeros(36)))

    def pose_stamped(self, stamp_ns: int, p: np.ndarray, q_wxyz: np.ndarray) -> Any:
        pose = self._t("geometry_msgs/msg/Pose")(position=self.point(p),
                                                 orientation=self.quaternion(q_wxyz))
        return self._t("geometry_msgs/msg/PoseStamped")(header=self.header(stamp_ns), pose=pose)

    def twist_stamped(self, stamp_ns: int, v: np.ndarray) -> Any:
        twist = self._t("geometry_msgs/msg/Twist")(linear=self.vector3(v),
                                                   angular=self.vector3(np.zeros(3)))
        return self._t("geometry_msgs/msg/TwistStamped")(header=self.header(stamp_ns),
                                                         twist=twist)

    def vector3_stamped(self, stamp_ns: int, v: np.ndarray) -> Any:
        return self._t("geometry_msgs/msg/Vector3Stamped")(header=self.header(stamp_ns),
                                                           vector=self.vector3(v))

    def imu(self, stamp_ns: int, q_wxyz: np.ndarray, force: np.ndarray) -> Any:
        return self._t("sensor_msgs/msg/Imu")(
            header=self.header(stamp_ns, "base_link"), orientation=self.quaternion(q_wxyz),
            orientation_covariance=np.zeros(9), angular_velocity=self.vector3(np.zeros(3)),
            angular_velocity_covariance=np.zeros(9), linear_acceleration=self.vector3(force),
            linear_acceleration_covariance=np.zeros(9))


BagTopics = dict[str, tuple[str, list[tuple[int, Any]]]]


def write_bag(path: Path, topics: BagTopics, storage: str = "mcap",
              ros: RosMessages | None = None) -> Path:
    """Write a rosbag2 folder: topic -> (message type, [(bag time ns, message), ...])."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    ros = ros or RosMessages()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=ros.store)
                       for topic, (msgtype, _) in topics.items()}
        records = [(ns, topic, msg) for topic, (_, msgs) in topics.items() for ns, msg in msgs]
        for ns, topic, msg in sorted(records, key=lambda r: (r[0], r[1])):
            writer.write(connections[topic], ns,
                         ros.store.serialize_cdr(msg, topics[topic][0]))
    return path


BAG_T0_NS = 1_700_000_000 * 10**9


def freyja_topics(ros: RosMessages, n: int = 400, *, with_rpyt: bool = False,
                  leader_n: int | None = None) -> BagTopics:
    """A Freyja-like bag of :func:`synthetic_flight` (NED): the default mapping's topics."""
    t = np.arange(n) * 0.01
    fl = synthetic_flight(t)
    ns = [BAG_T0_NS + int(round(x * 1e9)) for x in t]
    rpy = np.column_stack([fl["roll"], fl["pitch"], fl["yaw"]])
    nl = n if leader_n is None else leader_n
    topics: BagTopics = {
        "/alpha/current_state": ("freyja_msgs/msg/CurrentState", [
            (ns[i], ros.current_state(ns[i], fl["leader_p"][i], fl["leader_v"][i], np.zeros(3)))
            for i in range(nl)]),
        "/bravo/current_state": ("freyja_msgs/msg/CurrentState", [
            (ns[i], ros.current_state(ns[i], fl["p"][i], fl["v"][i], rpy[i])) for i in range(n)]),
        "/bravo/controller_debug": ("freyja_msgs/msg/ControllerDebug", [
            (ns[i], ros.controller_debug(ns[i], fl["u"][i])) for i in range(n)]),
        "/bravo/reference_state": ("freyja_msgs/msg/ReferenceState", [
            (ns[i], ros.reference_state(ns[i], fl["p"][i], fl["v"][i], fl["yaw"][i],
                                        fl["a"][i])) for i in range(n)]),
    }
    if with_rpyt:
        topics["/bravo/rpyt_command"] = ("freyja_msgs/msg/CtrlCommand", [
            (ns[i], ros.ctrl_command(fl["roll"][i], fl["pitch"][i], fl["thrust_n"][i]))
            for i in range(n)])
    return topics


def px4_topics(ros: RosMessages, n: int = 400, *, hover: float = 0.5,
               follower_velocity_frame: int = 1) -> BagTopics:
    """A PX4 (uXRCE-DDS) bag of :func:`synthetic_flight`: px4_msgs, NED, no headers.

    The follower's VehicleOdometry gives its velocity in NED (``velocity_frame`` 1) or in the
    body (3); its VehicleThrustSetpoint realises ``u`` through ``hover``; its
    VehicleLocalPosition carries the kinematic acceleration.
    """
    t = np.arange(n) * 0.01
    fl = synthetic_flight(t)
    ns = [BAG_T0_NS + int(round(x * 1e9)) for x in t]
    boot_us = [int(5e6 + x * 1e6) for x in t]
    thrust = np.linalg.norm(G * E3 - fl["u"], axis=1) * hover / G
    v_f = fl["v"] if follower_velocity_frame == 1 else np.einsum("tji,tj->ti", fl["R"], fl["v"])

    def odom(i: int, p: np.ndarray, q: np.ndarray, v: np.ndarray, frame: int) -> Any:
        return ros.make("px4_msgs/msg/VehicleOdometry", timestamp=boot_us[i],
                        timestamp_sample=boot_us[i], pose_frame=1, position=p, q=q,
                        velocity_frame=frame, velocity=v)

    return {
        "/alpha/fmu/out/vehicle_odometry": ("px4_msgs/msg/VehicleOdometry", [
            (ns[i], odom(i, fl["leader_p"][i], np.array([1.0, 0, 0, 0]), fl["leader_v"][i], 1))
            for i in range(n)]),
        "/bravo/fmu/out/vehicle_odometry": ("px4_msgs/msg/VehicleOdometry", [
            (ns[i], odom(i, fl["p"][i], fl["quat"][i], v_f[i], follower_velocity_frame))
            for i in range(n)]),
        "/bravo/fmu/out/vehicle_thrust_setpoint": ("px4_msgs/msg/VehicleThrustSetpoint", [
            (ns[i], ros.make("px4_msgs/msg/VehicleThrustSetpoint", timestamp=boot_us[i],
                             xyz=[0.0, 0.0, -thrust[i]])) for i in range(n)]),
        "/bravo/fmu/out/vehicle_local_position": ("px4_msgs/msg/VehicleLocalPosition", [
            (ns[i], ros.make("px4_msgs/msg/VehicleLocalPosition", timestamp=boot_us[i],
                             x=fl["p"][i, 0], y=fl["p"][i, 1], z=fl["p"][i, 2],
                             vx=fl["v"][i, 0], vy=fl["v"][i, 1], vz=fl["v"][i, 2],
                             ax=fl["a"][i, 0], ay=fl["a"][i, 1], az=fl["a"][i, 2]))
            for i in range(n)]),
    }


PX4_MAPPING = {
    "frame": "ned",
    "leader": {"state": "/alpha/fmu/out/vehicle_odometry"},
    "follower": {"state": "/bravo/fmu/out/vehicle_odometry",
                 "command": "/bravo/fmu/out/vehicle_thrust_setpoint",
                 "imu": "/bravo/fmu/out/vehicle_local_position", "hover_thrust": 0.5,
                 "mass_kg": MASS_KG},
}
