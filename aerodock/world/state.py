"""The world's batch state (what a physics step reads and writes) and one step's frame.

Both vehicles are one batch of 2n rows, leaders first: every vehicle operation is row-wise, so the
numbers are those of two separate calls at half the per-call overhead. ``leader`` and ``follower``
are views of that batch's halves, split off when first asked for; replacing either rebuilds the
batch from the two halves. States are never modified in place by the step: it makes new arrays,
so a reference kept by a log or the motion-capture buffer keeps its values (the compiled control
period, :mod:`aerodock.world.period`, writes each step's outputs into that step's own rows of
arrays it makes for the period, and hands the last rows on as the state). The one exception is
the IMU chain's own memory (its filters' states, delay lines and the navigation's ring,
:class:`~aerodock.world.imu.ImuState`), which the step advances in place: nothing outside the
chain holds it, copies of a state (``take_rows``) copy it, and what the chain hands out (rates,
specific force, attitude estimate) is a new array every step.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from aerodock.downwash import BodyState, DownwashField
from aerodock.frozen import freeze, is_frozen
from aerodock.rng import TrialRNG
from aerodock.rows import pair_rows, take_rows
from aerodock.world.gripper import _CAPTURED, GripperState, gripper_idle
from aerodock.world.imu import ImuState
from aerodock.world.platform import BarState
from aerodock.world.torque_sensing import TorqueLog, TorqueReading
from aerodock.world.vehicles.fleet import Fleet, concat_states, split_state, state_rows


@dataclass(frozen=True)
class BatchConstants:
    """Arrays of the hot loop that depend only on the batch size (never modified in place)."""

    bar_mass_kg: np.ndarray  # (n,)
    no_close: np.ndarray  # (n,) bool, all False: no active trigger command
    gravity_mps2: np.ndarray  # (3,) g e3
    rotor_offsets_m: np.ndarray  # (k, 3) the follower's rotor disks, body FRD ((1, 3) zeros for
    # a point mass, which takes the field's whole force from ``acceleration``)
    hover_thrust_n: np.ndarray  # (2n,) each vehicle type's nominal hover thrust, leaders first

    def take_rows(self, rows: np.ndarray) -> BatchConstants:
        """The constants of the trials at ``rows``."""
        n = self.bar_mass_kg.shape[0]
        return BatchConstants(self.bar_mass_kg[rows], self.no_close[rows], self.gravity_mps2,
                              self.rotor_offsets_m, self.hover_thrust_n[pair_rows(rows, n)])


@dataclass
class AccelWindow:
    """The follower's accelerometer: it averages over the time since it was last read."""

    v_mps: np.ndarray  # (n, 3) velocity at the last read
    t_s: float
    step_index: int
    reading: np.ndarray | None = None  # the last reading (a second read of one step returns it)


