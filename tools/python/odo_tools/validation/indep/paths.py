"""Reference paths and motion profiles: what the robot's own planner asks its controller for.

A path is a list of segments, each a tuple:
  ("line", L_mm)        straight along the current heading (L < 0: drive backwards)
  ("arc", R_mm, ang)    constant-curvature arc, ang in rad (> 0 turns left)
  ("spin", ang)         turn on the spot by ang rad (> 0 counter-clockwise)
Consecutive lines and arcs are driven as one continuous move (the speed is limited on arcs by a
lateral-acceleration and a wheel-speed bound); a spin or a reverse line is a move of its own, and
the robot pauses between moves. Each move gets an acceleration- and jerk-limited speed profile:
a forward/backward pass for the acceleration bounds on a grid along the path, then a moving
average over a_max/j_max seconds, which bounds the jerk and keeps the travelled distance.
Everything is sampled on a 1 ms grid; the controller picks its ticks from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

DT_REF = 0.001  # s, the planner's time grid
DS = 5.0  # mm, the grid along a path for the speed profile


@dataclass(frozen=True)
class Limits:
    """The planner's bounds (nominal units: mm, s, rad)."""

    v: float  # cruise speed, mm/s
    a: float  # acceleration, mm/s^2
    d: float  # deceleration, mm/s^2
    jerk_s: float  # a/j: the time over which acceleration builds up, s
    a_lat: float  # lateral acceleration on arcs, mm/s^2
    w: float  # spin rate, rad/s
    alpha: float  # spin acceleration, rad/s^2
    v_wheel: float  # wheel surface speed bound, mm/s
    b: float  # nominal wheelbase, mm
    pause: float  # s standing still between moves


