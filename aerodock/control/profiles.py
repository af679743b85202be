"""Controller profiles: the paper's controller, and ours, as configurations of one controller.

- ``paper``: what the paper flies, as its flight stack (Freyja, ``ros2-devel`` at the time of
  the paper's flights) publishes it: the LQR weights ``Q = diag(1, 1, 8, 0.01, 0.01, 0.1, 1)``,
  ``R = diag(0.8, 0.8, 0.8, 1)`` in every phase (no terminal gain schedule); the controller at
  50 Hz (``controller_rate`` of ``freyja_flight.launch.yaml``); no reference acceleration fed
  forward (``flatness_ff`` off by default in that launch file); its state manager's Kalman
  filter for position and velocity (:mod:`aerodock.control.freyja_state_filter`); its bias
  estimator (:mod:`aerodock.control.freyja_estimator`, propagated at 20 Hz). Used for every
  figure that stands beside the paper's. The paper itself states none of the last four; each
  one's effect is measured (``docs/results.md``).
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
"""

from __future__ import annotations

from aerodock.config import Config

PAPER_Q_DIAG = (1.0, 1.0, 8.0, 0.01, 0.01, 0.1, 1.0)
PAPER_R_DIAG = (0.8, 0.8, 0.8, 1.0)
PAPER_COMMAND_RATE_HZ = 50.0  # freyja_flight.launch.yaml: controller_rate
PAPER_REFERENCE_FF = 0.0  # freyja_flight.launch.yaml: flatness_ff "false"
PROFILES = ("paper", "tuned", "ours")


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
    return cfg.with_overrides({"control": {
        "q_diag": list(PAPER_Q_DIAG), "r_diag": list(PAPER_R_DIAG),
        "terminal_q_diag": list(PAPER_Q_DIAG), "terminal_r_diag": list(PAPER_R_DIAG),
        "bias_estimator": "freyja", "state_filter": "freyja",
        "command_rate_hz": PAPER_COMMAND_RATE_HZ, "reference_ff_factor": PAPER_REFERENCE_FF,
        "rejection": "bias-observer", "torque_feedforward": False,
    }}, source=f"{cfg.source} + paper's controller")
