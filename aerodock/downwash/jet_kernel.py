"""The round jet's forces, compiled: the one implementation of :class:`RoundJetField`'s physics
(its docstring and :mod:`aerodock.downwash.jet`'s give the model; this module gives the numbers).

Each kernel works over the batch in phases, as the NumPy field did: the geometry of every trial
first, then each transcendental function over a whole row of the batch in one call of NumPy's
own loop (:func:`aerodock.jit.np_exp` and its kin: NumPy's SIMD exp, log and power round
differently from the C library's), then the forces. Every other operation is written in the
order the NumPy field computed it, so the numbers are the same to the bit
(``tests/unit/test_compiled_step.py``).

Parameters travel as one float64 array (``JP_*`` index it) and the per-point constants as
columns (``COL_*``): the disks' rows first, the body's last.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.borrowed import (
    borrowed,
    keep_alive,
    scratch_row,
    scratch_rows,
    scratch_size,
    scratch_slab,
)
from aerodock.jit import any_layout, njit, np_exp, np_log, np_power

# jet parameters (a float64 array)
JP_B0, JP_SPREAD, JP_P, JP_JET_CONST, JP_TIME_RATIO, JP_LENGTH_RATIO, JP_PAIR_DIST = range(7)
JP_TURB_V, JP_TURB_L, JP_TORQUE_GAIN, JP_PLANAR, JP_LN2 = range(7, 12)
JP_SIZE = 12
# per-point columns (4, k + 1): sig2's divisor, the area's second moment, the exponent's
# factor, the planar scale
COL_DIV, COL_ADD, COL_SCALE, COL_PLANAR = range(4)


@njit
def leader_wake(lead_r: np.ndarray, lead_thrust: np.ndarray, lead_v: np.ndarray,
                jet_const: float, axis: np.ndarray, jet: np.ndarray, jet_min: np.ndarray,
                v_perp: np.ndarray) -> None:
    """The parts of the wake that depend on the leader only, component-major: the axis (body
    z) (3, n), the jet's momentum speed ``sqrt(2 ln2 T / (rho pi))`` (n,), the same floored at
    1e-6, the leader's velocity across the axis (3, n)."""
    for i in range(lead_r.shape[0]):
        a0, a1, a2 = lead_r[i, 0, 2], lead_r[i, 1, 2], lead_r[i, 2, 2]
        axis[0, i], axis[1, i], axis[2, i] = a0, a1, a2
        t = lead_thrust[i]
        t = t if (t >= 0.0 or t != t) else 0.0
        j = math.sqrt(t * jet_const)
        jet[i] = j
        jet_min[i] = j if (j >= 1e-6 or j != j) else 1e-6
        v0, v1, v2 = lead_v[i, 0], lead_v[i, 1], lead_v[i, 2]
        along = v0 * a0 + v1 * a1
        along += v2 * a2
        v_perp[0, i] = v0 - along * a0
        v_perp[1, i] = v1 - along * a1
        v_perp[2, i] = v2 - along * a2


@njit
def _depth_terms(r0: float, r1: float, r2: float, a0: float, a1: float, a2: float,
                 jet: float, jet_min: float, vp0: float, vp1: float, vp2: float, b0: float,
                 spread: float) -> tuple[float, float, float, float, float, float]:
    """A point at ``r`` from the leader: depth along the axis ``a``, half-width, centreline
    speed and the radial vector from the (skewed) wake centre."""
    depth = r0 * a0 + r1 * a1
    depth += r2 * a2
    s = depth if (depth >= 0.0 or depth != depth) else 0.0
    half_width = spread * s + b0
    centre = jet / half_width
    # wake skew: convection time from the rotor to depth s, int_0^s b(s') ds' / jet
    tau = (0.5 * spread) * s + b0
    tau *= s
    tau /= jet_min
    q0 = r0 - depth * a0
    q1 = r1 - depth * a1
    q2 = r2 - depth * a2
    q0 += vp0 * tau
    q1 += vp1 * tau
    q2 += vp2 * tau
    return depth, half_width, centre, q0, q1, q2


@njit
def _jet_scratch_size(n: int, k: int) -> int:
    """How many floats :func:`jet_forces`'s temporary rows take (k disks, n trials)."""
    npts = k + 1
    return scratch_size(n * (17 + 12 * npts + k) + 4 * npts, 24)