@dataclass
class WorldState:
    """N trials' world: vehicles, bar, cables, gripper, clock, and what the sensors keep.

    Attributes:
        n: number of trials.
        fleet: the vehicle model (to split and join the 2n batch).
        rng: the world's only source of randomness.
        field: the downwash field (it keeps its own turbulence state).
        leader_fixed: the leader is held on a rigid stand at hover thrust.
        bar: the hanging bars.
        cable_force_n: (n, 3) the cables' pull on the leader, from the last step.
        gripper: the followers' grippers.
        t_s, step_index: the clock (``t_s = step_index * dt_s``).
        leader_accel, follower_accel: (n, 3) last step's accelerations.
        last_downwash_mps2: (n, 3) last step's wake force on the follower per unit mass.
        contact_seen: (n,) any bar contact since the recorder last cleared it (the truth).
        contact_sensed: (n,) the strain gauge read above the contact threshold at a sample since
            then (what the follower knows).
        ground_contact: (n,) a vehicle reached the ground (z = 0) at some step.
        rotor_loss: (n, 4) injected thrust loss of the follower's rotors (None: healthy).
        accel_bias_body_mps2: (n, 3) the accelerometer's residual bias, body frame.
        history: ring buffer of the last ``latency_steps + 1`` true states (motion capture).
        accel_window: the accelerometer's averaging window.
        torque_log: kept once someone reads the torques (None until then).
        imu: the flight computers' IMU chains and attitude estimates (``imu.chain = "filtered"``;
            None: the ideal chain).
    """

    n: int
    fleet: Fleet
    rng: np.random.Generator | TrialRNG
    field: DownwashField
    leader_fixed: bool
    constants: BatchConstants
    bar: BarState
    cable_force_n: np.ndarray
    gripper: GripperState
    accel_bias_body_mps2: np.ndarray
    accel_window: AccelWindow
    history: list[tuple[np.ndarray, ...]] = field(default_factory=list)
    t_s: float = 0.0
    step_index: int = 0
    leader_accel: np.ndarray | None = None
    follower_accel: np.ndarray | None = None
    last_downwash_mps2: np.ndarray | None = None
    contact_seen: np.ndarray | None = None
    contact_sensed: np.ndarray | None = None
    ground_contact: np.ndarray | None = None
    rotor_loss: np.ndarray | None = None
    torque_log: TorqueLog | None = None
    imu: ImuState | None = None
    torque_reading: TorqueReading | None = None
    steps_at_last_torque: int = 0
    # The 2n batch and its halves (see the module docstring).
    _both: Any = None
    _lead: Any = None
    _fol: Any = None

    @property
    def both(self) -> Any:
        """Leaders and followers as one batch of 2n vehicles (rebuilt if either was replaced)."""
        if self._both is None:
            self._both = concat_states(self.fleet, self._lead, self._fol)
        return self._both

    @both.setter
    def both(self, value: Any) -> None:
        self._both, self._lead, self._fol = value, None, None

    @property
    def leader(self) -> Any:
        """The leaders (n trials): a view of the batch's first half."""
        if self._lead is None:
            self._split()
        return self._lead

    @leader.setter
    def leader(self, value: Any) -> None:
        if self._lead is None:
            self._split()
        self._lead, self._both = value, None

    @property
    def follower(self) -> Any:
        """The followers (n trials): a view of the batch's second half."""
        if self._fol is None:
            self._split()
        return self._fol

    @follower.setter
    def follower(self, value: Any) -> None:
        if self._fol is None:
            self._split()
        self._fol, self._both = value, None

    def body_halves(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The vehicles' true masses: the leaders' (n,), the followers' (n,) and the followers'
        rows (n, 3), the same arrays every step for the same body (the field's caches key on
        them)."""
        body = self.both.body
        cached = self.__dict__.get("_body_halves")  # not a field: not state, a view of it
        if cached is None or cached[0] is not body:
            n, mass = self.n, body.mass_kg
            cached = self.__dict__["_body_halves"] = (body, mass[:n], mass[n:],
                                                      body.mass_rows_kg[n:])
        return cached[1:]

    def gripper_flags(self) -> tuple[np.ndarray, bool, bool]:
        """The gripper's (captured (n,) bool, read-only; any captured; idle, see
        :func:`~aerodock.world.gripper.gripper_idle`), computed once per gripper state and read
        by every physics step. Kept while the state's gate and servo start times (what they are
        computed from) are the same read-only arrays (a :class:`GripperState` makes its arrays
        read-only; a changed gripper is a new state, and one whose strain gauge alone changed,
        as in most control periods, keeps its gate and start times: the flags stay)."""
        gripper = self.gripper
        gate, start = gripper.gate, gripper.servo_start_s
        cached = self.__dict__.get("_gripper_flags")  # not a field: not state, a view of it
        if (cached is not None and cached[0] is gate and cached[1] is start and is_frozen(gate)
                and is_frozen(start)):
            return cached[2:]
        captured = gate == _CAPTURED
        freeze(captured)
        cached = self.__dict__["_gripper_flags"] = (
            gate, start, captured, bool(np.count_nonzero(captured)), gripper_idle(gripper))
        return cached[2:]

    def _split(self) -> None:
        if self._both is not None:
            self._lead, self._fol = split_state(self.fleet, self._both, self.n)

    def take_rows(self, rows: np.ndarray, rng: np.random.Generator | TrialRNG,
                  field: DownwashField) -> WorldState:
        """The state of the trials at ``rows`` (copies), drawing from ``rng`` and feeling
        ``field`` (those trials' own streams and turbulence:
        :meth:`aerodock.world.world.World.take_rows`).

        Raises:
            ValueError: the torques are being logged (a flight recorder reads them).
        """
        if self.torque_log is not None:
            raise ValueError("a world whose torques are being logged cannot be split into trials")
        n, rows = self.n, np.asarray(rows, dtype=np.int64)
        own = {"n", "fleet", "rng", "field", "leader_fixed", "constants", "imu", "torque_log",
               "_both", "_lead", "_fol"}
        taken = {f.name: take_rows(getattr(self, f.name), rows) for f in fields(self)
                 if f.name not in own}
        out = WorldState(n=int(rows.size), fleet=self.fleet, rng=rng, field=field,
                         leader_fixed=self.leader_fixed,
                         constants=self.constants.take_rows(rows),
                         imu=None if self.imu is None else self.imu.take_rows(
                             pair_rows(rows, n)), **taken)
        out.both = state_rows(self.fleet, self.both, pair_rows(rows, n))
        return out


@dataclass
class StepFrame:
    """One physics step's inputs, shared quantities and accumulators.

    The terms of the step read the state through it and add into its accumulators in the order
    the step names them (the order of additions is part of the numbers: see
    :mod:`aerodock.world.step`).

    Attributes:
        targets: both vehicles' autopilot targets, held over the control period.
        close_command: (n,) the active trigger's command this step.
        both: the 2n vehicles at the start of the step; ``rot``/``pos``/``vel`` its arrays.
        lead, fol: the two halves as the downwash field sees them.
        mass_kg, mass_rows_kg: (2n,) and (2n, 3) each vehicle's true mass;
            ``fol_mass_rows_kg`` the followers' rows.
        captured, any_captured: followers hanging from the bar.
        bar_axis_t: (3, n) the bars' axes, ``(cos yaw, sin yaw, 0)``, component-major.
        force_n: (2n, 3) external forces on the vehicles, world NED, N (accumulator).
        torque_t: (3, 2n) external torques, body FRD, N m, component-major (accumulator; None
            for point masses).
        bar_force_n: (n, 3) forces on the hanging mass besides gravity and the cables
            (accumulator).
        wake_force_n: (n, 3) the wake's force on the followers' rotor disks (None: none yet).
        wake_torque_nm: (n, 3) the wake's torque on the followers (None: none).
        contact_n, inside: (n,) the gripper's contact force and bar-inside-the-gate flag.
        gyro_noise_radps: (2n, 3) this step's gyro noise (None: a noiseless gyro).
        gyro_radps, attitude_est: (2n, 3), (2n, 3, 3) what the autopilots read, with the
            filtered IMU chain (None: the true attitude and the gyro's noisy rates).
        new, accel: the vehicles after the step and their accelerations (2n, 3).
        wake_terms_together: the step runs the three wake terms one after the other, so the
            field may give all three forces in one call (:func:`aerodock.world.step.step_world`).
        wake_body_n, wake_bar_n: (n, 3) the wake's force on the followers' bodies and on the
            bars from that one call, N, NED, for their own terms to add (None: not made).
    """

    targets: Any
    close_command: np.ndarray
    both: Any
    rot: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    lead: BodyState
    fol: BodyState
    mass_kg: np.ndarray
    mass_rows_kg: np.ndarray
    fol_mass_rows_kg: np.ndarray
    captured: np.ndarray
    any_captured: bool
    bar_axis_t: np.ndarray
    force_n: np.ndarray
    torque_t: np.ndarray | None
    bar_force_n: np.ndarray
    wake_force_n: np.ndarray | None = None
    wake_torque_nm: np.ndarray | None = None
    contact_n: np.ndarray | None = None
    inside: np.ndarray | None = None
    gyro_noise_radps: np.ndarray | None = None
    gyro_radps: np.ndarray | None = None
    attitude_est: np.ndarray | None = None
    new: Any = None
    accel: np.ndarray | None = None
    wake_terms_together: bool = False
    wake_body_n: np.ndarray | None = None
    wake_bar_n: np.ndarray | None = None
