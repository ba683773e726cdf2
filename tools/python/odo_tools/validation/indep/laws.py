"""Effect laws, each a small pure function of arrays (mm, s, rad unless a name says otherwise).

These are the independent world's own laws (see README.md for equations and sources); nothing
here is shared with host_sim or with the diagnosis.
"""

from __future__ import annotations

import numpy as np

G = 9810.0  # mm/s^2


def motor(om0, omc, tau, amax, tk, decay=None):
    """Wheel speed of a speed-controlled motor after a command step: first-order lag tau with
    the acceleration bounded by amax (torque saturation), in closed form.

    om0, omc: (..., ) start speed and command (rad/s); tk: (n,) times since the step; decay:
    exp(-tk / tau) if the caller has it. Returns speed (..., n), angle turned since the step
    (..., n) and acceleration (..., n)."""
    e0 = (omc - om0)[..., None]
    if decay is None:
        decay = np.exp(-tk / tau)
    if (np.abs(e0) <= amax * tau).all():  # within the torque limit: a plain lag
        e = e0 * decay
        return omc[..., None] - e, omc[..., None] * tk - e0 * tau * (1.0 - decay), e / tau
    sg = np.sign(e0)
    ae = np.abs(e0)
    ts = np.maximum(0.0, (ae - amax * tau) / amax)  # time at the torque limit
    e1 = np.minimum(ae, amax * tau)
    t = tk
    sat = t <= ts
    dec = np.exp(-np.maximum(t - ts, 0.0) / tau)
    e = np.where(sat, ae - amax * t, e1 * dec) * sg
    ints = ae * ts - amax * ts * ts / 2
    integ = np.where(sat, ae * t - amax * t * t / 2, ints + e1 * tau * (1.0 - dec)) * sg
    acc = np.where(sat, amax, e1 / tau * dec) * sg
    return omc[..., None] - e, omc[..., None] * t - integ, acc


def play(x: np.ndarray, y0: np.ndarray, half: float) -> np.ndarray:
    """Backlash: the output follows the input only once the input has crossed the play
    (y_k = clip(y_{k-1}, x_k - half, x_k + half)); x (..., n), y0 (...)."""
    y = np.empty_like(x)
    prev = y0
    for k in range(x.shape[-1]):
        prev = np.clip(prev, x[..., k] - half, x[..., k] + half)
        y[..., k] = prev
    return y


def slip_accel(ds, acc, k1, p, cap):
    """Longitudinal slip tied to the wheel's acceleration: slip ratio k1 (|a| / 1 m/s^2)^p,
    capped; the wheel spins (true travel short) when it speeds up, drags when it slows down.
    ds: rolled distance per substep; acc: wheel surface acceleration (mm/s^2). The slip takes
    travel off in the direction the torque pushes (sign of acc), so a wheel speeding up
    backwards also falls short; a sign(ds) factor here once made reversing wheels run long
    when speeding up and short when slowing (half of every spot turn, every shuttle's return)."""
    kap = np.minimum(cap, k1 * (np.abs(acc) / 1000.0) ** p)
    return ds - np.sign(acc) * kap * np.abs(ds)


def traction(vw, vg0, alim, dt):
    """Friction-circle traction limit: the contact's ground speed follows the wheel's surface
    speed vw (..., n) but can change by at most alim (..., n) mm/s^2; the rest is spin or skid.
    Returns the ground speed (..., n). Sequential over the substeps (a rate limiter)."""
    out = np.empty_like(vw)
    vg = vg0
    for k in range(vw.shape[-1]):
        step = alim[..., k] * dt
        vg = vg + np.clip(vw[..., k] - vg, -step, step)
        out[..., k] = vg
    return out


