"""Compiled parts of the world's sensing: motion capture's noise (:func:`mocap_noise_kernel`)
and the gripper's strain gauge, triggers and gate (:func:`gripper_step_kernel`).

Both do elementwise arithmetic only (a product, then a sum: each rounded as NumPy rounds it);
the random draws are made in Python, in the order they always were, and passed in."""

from __future__ import annotations

import numpy as np

from aerodock.jit import any_layout, njit


@any_layout("out")
@njit
def mocap_noise_kernel(lp: np.ndarray, lv: np.ndarray, lrpy: np.ndarray, ldraw: np.ndarray,
                       fp: np.ndarray, fv: np.ndarray, frpy: np.ndarray, fdraw: np.ndarray,
                       pos_sd: float, vel_sd: float, att_sd: float, out: np.ndarray) -> None:
    """Motion capture's observations of the leaders (``l*``) and followers (``f*``): position
    ``p`` (n, 3), velocity ``v`` (n, 3) and angles ``rpy`` (n, 3) plus their noise, into
    ``out`` (6, n, 3): the leaders' p, v, rpy, then the followers'.

    ``*draw`` (k, n): each trial's standard normal draws, component-major; with ``att_sd > 0``
    (k = 9) the angles' three, then the position's and the velocity's; else (k >= 6) the
    position's and the velocity's. Each element is ``x + sd * draw`` (NumPy's
    ``x + sd * noise``: the product rounded, then the sum)."""
    off = 3 if att_sd > 0 else 0
    _noisy(lp, lv, lrpy, ldraw, pos_sd, vel_sd, att_sd, off, out, 0)
    _noisy(fp, fv, frpy, fdraw, pos_sd, vel_sd, att_sd, off, out, 3)


@njit
def _noisy(p: np.ndarray, v: np.ndarray, rpy: np.ndarray, draw: np.ndarray, pos_sd: float,
           vel_sd: float, att_sd: float, off: int, out: np.ndarray, o: int) -> None:
    """One vehicle's rows of :func:`mocap_noise_kernel` into ``out[o:o + 3]``."""
    for i in range(p.shape[0]):
        for j in range(3):
            out[o, i, j] = p[i, j] + pos_sd * draw[off + j, i]
            out[o + 1, i, j] = v[i, j] + vel_sd * draw[off + 3 + j, i]
            if off:
                out[o + 2, i, j] = rpy[i, j] + att_sd * draw[j, i]
            else:
                out[o + 2, i, j] = rpy[i, j]


# gripper_step_kernel's report of what changed (bits of its return value)
CHANGED_READING, CHANGED_BY_CONTACT, CHANGED_SERVO, CHANGED_START, CHANGED_DONE = 1, 2, 4, 8, 16
_OPEN, _CLOSING, _CAPTURED, _MISSED = 0, 1, 2, 3  # aerodock.world.gripper.GateState