@any_layout("processes", "force", "torque", "body", "axial", "tau_out", "share_out")
@njit
def jet_forces(loops: np.ndarray, jp: np.ndarray, cols: np.ndarray, offsets: np.ndarray,
               lead_r: np.ndarray, lead_thrust: np.ndarray, lead_v: np.ndarray,
               lead_p: np.ndarray, fol_r: np.ndarray, fol_p: np.ndarray, fol_v: np.ndarray,
               coeff: np.ndarray, processes: np.ndarray, draws: np.ndarray, dt: float,
               advance: bool, noisy: bool, split: bool, want_torque: bool,
               force: np.ndarray, torque: np.ndarray, body: np.ndarray, axial: np.ndarray,
               tau_out: np.ndarray, share_out: np.ndarray) -> None:
    """The wake on the follower's ``k`` rotor disks and its body (the field's ``_step`` and
    ``_forces_from``).

    ``advance``: step the turbulence ``processes`` (3 + k, n: the shared axial and two lateral
    ones, then each disk's own) by ``dt`` with ``draws`` (3 + k, n) first. ``noisy``: the
    forces of the current turbulence (else the mean). ``split``: the disks' force ``force``
    (n, 3, NED), their torque ``torque`` (n, 3, body FRD; when ``want_torque``) and the body's
    force ``body`` (n, 3); else the whole force in ``force``. Always: the mean axial force per
    point ``axial`` (k + 1, n), the turbulence's correlation time ``tau_out`` and the disks'
    shared variance ``share_out`` (n,).

    It is long on purpose: one compiled pass computes the wake at every point of every trial
    in the order the NumPy field once did, so its numbers stay those of that code to the bit
    (docs/performance.md); its parts that stand alone (the leader's wake, the profile at a
    point, the turbulence's step) are the helpers above.
    """
    n = lead_r.shape[0]
    k = offsets.shape[0]
    npts = k + 1
    b0, spread_rate, p = jp[JP_B0], jp[JP_SPREAD], jp[JP_P]
    flat = True
    for q in range(k):
        if offsets[q, 2] != 0.0:
            flat = False
    # every temporary row below is a view of one allocation (aerodock.borrowed's scratch)
    owner = np.empty(_jet_scratch_size(n, k))
    (work,) = borrowed((owner,))
    axis, at = scratch_rows(work, 0, 3, n)
    jet, at = scratch_row(work, at, n)
    jet_min, at = scratch_row(work, at, n)
    v_perp, at = scratch_rows(work, at, 3, n)
    leader_wake(lead_r, lead_thrust, lead_v, jp[JP_JET_CONST], axis, jet, jet_min, v_perp)
    depth, at = scratch_rows(work, at, npts, n)
    half_width, at = scratch_rows(work, at, npts, n)
    centre, at = scratch_rows(work, at, npts, n)
    radial, at = scratch_slab(work, at, 3, npts, n)
    d2, at = scratch_rows(work, at, npts, n)
    v_axial, at = scratch_row(work, at, n)
    ratio, at = scratch_rows(work, at, npts, n)
    spread, at = scratch_rows(work, at, npts, n)
    exp_args, at = scratch_rows(work, at, 2, n)  # the turbulence's decay and share, before exp
    any_above = False
    # -- phase 1: geometry at the k disk centres and the body centre -------------------------
    for i in range(n):
        d0 = fol_p[i, 0] - lead_p[i, 0]
        d1 = fol_p[i, 1] - lead_p[i, 1]
        dd2 = fol_p[i, 2] - lead_p[i, 2]
        a0, a1, a2 = axis[0, i], axis[1, i], axis[2, i]
        for q in range(npts):
            px = offsets[q, 0] if q < k else 0.0
            py = offsets[q, 1] if q < k else 0.0
            r0 = fol_r[i, 0, 0] * px + fol_r[i, 0, 1] * py
            r1 = fol_r[i, 1, 0] * px + fol_r[i, 1, 1] * py
            r2 = fol_r[i, 2, 0] * px + fol_r[i, 2, 1] * py
            if not flat:
                pz = offsets[q, 2] if q < k else 0.0
                r0 += fol_r[i, 0, 2] * pz
                r1 += fol_r[i, 1, 2] * pz
                r2 += fol_r[i, 2, 2] * pz
            r0 += d0
            r1 += d1
            r2 += dd2
            dep, hw, cen, q0, q1, q2 = _depth_terms(
                r0, r1, r2, a0, a1, a2, jet[i], jet_min[i], v_perp[0, i], v_perp[1, i],
                v_perp[2, i], b0, spread_rate)
            depth[q, i], half_width[q, i], centre[q, i] = dep, hw, cen
            radial[0, q, i], radial[1, q, i], radial[2, q, i] = q0, q1, q2
            dist2 = q0 * q0 + q1 * q1
            dist2 += q2 * q2
            d2[q, i] = dist2
            if dep < 0.0:
                any_above = True
            # w^p of a Gaussian averaged over the disk (the body: drag, p = 2, over its area)
            sig2 = hw * hw / cols[COL_DIV, q]
            sige2 = sig2 + cols[COL_ADD, q]
            ratio[q, i] = sig2 / sige2
            spread[q, i] = dist2 / (sige2 * cols[COL_SCALE, q])
        va = fol_v[i, 0] * a0 + fol_v[i, 1] * a1
        va += fol_v[i, 2] * a2
        v_axial[i] = va
        b_c = half_width[k, i]
        c_c = centre[k, i]
        tau = jp[JP_TIME_RATIO] * b_c / (c_c if (c_c >= 1e-6 or c_c != c_c) else 1e-6)
        tau_out[i] = tau
        exp_args[0, i] = -dt / tau
        exp_args[1, i] = -jp[JP_PAIR_DIST] / (jp[JP_LENGTH_RATIO] * b_c)
    # -- phase 2: the transcendental rows -----------------------------------------------------
    exps, at = scratch_rows(work, at, 2, n)
    np_exp(loops, exp_args[0], exps[0])
    np_exp(loops, exp_args[1], share_out)
    log_g, at = scratch_rows(work, at, k, n)
    for q in range(k):
        np_log(loops, ratio[q], log_g[q])
    for q in range(k):
        for i in range(n):
            g = log_g[q, i] - spread[q, i]
            log_g[q, i] = g / p
    w, at = scratch_rows(work, at, npts, n)
    for q in range(k):
        np_exp(loops, log_g[q], w[q])
        for i in range(n):
            w[q, i] = centre[q, i] * w[q, i]
    neg, at = scratch_row(work, at, n)
    fade, at = scratch_row(work, at, n)
    for i in range(n):
        neg[i] = -spread[k, i]
    np_exp(loops, neg, neg)
    for i in range(n):
        wb = centre[k, i] * math.sqrt(ratio[k, i])
        w[k, i] = wb * neg[i]
    if any_above:  # nothing above the rotors: the wake fades above the rotor plane
        for q in range(npts):
            for i in range(n):
                x = depth[q, i] / b0
                neg[i] = -(x * x)
            np_exp(loops, neg, fade)
            for i in range(n):
                if depth[q, i] < 0.0:
                    w[q, i] *= fade[i]
    # the ingest laws: phi(w - v) - phi(-v), phi(x) = sign(x) |x|^p (the body's p = 2)
    rel, at = scratch_rows(work, at, npts, n)
    mag, at = scratch_rows(work, at, npts, n)
    own, at = scratch_row(work, at, n)
    pw, at = scratch_row(work, at, n)
    for q in range(npts):
        for i in range(n):
            r = w[q, i] - v_axial[i]
            rel[q, i] = r
            mag[q, i] = abs(r)
    for i in range(n):
        own[i] = abs(v_axial[i])
    if p == 1.0:
        for q in range(k):
            for i in range(n):
                axial[q, i] = w[q, i]
    elif p == 2.0:
        for q in range(k):
            for i in range(n):
                a = rel[q, i] * mag[q, i]
                axial[q, i] = a + v_axial[i] * own[i]
    else:
        for i in range(n):
            pw[i] = p
        for q in range(k):
            np_power(loops, mag[q], pw, axial[q])
        np_power(loops, own, pw, pw)  # |v|^p, in place
        for q in range(k):
            for i in range(n):
                a = math.copysign(axial[q, i], rel[q, i])
                axial[q, i] = a + math.copysign(pw[i], v_axial[i])
    for i in range(n):
        b = rel[k, i] * mag[k, i]
        axial[k, i] = b + v_axial[i] * own[i]
    for q in range(npts):
        for i in range(n):
            axial[q, i] *= coeff[q, i]
    # -- phase 3: the turbulence and the forces ----------------------------------------------
    decay = exps[0]
    if advance:
        for i in range(n):
            dc = decay[i]
            innov = math.sqrt(1.0 - dc * dc)
            for r in range(3 + k):
                x = processes[r, i] * dc
                processes[r, i] = x + draws[r, i] * innov
    gain = jp[JP_TORQUE_GAIN]
    planar_on = jp[JP_PLANAR] != 0.0
    turb_v, turb_l = jp[JP_TURB_V], jp[JP_TURB_L]
    along, at = scratch_row(work, at, npts)
    fq, at = scratch_rows(work, at, 3, npts)
    for i in range(n):
        if noisy:
            sh = share_out[i]
            root_own = math.sqrt(1.0 - sh)
            root_sh = math.sqrt(sh)
            c0 = processes[0, i]
            for q in range(k):
                x = processes[3 + q, i] * root_own
                along[q] = x + root_sh * c0
            along[k] = c0
            for q in range(npts):
                x = along[q] * turb_v
                x += 1.0
                along[q] = x * axial[q, i]
        else:
            for q in range(npts):
                along[q] = axial[q, i]
        if gain != 1.0 and (split or want_torque):
            mean = 0.0
            for q in range(k):
                mean = axial[q, i] if q == 0 else mean + axial[q, i]
            mean = mean / k
            for q in range(k):
                along[q] += (axial[q, i] - mean) * (gain - 1.0)
        a0, a1, a2 = axis[0, i], axis[1, i], axis[2, i]
        gust_on = noisy and turb_l != 0.0
        g0 = g1 = g2 = 0.0
        if gust_on:  # one lateral process pushes every disk and the body: R e1 n1 + R e2 n2
            n1, n2 = processes[1, i], processes[2, i]
            g0 = (lead_r[i, 0, 0] * n1 + lead_r[i, 0, 1] * n2) * turb_l
            g1 = (lead_r[i, 1, 0] * n1 + lead_r[i, 1, 1] * n2) * turb_l
            g2 = (lead_r[i, 2, 0] * n1 + lead_r[i, 2, 1] * n2) * turb_l
        if not split and not want_torque:
            s = 0.0
            for q in range(npts):
                s = along[q] if q == 0 else s + along[q]
            t0, t1, t2 = a0 * s, a1 * s, a2 * s
            if planar_on:
                for c in range(3):
                    acc = 0.0
                    for q in range(npts):
                        pl = axial[q, i] * cols[COL_PLANAR, q] / half_width[q, i]
                        x = radial[c, q, i] * pl
                        acc = x if q == 0 else acc + x
                    if c == 0:
                        t0 += acc
                    elif c == 1:
                        t1 += acc
                    else:
                        t2 += acc
            if gust_on:
                m = 0.0
                for q in range(npts):
                    m = abs(axial[q, i]) if q == 0 else m + abs(axial[q, i])
                t0 += g0 * m
                t1 += g1 * m
                t2 += g2 * m
            force[i, 0], force[i, 1], force[i, 2] = t0, t1, t2
            continue
        for q in range(npts):
            if planar_on:
                pl = axial[q, i] * cols[COL_PLANAR, q] / half_width[q, i]
                f0, f1, f2 = radial[0, q, i] * pl, radial[1, q, i] * pl, radial[2, q, i] * pl
            else:
                f0 = f1 = f2 = 0.0
            f0 += a0 * along[q]
            f1 += a1 * along[q]
            f2 += a2 * along[q]
            if gust_on:
                m = abs(axial[q, i])
                f0 += g0 * m
                f1 += g1 * m
                f2 += g2 * m
            fq[0, q], fq[1, q], fq[2, q] = f0, f1, f2
        for c in range(3):
            s = fq[c, 0]
            for q in range(1, k):
                s += fq[c, q]
            force[i, c] = s
            body[i, c] = fq[c, k]
        if not want_torque:
            continue
        # R^T F_k per disk, then sum_k r_k x (R^T F_k)
        t0 = t1 = t2 = 0.0
        u0 = u1 = 0.0
        for q in range(k):
            fb0 = fol_r[i, 0, 0] * fq[0, q] + fol_r[i, 1, 0] * fq[1, q]
            fb0 += fol_r[i, 2, 0] * fq[2, q]
            fb1 = fol_r[i, 0, 1] * fq[0, q] + fol_r[i, 1, 1] * fq[1, q]
            fb1 += fol_r[i, 2, 1] * fq[2, q]
            fb2 = fol_r[i, 0, 2] * fq[0, q] + fol_r[i, 1, 2] * fq[1, q]
            fb2 += fol_r[i, 2, 2] * fq[2, q]
            ox, oy = offsets[q, 0], offsets[q, 1]
            x0 = oy * fb2
            x1 = ox * fb2
            x2 = ox * fb1 - oy * fb0
            t0 = x0 if q == 0 else t0 + x0
            t1 = x1 if q == 0 else t1 + x1
            t2 = x2 if q == 0 else t2 + x2
            if not flat:
                oz = offsets[q, 2]
                y0 = oz * fb1
                y1 = oz * fb0
                u0 = y0 if q == 0 else u0 + y0
                u1 = y1 if q == 0 else u1 + y1
        torque[i, 0] = t0
        torque[i, 1] = -t1
        torque[i, 2] = t2
        if not flat:
            torque[i, 0] -= u0
            torque[i, 1] += u1
    keep_alive(owner)


