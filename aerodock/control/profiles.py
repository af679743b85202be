"""Controller profiles: the paper's controller, and ours, as configurations of one controller.

- ``paper``: what the paper flies, as its flight stack (Freyja, ``ros2-devel`` at the time of
  the paper's flights) publishes it: the LQR weights ``Q = diag(1, 1, 8, 0.01, 0.01, 0.1, 1)``,
  ``R = diag(0.8, 0.8, 0.8, 1)`` in every phase (no terminal gain schedule); the controller at
  50 Hz (``controller_rate`` of ``freyja_flight.launch.yaml``); no reference acceleration fed
  forward (``flatness_ff`` off by default in that launch file); its state manager's Kalman
  filter for position and velocity (:mod:`aerodock.control.freyja_state_filter`); its bias
  estimator (:mod:`aerodock.control.freyja_estimator`, propagated at 20 Hz). Used for every
  figure that stands beside the paper's. The paper itself states none of the last four; each
  one's effect is measured (``docs/results/hand-calibrated-wake.md``,
  ``docs/results/hand-calibrated-levers.md``).
- ``tuned``: the configuration as given (by default: stiffer terminal weights scheduled in the
  last ``mission.terminal_s`` before arrival). A separate, named row wherever it is reported.
- ``ours``: ``tuned`` plus fast disturbance rejection from the accelerometer
  (``control.rejection = "accelerometer"``, :mod:`aerodock.control.accel_observer`) on top of
  the slow bias observer and the learnt feed-forward. The wake-torque feed-forward
  (``control.torque_feedforward``) is not part of it by default: it belongs with a model whose
  force labels exclude the tilt the wake's torque causes (``curriculum.label_basis = "thrust"``,
  a ``so2-wrench`` model; ``reproduce``'s targets table has that pairing as its own row). With
  the paper's labels the force model already counts that tilt, and cancelling the torque as
  well costs docking.

The paper's profile never flies the accelerometer observer or the torque feed-forward, whatever
the configuration says: the paper has neither.

Freyja's weights were set for the paper's vehicles (0.27 m motor to motor). On a vehicle of
another size the profile scales them by Bryson's rule with the errors a vehicle of that size
tolerates (:func:`scaled_weights`: lengths in proportion to ``vehicle.diagonal_m``, speeds as
the square root, accelerations unchanged); on the paper's vehicles they are Freyja's exactly.
"""

from __future__ import annotations

from aerodock.config import Config

PAPER_Q_DIAG = (1.0, 1.0, 8.0, 0.01, 0.01, 0.1, 1.0)
PAPER_R_DIAG = (0.8, 0.8, 0.8, 1.0)
PAPER_COMMAND_RATE_HZ = 50.0  # freyja_flight.launch.yaml: controller_rate
PAPER_REFERENCE_FF = 0.0  # freyja_flight.launch.yaml: flatness_ff "false"
PROFILES = ("paper", "tuned", "ours")
PAPER_DIAGONAL_M = 0.27  # the paper's vehicles, motor to motor (DESIGN.md)


def scaled_weights(q_diag: tuple[float, ...] | list[float], diagonal_m: float) -> list[float]:
    """LQR state weights ``[p_n, p_e, p_d, v_n, v_e, v_d, psi]`` set for the paper's vehicle,
    for a vehicle of ``diagonal_m`` (motor to motor, m).

    Bryson's rule (a weight is one over the square of the error tolerated) with the tolerated
    errors in proportion to the vehicle: positions with its size ``L = diagonal_m / 0.27``, speeds
    with ``sqrt(L)`` (Froude: the same gravity, and a hover-induced velocity that scales so), yaw
    and the input weights (accelerations) unchanged. Position weights are divided by ``L^2``,
    velocity weights by ``L``; the closed loop is ``sqrt(1 / L)`` times faster and leaves ``L``
    times smaller errors under the same disturbing acceleration. At ``L = 1``: unchanged.
    """
    scale = float(diagonal_m) / PAPER_DIAGONAL_M
    q = [float(w) for w in q_diag]
    return [q[0] / scale**2, q[1] / scale**2, q[2] / scale**2,
            q[3] / scale, q[4] / scale, q[5] / scale, q[6]]


def controller_config(cfg: Config, profile: str) -> Config:
    """``cfg`` with the follower's and leader's controller set to ``profile`` (see module doc).

    Raises:
        ValueError: unknown profile.
    """
    if profile == "tuned":
        return cfg
    if profile == "ours":
        return cfg.with_overrides({"control": {"rejection": "accelerometer"}},
                                  source=f"{cfg.source} + our controller")
    if profile != "paper":
        raise ValueError(f"controller must be one of {'|'.join(PROFILES)}, got {profile!r}")
    q_diag = scaled_weights(PAPER_Q_DIAG, cfg.vehicle.diagonal_m)
    return cfg.with_overrides({"control": {
        "q_diag": q_diag, "r_diag": list(PAPER_R_DIAG),
        "terminal_q_diag": q_diag, "terminal_r_diag": list(PAPER_R_DIAG),
        "bias_estimator": "freyja", "state_filter": "freyja",
        "command_rate_hz": PAPER_COMMAND_RATE_HZ, "reference_ff_factor": PAPER_REFERENCE_FF,
        "rejection": "bias-observer", "torque_feedforward": False,
    }}, source=f"{cfg.source} + paper's controller")
