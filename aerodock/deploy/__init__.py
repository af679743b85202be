"""From a trained model to what a flight computer runs: the ONNX export
(:mod:`aerodock.deploy.export`) and the warnings for flying a model on vehicles or with a
controller it was not trained for (:mod:`aerodock.deploy.compatibility`).

The NumPy runtime the mission and the ROS node load is :mod:`aerodock.learning.runtime`.
"""