@any_layout("axis", "speed", "half_width", "centre")
@njit
def point_wake(loops: np.ndarray, jp: np.ndarray, lead_r: np.ndarray,
               lead_thrust: np.ndarray, lead_v: np.ndarray, lead_p: np.ndarray,
               points: np.ndarray, axis: np.ndarray, speed: np.ndarray,
               half_width: np.ndarray, centre: np.ndarray) -> None:
    """The wake at one point per trial, ``points`` (n, 3): the axis (3, n) and the local axial
    air speed, half-width and centreline speed (n,) (a point: no averaging over an area)."""
    n = lead_r.shape[0]
    b0 = jp[JP_B0]
    owner = np.empty(scratch_size(7 * n, 5))  # the temporary rows below are views of it
    (work,) = borrowed((owner,))
    jet, at = scratch_row(work, 0, n)
    jet_min, at = scratch_row(work, at, n)
    v_perp, at = scratch_rows(work, at, 3, n)
    leader_wake(lead_r, lead_thrust, lead_v, jp[JP_JET_CONST], axis, jet, jet_min, v_perp)
    depth, at = scratch_row(work, at, n)
    arg, at = scratch_row(work, at, n)
    any_above = False
    for i in range(n):
        dep, hw, cen, q0, q1, q2 = _depth_terms(
            points[i, 0] - lead_p[i, 0], points[i, 1] - lead_p[i, 1],
            points[i, 2] - lead_p[i, 2], axis[0, i], axis[1, i], axis[2, i], jet[i],
            jet_min[i], v_perp[0, i], v_perp[1, i], v_perp[2, i], b0, jp[JP_SPREAD])
        depth[i], half_width[i], centre[i] = dep, hw, cen
        dist2 = q0 * q0 + q1 * q1
        dist2 += q2 * q2
        dist2 /= hw * hw
        arg[i] = dist2 * -jp[JP_LN2]
        if dep < 0.0:
            any_above = True
    np_exp(loops, arg, speed)
    for i in range(n):
        speed[i] = centre[i] * speed[i]
    if any_above:
        for i in range(n):
            x = depth[i] / b0
            arg[i] = -(x * x)
        np_exp(loops, arg, arg)
        for i in range(n):
            if depth[i] < 0.0:
                speed[i] *= arg[i]
    keep_alive(owner)


