"""Identifying the world from flights: the wake's parameters fitted to real logs.

``flights`` reads flight logs into the fit's samples (de-biased labels below the leader, the
free-air noise); ``wake_fit`` fits the dimensionless round jet (mean, turbulence, correlation
time) to them; ``wake_score`` scores a fit against flights and probes the fitted wake;
``wake_folds`` cross-validates the fit flight by flight; ``wake_torque`` reads the wake's torque
on the follower from its motor commands; ``label_noise`` separates the label's own noise, which
grows with the follower's speed, from the wake's turbulence; ``attitude_loop`` reads the
follower's attitude loop (how its commanded torque answers its attitude) from its logs, beside
the SJC law's. It reads flights through
:mod:`aerodock.learning.labels` (the same residual the models learn) and writes nothing but
parameters: ``aerodock field fit`` turns them into a world.
"""
