"""ROS 2 launch file: ``aerodock node`` beside a flight stack whose states are Odometry.

    ros2 launch examples/launch/aerodock_node.launch.py model:=models/so2
    ros2 launch examples/launch/aerodock_node.launch.py model:=models/so2 namespace:=bravo \
        mapping:=my_mapping.toml use_sim_time:=true

It needs ros2launch (the ``launch`` package of a ROS 2 install; the ``aerodock[ros]`` extra does
not bring it) and the ``aerodock`` command on ``PATH`` (``pip install 'aerodock[ros]'``). The
command is a Python console script, not a ROS package's executable, so it is started with
``ExecuteProcess``; ROS's own arguments (the namespace, ``use_sim_time``) go last, after
``--ros-args``, as for any ROS 2 node. The node publishes ``f_ext`` and ``diagnostics`` in its
namespace (``/bravo/f_ext``), in ENU for Odometry input (REP 103; the diagnostics'
``output_frame`` says so): docs/deploy.md.
"""

import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.substitutions import LaunchConfiguration

HERE = os.path.dirname(os.path.abspath(__file__))


def generate_launch_description() -> LaunchDescription:
    """The node's launch arguments and the ``aerodock node`` process."""
    return LaunchDescription([
        DeclareLaunchArgument("model", description="trained model folder (aerodock train)"),
        DeclareLaunchArgument("mapping", default_value=os.path.join(HERE, "odometry_mapping.toml"),
                              description="topic mapping TOML (the leader's and follower's "
                                          "state topics)"),
        DeclareLaunchArgument("namespace", default_value="bravo",
                              description="the node's namespace (f_ext and diagnostics in it)"),
        DeclareLaunchArgument("use_sim_time", default_value="false",
                              description="stamp f_ext with /clock (a bag played with --clock)"),
        ExecuteProcess(
            cmd=["aerodock", "node",
                 "--model", LaunchConfiguration("model"),
                 "--mapping", LaunchConfiguration("mapping"),
                 "--output-topic", "f_ext",
                 "--diagnostics-topic", "diagnostics",
                 "--ros-args",
                 "-r", ["__ns:=/", LaunchConfiguration("namespace")],
                 "-p", ["use_sim_time:=", LaunchConfiguration("use_sim_time")]],
            name="aerodock_node", output="screen"),
    ])