@any_layout("noise", "out")
@njit
def bar_force(loops: np.ndarray, jp: np.ndarray, lead_r: np.ndarray,
              lead_thrust: np.ndarray, lead_v: np.ndarray, lead_p: np.ndarray,
              bar_p: np.ndarray, bar_v: np.ndarray, bar_axis: np.ndarray, has_axis: bool,
              noise: np.ndarray, draws: np.ndarray, dt: float, advance: bool,
              bar_consts: np.ndarray, out: np.ndarray) -> None:
    """The turbulent wake air's drag on the docking bar (the field's ``bar_force_n``): the
    bar's turbulence ``noise`` (3, n) advanced by ``dt`` with ``draws`` (3, n) when
    ``advance``; the force (n, 3), N, NED, into ``out``. ``bar_consts``: (a, b, drag) =
    (bar_turb_vertical / 2, bar_turb_lateral, rho C_d A / 2)."""
    n = lead_r.shape[0]
    owner = np.empty(scratch_size(7 * n + 3, 6))  # the temporary rows below are views of it
    (work,) = borrowed((owner,))
    axis, at = scratch_rows(work, 0, 3, n)
    speed, at = scratch_row(work, at, n)
    half_width, at = scratch_row(work, at, n)
    centre, at = scratch_row(work, at, n)
    decay, at = scratch_row(work, at, n)
    u, at = scratch_row(work, at, 3)
    point_wake(loops, jp, lead_r, lead_thrust, lead_v, lead_p, bar_p, axis, speed, half_width,
               centre)
    if advance:
        for i in range(n):
            c = centre[i]
            tau = jp[JP_TIME_RATIO] * half_width[i] / (c if (c >= 1e-6 or c != c) else 1e-6)
            decay[i] = -dt / tau
        np_exp(loops, decay, decay)
        for i in range(n):
            dc = decay[i]
            innov = math.sqrt(1.0 - dc * dc)
            for r in range(3):
                x = draws[r, i] * innov
                noise[r, i] = x + dc * noise[r, i]
    half_v, lat, drag = bar_consts[0], bar_consts[1], bar_consts[2]
    for i in range(n):
        s = speed[i]
        along = half_v * noise[0, i]
        along += 1.0
        along *= s
        scale = lat * s
        n1 = noise[1, i] * scale
        n2 = noise[2, i] * scale
        for c in range(3):
            x = axis[c, i] * along
            x += lead_r[i, c, 0] * n1
            x += lead_r[i, c, 1] * n2
            u[c] = x - bar_v[i, c]
        if has_axis:
            dot = u[0] * bar_axis[i, 0] + u[1] * bar_axis[i, 1]
            dot += u[2] * bar_axis[i, 2]
            for c in range(3):
                u[c] -= dot * bar_axis[i, c]
        norm = u[0] * u[0] + u[1] * u[1]
        norm += u[2] * u[2]
        norm = math.sqrt(norm) * drag
        for c in range(3):
            out[i, c] = norm * u[c]
    keep_alive(owner)


