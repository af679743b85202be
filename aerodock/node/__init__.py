"""The ROS 2 node that runs a trained downwash model next to a flight stack (``aerodock node``).

Layout:

- :mod:`aerodock.node.core`: everything that does not need ROS: turning the fields of the
  supported state messages into NED states, the staleness rule, one prediction step and the
  output frame. Pure functions, unit-tested without ``rclpy``.
- :mod:`aerodock.node.ros`: the ``rclpy`` node (subscriptions, timer, publishers). Needs the
  ``aerodock[ros]`` extra.
- :mod:`aerodock.node.command`: the ``aerodock node`` command.
- :mod:`aerodock.node.bench`: latency of the predictor and of the node at its rate.
"""
