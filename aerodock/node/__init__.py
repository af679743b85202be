"""The ROS 2 node that runs a trained downwash model next to a flight stack (``aerodock node``).

Layout:

- :mod:`aerodock.node.core`: everything that does not need ROS: turning the fields of the
  supported state messages into NED states (attitudes that are no rotation refused), the
  staleness rule, one prediction step and the output frame. Pure functions, unit-tested
  without ``rclpy``.
- :mod:`aerodock.node.refusals`: the bounded account of refused messages (also ROS-free).
- :mod:`aerodock.node.ros`: the ``rclpy`` node (subscriptions, timer, publishers). Needs the
  ``aerodock[ros]`` extra.
- :mod:`aerodock.node.replay`: a flight replayed as state messages, what the node publishes
  recorded (the end-to-end test, the latency benchmark).

The ``aerodock node`` command is in :mod:`aerodock.cli.node`; the latency of the predictor and of
the node at its rate is measured by :mod:`aerodock.bench.node`.
"""