@any_layout("processes", "bar_noise", "out")
@njit
def wake_step(loops: np.ndarray, jp: np.ndarray, cols: np.ndarray, offsets: np.ndarray,
              lead_r: np.ndarray, lead_thrust: np.ndarray, lead_v: np.ndarray,
              lead_p: np.ndarray, fol_r: np.ndarray, fol_p: np.ndarray, fol_v: np.ndarray,
              coeff: np.ndarray, processes: np.ndarray, draws: np.ndarray, dt: float,
              bar_p: np.ndarray, bar_v: np.ndarray, bar_axis: np.ndarray, has_axis: bool,
              bar_noise: np.ndarray, bar_draws: np.ndarray, bar_dt: float, bar_advance: bool,
              bar_consts: np.ndarray, out: np.ndarray) -> None:
    """One physics step's wake on the follower and the bar in one call (the field's
    ``wake_step``): :func:`jet_forces` as the field's ``wrench`` calls it (the turbulence
    ``processes`` advanced by ``dt`` with ``draws``; the noisy, split forces and the torque),
    then :func:`bar_force` as its ``bar_force_n`` does (``bar_noise`` advanced by ``bar_dt``
    with ``bar_draws`` when ``bar_advance``). Their arguments are theirs; ``out`` (4, n, 3)
    takes the disks' force (N, NED), their torque (N·m, body FRD), the body's force and the
    bar's (N, NED). Nothing here computes: the two kernels are the physics, so the numbers are
    theirs called one after the other."""
    n = lead_r.shape[0]
    npts = offsets.shape[0] + 1
    owner = np.empty(scratch_size((npts + 2) * n, 3))  # the temporary rows below are views of it
    (work,) = borrowed((owner,))
    axial, at = scratch_rows(work, 0, npts, n)
    tau, at = scratch_row(work, at, n)
    share, at = scratch_row(work, at, n)
    jet_forces(loops, jp, cols, offsets, lead_r, lead_thrust, lead_v, lead_p, fol_r, fol_p,
               fol_v, coeff, processes, draws, dt, True, True, True, True, out[0], out[1],
               out[2], axial, tau, share)
    bar_force(loops, jp, lead_r, lead_thrust, lead_v, lead_p, bar_p, bar_v, bar_axis, has_axis,
              bar_noise, bar_draws, bar_dt, bar_advance, bar_consts, out[3])
    keep_alive(owner)
