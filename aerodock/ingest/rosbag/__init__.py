"""Reader for ROS 2 bags (``.db3`` and ``.mcap``, or a bag folder) through ``rosbags``.

One bag holds one flight of both vehicles. A topic mapping (:mod:`.mapping`: a TOML file or a
dict) says which topic carries what; :mod:`.messages` knows the message types (standard ROS,
Freyja's and PX4's) and what their numbers mean; :mod:`.reader` reads a bag into a FlightLog
(:func:`read_rosbag`).
"""

from aerodock.ingest.rosbag.mapping import (
    DEFAULT_MAPPING,
    RoleTopics,
    TopicMapping,
    load_mapping,
)
from aerodock.ingest.rosbag.messages import (
    ACCEL_COMMAND_TYPES,
    ATTITUDE_THRUST_TYPES,
    EXTRACT,
    FREYJA_MSGS,
    IMU_TYPES,
    PX4_LOCAL_POSITION,
    PX4_MSGS,
    PX4_ODOMETRY,
    PX4_THRUST,
    STATE_TYPES,
    THRUST_SETPOINT_TYPES,
    Stream,
)
from aerodock.ingest.rosbag.reader import DEFAULT_MASS_KG, SOURCE, read_rosbag

__all__ = [
    "ACCEL_COMMAND_TYPES", "ATTITUDE_THRUST_TYPES", "DEFAULT_MAPPING", "DEFAULT_MASS_KG",
    "EXTRACT", "FREYJA_MSGS", "IMU_TYPES", "PX4_LOCAL_POSITION", "PX4_MSGS", "PX4_ODOMETRY",
    "PX4_THRUST", "SOURCE", "STATE_TYPES", "THRUST_SETPOINT_TYPES", "RoleTopics", "Stream",
    "TopicMapping", "load_mapping", "read_rosbag",
]