@dataclass
class Ref:
    """A run's reference on the 1 ms grid."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    th: np.ndarray  # unwrapped heading, rad
    v: np.ndarray  # mm/s along the heading
    w: np.ndarray  # rad/s
    s: np.ndarray  # mm along the forward path (constant while spinning or standing)
    phase: np.ndarray  # 0 standing, 1 driving forward, 2 spinning, 3 reversing
    geo: np.ndarray | None = None  # (m, 5): s, x, y, th, kappa of the forward path (with lead-in)


def _moves(segs: list[tuple]) -> list[tuple[str, list[tuple]]]:
    out: list[tuple[str, list[tuple]]] = []
    for sg in segs:
        if sg[0] == "spin" or (sg[0] == "line" and sg[1] < 0):
            out.append(("spin" if sg[0] == "spin" else "rev", [sg]))
        elif out and out[-1][0] == "fwd":
            out[-1][1].append(sg)
        else:
            out.append(("fwd", [sg]))
    return out


def geometry(segs: list[tuple], x0: float, y0: float, th0: float) -> np.ndarray:
    """(m, 5) samples s, x, y, th, kappa of consecutive lines/arcs, exact per segment."""
    rows = [np.array([[0.0, x0, y0, th0, 0.0]])]
    s0, x, y, th = 0.0, x0, y0, th0
    for sg in segs:
        if sg[0] == "line":
            L = float(sg[1])
            n = max(2, math.ceil(L / DS) + 1)
            u = np.linspace(0.0, L, n)[1:]
            k = 0.0
            px, py, pt = x + u * math.cos(th), y + u * math.sin(th), np.full(u.size, th)
        else:
            R, ang = float(sg[1]), float(sg[2])
            L = R * abs(ang)
            n = max(2, math.ceil(L / DS) + 1)
            u = np.linspace(0.0, L, n)[1:]
            k = math.copysign(1.0 / R, ang)
            pt = th + k * u
            px = x + (np.sin(pt) - math.sin(th)) / k
            py = y - (np.cos(pt) - math.cos(th)) / k
        rows.append(np.column_stack([s0 + u, px, py, pt, np.full(u.size, k)]))
        s0, x, y, th = s0 + L, float(px[-1]), float(py[-1]), float(pt[-1])
    g = np.vstack(rows)
    if len(segs):
        g[0, 4] = g[1, 4]
    return g


def _passes(length: float, vlim: np.ndarray, a: float, d: float) -> np.ndarray:
    """Speeds on the grid under the bounds: v^2 grows by at most 2 a ds per grid step,
    w_i = min_j (vlim_j^2 + 2 a ds (i - j)), w_0 = 0; the same backwards with d."""
    n = vlim.size
    ds = length / (n - 1)
    i = np.arange(n)
    w = vlim**2
    w[0] = 0.0
    w = np.minimum.accumulate(w - 2.0 * a * ds * i) + 2.0 * a * ds * i
    w[-1] = 0.0
    j = (n - 1) - i
    w = (np.minimum.accumulate((w - 2.0 * d * ds * j)[::-1]) + 2.0 * d * ds * j[::-1])[::-1]
    return np.sqrt(np.maximum(w, 0.0))


def profile(length: float, vlim: np.ndarray, a: float, d: float, jerk_s: float) -> np.ndarray:
    """Distance covered on the 1 ms grid along a path of `length` whose speed bound on the
    uniform grid `vlim` (first and last point included) is given; starts and ends at rest."""
    n = vlim.size
    ds = length / (n - 1)
    v = _passes(length, vlim, a, d)
    dt = 2.0 * ds / np.maximum(v[1:] + v[:-1], 1e-9)
    t = np.concatenate([[0.0], np.cumsum(dt)])
    m = max(2, math.ceil(t[-1] / DT_REF) + 1)
    # constant acceleration within each grid interval (v^2 linear in s): s(t) is exact there
    tg = np.minimum(np.arange(m) * DT_REF, t[-1])
    i = np.clip(np.searchsorted(t, tg, side="right") - 1, 0, n - 2)
    acc = (v[i + 1] ** 2 - v[i] ** 2) / (2.0 * ds)
    tau = tg - t[i]
    s_t = np.minimum(i * ds + v[i] * tau + 0.5 * acc * tau**2, length)
    vel = np.diff(s_t) / DT_REF
    nj = max(1, round(jerk_s / DT_REF))
    vel = np.convolve(vel, np.ones(nj) / nj)  # bounded jerk; keeps the area (distance)
    s_t = np.concatenate([[0.0], np.cumsum(vel) * DT_REF])
    return s_t * (length / s_t[-1])


def build(segs: list[tuple], lim: Limits, lead_in_mm: float = 0.0, lead_s: float = 0.5) -> Ref:
    """The reference of a run that starts at rest at the origin heading +x.

    lead_in_mm > 0 adds the forward path's straight extension behind the start (a towed or
    following truck starts there). lead_s is the standing time before the first move."""
    parts = []
    x, y, th, s_fwd = 0.0, 0.0, 0.0, 0.0
    geos = []
    if lead_in_mm > 0:
        g = geometry([("line", lead_in_mm)], -lead_in_mm, 0.0, 0.0)
        g[:, 0] -= lead_in_mm
        geos.append(g[:-1])

    def stand(sec: float) -> None:
        k = max(1, round(sec / DT_REF))
        z = np.zeros(k)
        parts.append((z + x, z + y, z + th, z, z, z + s_fwd, z.astype(np.int8)))

    stand(lead_s)
    for kind, mv in _moves(segs):
        if kind == "spin":
            ang = float(mv[0][1])
            L = abs(ang)
            npt = max(3, math.ceil(L / 0.002) + 1)
            a_ = lim.alpha
            prof = profile(L, np.full(npt, lim.w), a_, a_, lim.jerk_s)
            sg = math.copysign(1.0, ang)
            thv = th + sg * prof
            z = np.zeros(prof.size)
            w = sg * np.gradient(prof, DT_REF)
            parts.append((z + x, z + y, thv, z, w, z + s_fwd, z.astype(np.int8) + 2))
            th = float(thv[-1])
        elif kind == "rev":
            L = -float(mv[0][1])
            npt = max(3, math.ceil(L / DS) + 1)
            prof = profile(L, np.full(npt, min(lim.v, lim.v_wheel)), lim.a, lim.d, lim.jerk_s)
            z = np.zeros(prof.size)
            px, py = x - prof * math.cos(th), y - prof * math.sin(th)
            v = -np.gradient(prof, DT_REF)
            parts.append((px, py, z + th, v, z, z + s_fwd, z.astype(np.int8) + 3))
            x, y = float(px[-1]), float(py[-1])
        else:
            g = geometry(mv, x, y, th)
            L, vl = _vlim_fwd(g, lim)
            prof = profile(L, vl, lim.a, lim.d, lim.jerk_s)
            px = np.interp(prof, g[:, 0], g[:, 1])
            py = np.interp(prof, g[:, 0], g[:, 2])
            pt = np.interp(prof, g[:, 0], g[:, 3])
            v = np.gradient(prof, DT_REF)
            w = np.interp(prof, g[:, 0], g[:, 4]) * v
            gg = g.copy()
            gg[:, 0] += s_fwd
            geos.append(gg if not geos else gg[1:])
            parts.append((px, py, pt, v, w, s_fwd + prof, np.zeros(prof.size, np.int8) + 1))
            x, y, th, s_fwd = float(px[-1]), float(py[-1]), float(pt[-1]), s_fwd + L
        stand(lim.pause)
    cols = [np.concatenate([p[i] for p in parts]) for i in range(7)]
    n = cols[0].size
    geo = np.vstack(geos) if geos else None
    return Ref(np.arange(n) * DT_REF, *cols, geo=geo)


def _vlim_fwd(g: np.ndarray, lim: Limits) -> tuple[float, np.ndarray]:
    L = float(g[-1, 0])
    npt = max(3, math.ceil(L / DS) + 1)
    su = np.linspace(0.0, L, npt)
    k = np.abs(np.interp(su, g[:, 0], g[:, 4]))
    vl = np.minimum(lim.v, np.sqrt(lim.a_lat / np.maximum(k, 1e-12)))
    return L, np.minimum(vl, lim.v_wheel / (1.0 + k * lim.b / 2.0))


def duration(segs: list[tuple], lim: Limits, lead_s: float = 0.5) -> float:
    """How long build(segs, lim) lasts (s), without building it."""
    total = lead_s
    x = y = th = 0.0
    for kind, mv in _moves(segs):
        if kind == "spin":
            L = abs(float(mv[0][1]))
            v = _passes(L, np.full(max(3, math.ceil(L / 0.002) + 1), lim.w), lim.alpha, lim.alpha)
        elif kind == "rev":
            L = -float(mv[0][1])
            n = max(3, math.ceil(L / DS) + 1)
            v = _passes(L, np.full(n, min(lim.v, lim.v_wheel)), lim.a, lim.d)
        else:
            g = geometry(mv, x, y, th)
            x, y, th = float(g[-1, 1]), float(g[-1, 2]), float(g[-1, 3])
            L, vl = _vlim_fwd(g, lim)
            v = _passes(L, vl, lim.a, lim.d)
        ds = L / (v.size - 1)
        total += float(np.sum(2.0 * ds / np.maximum(v[1:] + v[:-1], 1e-9))) + lim.jerk_s
        total += lim.pause
    return total


def follow(ref: Ref, back_mm: float) -> Ref:
    """The reference of a truck that keeps back_mm behind along the forward path (a clapper's
    rear truck): its pose is the path's at s - back_mm, its speed the leader's."""
    g = ref.geo
    if g is None or (ref.phase >= 2).any():
        raise ValueError("a follower needs a forward-only path without spins or reversing")
    sb = ref.s - back_mm
    if sb.min() < g[0, 0] - 1e-6:
        raise ValueError("the path's lead-in is shorter than the follower's distance")
    k = np.interp(sb, g[:, 0], g[:, 4])
    return Ref(
        ref.t,
        np.interp(sb, g[:, 0], g[:, 1]),
        np.interp(sb, g[:, 0], g[:, 2]),
        np.interp(sb, g[:, 0], g[:, 3]),
        ref.v.copy(),
        k * ref.v,
        sb,
        ref.phase.copy(),
        g,
    )


# ------------------------------------------------------------------------------------------------
# shapes: every one starts at the origin heading +x
# ------------------------------------------------------------------------------------------------


def square(side: float, ccw: bool, corner_r: float = 0.0) -> list[tuple]:
    """UMBmark square (000 s. 3.5): spot turns (corner_r 0) or arc corners of radius corner_r."""
    sg = 1.0 if ccw else -1.0
    q = sg * math.pi / 2
    if corner_r <= 0:
        return [("line", side), ("spin", q)] * 3 + [("line", side), ("spin", q)]
    return [("line", side - 2 * corner_r), ("arc", corner_r, q)] * 4


def circle(radius: float, ccw: bool, laps: float = 1.0) -> list[tuple]:
    return [("arc", radius, (1 if ccw else -1) * 2 * math.pi * laps)]


def eight(radius: float, ccw_first: bool) -> list[tuple]:
    sg = 1 if ccw_first else -1
    return [("arc", radius, sg * 2 * math.pi), ("arc", radius, -sg * 2 * math.pi)]


def oval(length: float, radius: float, ccw: bool) -> list[tuple]:
    sg = 1 if ccw else -1
    return [("line", length), ("arc", radius, sg * math.pi)] * 2


def outback(length: float, ccw: bool) -> list[tuple]:
    """Out, turn around on the spot, back, turn to the start heading."""
    sg = 1 if ccw else -1
    return [("line", length), ("spin", sg * math.pi), ("line", length), ("spin", sg * math.pi)]


def shuttle(length: float) -> list[tuple]:
    return [("line", length), ("line", -length)]


def spins(angles: list[float]) -> list[tuple]:
    return [("spin", a) for a in angles]


def drive(rng: np.random.Generator, n: int, r_min: float, r_max: float, l_max: float) -> list:
    """A random smooth drive: lines and arcs of random radii, alternating turn directions often
    enough to stay near the start."""
    segs: list[tuple] = []
    heading = 0.0
    for _ in range(n):
        if rng.uniform() < 0.35:
            segs.append(("line", float(rng.uniform(0.3, 1.0) * l_max)))
        else:
            r = float(np.exp(rng.uniform(math.log(r_min), math.log(r_max))))
            mag = float(rng.uniform(math.radians(30), math.radians(150)))
            # steer back towards the start heading band so the drive stays compact
            sg = -math.copysign(1.0, heading) if abs(heading) > 1.5 else float(rng.choice([-1, 1]))
            segs.append(("arc", r, sg * mag))
            heading += sg * mag
    return segs