def friction_circle(tx, ty, v0, alim, dt):
    """Skid by the friction circle: the wheels want the truck's centre to move at (tx, ty)
    (..., n) (their rolling speed along the heading, world frame); the floor can change the
    centre's velocity by at most alim (mm/s^2) in any direction, longitudinal and lateral
    together. While the wanted change is within that the centre follows (stick); beyond it the
    truck slides outward in a turn and its centre lags. v0 (..., 2) the velocity before.
    Returns the velocity (..., 2, n). Sequential over the substeps (a 2-D rate limiter)."""
    out = np.empty((*tx.shape[:-1], 2, tx.shape[-1]))
    v = v0.copy()
    step = alim * dt
    for k in range(tx.shape[-1]):
        dx = tx[..., k] - v[..., 0]
        dy = ty[..., k] - v[..., 1]
        m = np.hypot(dx, dy)
        f = np.minimum(1.0, step / np.maximum(m, 1e-12))
        v[..., 0] += f * dx
        v[..., 1] += f * dy
        out[..., :, k] = v
    return out


def scrub_factor_inv_radius(dl, dr, c_over_b2):
    """Turn-radius-dependent wheelbase b_eff = b (1 + c/R), R the turn radius, referred to the
    spot turn (R = b/2) so that spot turns are nominal: heading change factor
    (1 + 2c/b) / (1 + 2c/b * s), s = |dR - dL| / (|dL| + |dR|) = b / 2R (1 for |R| < b/2)."""
    den = np.abs(dl) + np.abs(dr)
    s = np.divide(np.abs(dr - dl), den, out=np.ones_like(den), where=den > 0)
    e = 2.0 * c_over_b2
    return (1.0 + e) / (1.0 + e * s)


def scrub_torque(dth, dl, dr, b, s_sat, r_t):
    """Tyre scrub torque: the contact patches resist yawing with a moment that grows with the
    patch's twist slip and saturates (tanh, transition radius r_t); the drive wheels creep
    longitudinally to overcome it, losing s_sat tanh(r_t/|R|) of their mean travel to yaw.
    The geometric wheelbase is narrower by (1 - s_sat) so that spot turns are nominal."""
    num = np.abs(dr + dl) * b / 2.0
    ratio = np.divide(r_t * np.abs(dr - dl), num, out=np.full_like(num, np.inf), where=num > 0)
    loss = s_sat * np.tanh(ratio) * (np.abs(dl) + np.abs(dr)) / b
    return dth - np.sign(dth) * np.minimum(loss, np.abs(dth))


def decode_saturating(dedges, slots):
    """An interrupt-driven decoder that can handle at most one edge per interrupt slot (slots
    (n,) per substep, f_max per second): edges that come faster coalesce into one interrupt and
    are lost. dedges (..., n) int. Returns (counted (..., n), overrun (..., n) bool)."""
    a = np.abs(dedges)
    got = np.minimum(a, slots)
    return np.sign(dedges) * got, got < a


def missed_prob(rate_hz, r50, width, pmax):
    """Probability that a quadrature state is too short to register, rising with the edge
    rate (the signal's amplitude falls and its edges slow down with frequency)."""
    return pmax / (1.0 + np.exp(-(rate_hz - r50) / width))


def link_eccentric(ax, ay, th_a, bx, by, th_b, d_a, d_b):
    """Extra length read by a linear encoder whose ends sit d_a, d_b (truck frames, mm) away
    from the pivot centres, beyond what it reads with both trucks square to the link."""
    ca, sa, cb, sb = np.cos(th_a), np.sin(th_a), np.cos(th_b), np.sin(th_b)
    px = ax + d_a[0] * ca - d_a[1] * sa - (bx + d_b[0] * cb - d_b[1] * sb)
    py = ay + d_a[0] * sa + d_a[1] * ca - (by + d_b[0] * sb + d_b[1] * cb)
    lt = np.hypot(ax - bx, ay - by)
    square = np.hypot(lt + d_a[0] - d_b[0], d_a[1] - d_b[1]) - lt
    return np.hypot(px, py) - lt - square


def diff0(a: np.ndarray, first: np.ndarray) -> np.ndarray:
    """Differences along the last axis with `first` (...,) as the value before a[..., 0]."""
    out = np.empty_like(a)
    out[..., 0] = a[..., 0] - first
    np.subtract(a[..., 1:], a[..., :-1], out=out[..., 1:])
    return out


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi
