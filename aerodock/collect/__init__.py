"""Collecting training data in the simulated world: the paper's curriculum of flights
(:mod:`aerodock.collect.curriculum`).

It flies the mission's world and controllers and trains a model between stages, so it sits
above :mod:`aerodock.learning` (the model pipeline, which flies nothing) and
:mod:`aerodock.mission`.
"""