@njit
def gripper_step_kernel_body(gate0: np.ndarray, bias_true: np.ndarray, bias_est: np.ndarray,
                             reading0: np.ndarray, servo_start0: np.ndarray,
                             by_contact0: np.ndarray, inside_at_start0: np.ndarray,
                             slipped0: np.ndarray, resolved0: np.ndarray, close_time: np.ndarray,
                             stuck: np.ndarray, t_s: float, contact: np.ndarray, inside: np.ndarray,
                             sample: bool, noise: np.ndarray, noise_sd: float, threshold: float,
                             passive_any: bool, passive: np.ndarray, active_any: bool,
                             active: np.ndarray, close_command: np.ndarray, latency: float,
                             reading: np.ndarray, by_contact: np.ndarray, servo_start: np.ndarray,
                             gate: np.ndarray, inside_at_start: np.ndarray, slipped: np.ndarray,
                             resolved: np.ndarray) -> int:
    """One step of the grippers (:func:`aerodock.world.gripper.step_gripper`): the state's
    arrays (``*0``, ``bias_*``, ``close_time``, ``stuck``) in, the next state's out (``reading``
    ... ``resolved``: every element written). Returns the ``CHANGED_*`` bits: which outputs the
    step made anew (the others equal their inputs, which the caller passes on as they are).

    With ``sample``, the strain gauge reads ``(contact + bias_true) + noise_sd * noise -
    bias_est`` (a stuck gauge, ``stuck`` not NaN, reads ``stuck``); ``passive`` / ``active``:
    (1,) for every trial or (n,) per trial, armed in any trial when ``*_any``."""
    n = gate0.shape[0]
    pw, aw = passive.shape[0] > 1, active.shape[0] > 1
    fired = started = finished = False
    for i in range(n):
        open_ = gate0[i] == _OPEN
        untriggered = open_ and servo_start0[i] != servo_start0[i]
        fire = False
        bc = by_contact0[i]
        r = reading0[i]
        if sample:
            r = contact[i] + bias_true[i]
            r = r + noise_sd * noise[i]
            r = r - bias_est[i]
            if stuck[i] == stuck[i]:
                r = stuck[i]
            if passive_any:
                sensed = untriggered and r > threshold and passive[i if pw else 0]
                fire = sensed
                bc = bc or sensed
        reading[i] = r
        by_contact[i] = bc
        if active_any and untriggered and close_command[i] and active[i if aw else 0]:
            fire = True
        s = servo_start0[i]
        if fire:
            fired = True
            s = t_s + latency
        servo_start[i] = s
        g = gate0[i]
        ias = inside_at_start0[i]
        if open_ and s <= t_s:
            started = True
            g = _CLOSING
            ias = inside[i]
        sl = slipped0[i]
        res = resolved0[i]
        if g == _CLOSING and t_s >= s + close_time[i]:
            finished = True
            g = _CAPTURED if inside[i] else _MISSED
            sl = sl or (not inside[i] and ias)
            res = t_s
        gate[i] = g
        inside_at_start[i] = ias
        slipped[i] = sl
        resolved[i] = res
    changed = 0
    if sample:
        changed |= CHANGED_READING
        if passive_any:
            changed |= CHANGED_BY_CONTACT
    if fired:
        changed |= CHANGED_SERVO
    if started:
        changed |= CHANGED_START
    if finished:
        changed |= CHANGED_DONE
    return changed


@any_layout("reading", "by_contact", "servo_start", "gate", "inside_at_start", "slipped",
            "resolved")
@njit
def gripper_step_kernel(gate0: np.ndarray, bias_true: np.ndarray, bias_est: np.ndarray,
                        reading0: np.ndarray, servo_start0: np.ndarray,
                        by_contact0: np.ndarray, inside_at_start0: np.ndarray,
                        slipped0: np.ndarray, resolved0: np.ndarray, close_time: np.ndarray,
                        stuck: np.ndarray, t_s: float, contact: np.ndarray, inside: np.ndarray,
                        sample: bool, noise: np.ndarray, noise_sd: float, threshold: float,
                        passive_any: bool, passive: np.ndarray, active_any: bool,
                        active: np.ndarray, close_command: np.ndarray, latency: float,
                        reading: np.ndarray, by_contact: np.ndarray, servo_start: np.ndarray,
                        gate: np.ndarray, inside_at_start: np.ndarray, slipped: np.ndarray,
                        resolved: np.ndarray) -> int:
    """:func:`gripper_step_kernel_body` for a call from Python: any array layout (sealed to one
    general signature, :func:`aerodock.jit.any_layout`); compiled callers call the body itself,
    which no seal stops from compiling for their types."""
    return gripper_step_kernel_body(gate0, bias_true, bias_est, reading0, servo_start0,
                                    by_contact0, inside_at_start0, slipped0, resolved0, close_time,
                                    stuck, t_s, contact, inside, sample, noise, noise_sd,
                                    threshold, passive_any, passive, active_any, active,
                                    close_command, latency, reading, by_contact, servo_start, gate,
                                    inside_at_start, slipped, resolved)
