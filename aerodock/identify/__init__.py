"""Identifying the world from flights: the wake's parameters fitted to real logs.

``wake_fit`` fits the dimensionless round jet (mean, turbulence, correlation time) to the
follower's residual accelerations below a leader; ``wake_score`` scores a fit against flights
and probes the fitted wake; ``wake_folds`` cross-validates the fit flight by flight;
``wake_torque`` reads the wake's torque on the follower from its motor commands; ``label_noise``
separates the label's own noise, which grows with the follower's speed, from the wake's
turbulence. It reads flights through :mod:`aerodock.learning.labels` (the same residual the
models learn) and writes nothing but parameters: ``aerodock field fit`` turns them into a world.
"""
