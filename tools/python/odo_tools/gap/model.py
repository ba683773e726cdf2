"""The counts-driven model: what the nominal robot (plus one hypothesised effect) says the recorded
wheel counts mean, integrated at the recorded tick (000 Eqs. 2.3-2.5 along the exact arc).

A hypothesis is a dict of effect parameters (catalog names, `effect.param`); absent = nominal.
Every function here is vectorised over ticks; one 2500-tick run dead-reckons in well under 1 ms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .io import Robot, RunData

TIRE_LOAD_KG = 100.0  # tire_compression: k * load is what kinematics sees; load fixed at default


@dataclass
class Prepared:
    """Per-run arrays the model needs, computed once."""

    run: RunData
    t: np.ndarray  # (n,) tick times
    ds: np.ndarray  # (n-1, trucks, 2) nominal wheel travel per tick (mm)
    S: np.ndarray  # (n, trucks, 2) cumulative |travel| per wheel (bump positions)
    b: list[float]
    R: list[float]
    dt: np.ndarray  # (n-1,)
    bumps: list[dict] = field(default_factory=list)  # events placed by the bump hypothesis
    # trucks whose wheels are driven (world.c `driven`: A, and B of a clapper); a set's trailer
    # rolls passively, so the drive effects (slip, skid: world.c step_driven) never act on it
    driven: list[bool] = field(default_factory=lambda: [True, True])
    link: tuple | None = None  # clapper: (l0, alpha0, beta0, l_min, l_max, at_limit) (mm, rad)
    path: str | None = None  # which path the run drove (fit.assign_paths)
    slip_cache: dict = field(default_factory=dict, repr=False)  # slip_loss results by parameters
    track_cache: dict = field(default_factory=dict, repr=False)  # _track results by parameters


def prepare(run: RunData, robot: Robot) -> Prepared:
    c = run.log.counts.astype(np.int64)
    n, T = c.shape[0], c.shape[1]
    ds = np.zeros((n - 1, T, 2))
    for t in range(T):
        bits = robot.trucks[t]["counter_bits"]
        mod, half = 1 << bits, 1 << (bits - 1)
        d = (np.diff(c[:, t, :], axis=0) + half) % mod - half  # counter wraparound
        if robot.trucks[t]["invert_left"]:
            d[:, 0] = -d[:, 0]
        if robot.trucks[t]["invert_right"]:
            d[:, 1] = -d[:, 1]
        ds[:, t, :] = d * robot.mm_per_count(t)
    S = np.concatenate([np.zeros((1, T, 2)), np.cumsum(np.abs(ds), axis=0)])
    return Prepared(
        run,
        run.log.t_s,
        ds,
        S,
        [robot.trucks[t]["wheelbase_mm"] for t in range(T)],
        [0.5 * robot.trucks[t]["wheel_diameter_mm"] for t in range(T)],
        np.diff(run.log.t_s),
        driven=[t == 0 or robot.vehicle == "clapper" for t in range(T)],
        link=_link_start(run, robot),
    )


def _link_start(run: RunData, robot: Robot) -> tuple | None:
    """A clapper's start geometry (its first linkage readings, else straight at its length) and
    the mechanical range of l."""
    if robot.vehicle != "clapper":
        return None
    lg = run.log
    lo, hi = robot.linkage["range_mm"]
    l0 = robot.linkage["length_mm"]
    a0 = b0 = 0.0
    if lg.l_mm is not None and np.isfinite(lg.l_mm[0]):
        l0 = float(lg.l_mm[0])
    if lg.alpha_deg is not None and np.isfinite(lg.alpha_deg[0]):
        a0 = math.radians(float(lg.alpha_deg[0]))
    if lg.beta_deg is not None and np.isfinite(lg.beta_deg[0]):
        b0 = math.radians(float(lg.beta_deg[0]))
    # ticks whose l reading sits at the range's ends (within 1 mm): the clamp is only replayed
    # there, so a start geometry a biased reading misplaces cannot clamp where the robot did not
    gate = None
    if lg.l_mm is not None:
        gate = (lg.l_mm <= lo + LIMIT_TOL_MM) | (lg.l_mm >= hi - LIMIT_TOL_MM)
    return (l0, a0, b0, lo, hi, gate)


LIMIT_TOL_MM = 1.0


# ------------------------------------------------------------------------------------------------
# bump geometry (004 Eqs. 1-5, host_sim/src/bump.c 'exact': pivot about the step's edge)
# ------------------------------------------------------------------------------------------------
def bump_dd(R: float, h: np.ndarray | float) -> np.ndarray:
    """Excess rotation arc over horizontal travel for one whole bump: 2 (R psi0 - D_hor)."""
    h = np.clip(np.asarray(h, dtype=float), 0.0, 0.999 * R)
    return 2.0 * (R * np.arccos(1.0 - h / R) - np.sqrt(np.maximum(2 * R * h - h * h, 0.0)))


def bump_excess(R: float, h: float, s: np.ndarray) -> np.ndarray:
    """Cumulative excess after s mm of rotation arc since first contact (climb, then mirrored)."""
    h = min(max(h, 1e-9), 0.999 * R)
    psi0 = math.acos(1.0 - h / R)
    dhor = math.sqrt(max(2 * R * h - h * h, 0.0))
    half_arc = R * psi0
    e_half = half_arc - dhor
    s = np.clip(s, 0.0, 2 * half_arc)
    climb = lambda x: x - (dhor - R * np.sin(psi0 - x / R))  # noqa: E731
    return np.where(s <= half_arc, climb(s), 2 * e_half - climb(2 * half_arc - s))


# ------------------------------------------------------------------------------------------------
# wheel floor travel under a hypothesis
# ------------------------------------------------------------------------------------------------
def wheel_factors(P: dict, R: float, b: float) -> tuple[float, float]:
    """Floor travel per unit of nominal travel, left and right (ed, es, tyre compression)."""
    ed = P.get("ed.value", 1.0)
    gl, gr = 2.0 / (ed + 1.0), 2.0 / (1.0 / ed + 1.0)  # 000 Eqs. 6.30-6.32
    es = P.get("es.value", 1.0)
    gl, gr = gl / es, gr / es  # 000 App. B
    k = P.get("tire_compression.k_mm_per_kg", 0.0)
    if k:
        off = P.get("tire_compression.lateral_offset_mm", 0.0)
        m = P.get("tire_compression.load_kg", TIRE_LOAD_KG)
        gl *= (R - k * m * (0.5 * b + off) / b) / R
        gr *= (R - k * m * (0.5 * b - off) / b) / R
    return gl, gr


def rough_moments(R: float, hmax: float, n: int = 64) -> tuple[float, float]:
    """Mean and mean square of one roughness grain's excess, heights uniform in [0, hmax]."""
    u = (np.arange(n) + 0.5) / n * hmax
    dd = bump_dd(R, u)
    return float(dd.mean()), float((dd * dd).mean())


def rough_window_var(R: float, hmax: float, L: np.ndarray, n: int = 32) -> tuple:
    """Per-grain E[dd^2 q] and E[q] over heights uniform in [0, hmax] for windows of L mm of travel.

    A grain spreads its excess over its horizontal span s = 2 sqrt(2 R h - h^2); a window cuts the
    grains at its ends, so of a grain starting at a uniform phase it sees the fraction f, and
    E[f^2] L = L - s / 3 (s <= L) or L^2 (s - L / 3) / s^2 (s > L). q = E[f^2] (per grain and
    window: the window's variance is lambda L E[dd^2 q] instead of lambda L E[dd^2])."""
    u = (np.arange(n) + 0.5) / n * hmax
    dd = bump_dd(R, u)
    s = 2.0 * np.sqrt(np.maximum(2 * R * u - u * u, 0.0))  # (n,)
    Lc = np.maximum(np.asarray(L, dtype=float), 1e-9)[:, None]
    q = np.where(s <= Lc, 1.0 - s / (3.0 * Lc), Lc * (s - Lc / 3.0) / np.maximum(s, 1e-12) ** 2)
    return (dd * dd * q).mean(axis=1), (dd * q).mean(axis=1), q.mean(axis=1)


def floor_travel(pr: Prepared, P: dict, truck: int) -> tuple[np.ndarray, float, np.ndarray]:
    """(n-1, 2) floor travel per tick, true wheelbase, (n-1,) lateral skid per tick (mm)."""
    ds = pr.ds[:, truck, :].copy()
    R, b = pr.R[truck], pr.b[truck]
    gl, gr = wheel_factors(P, R, b)
    ds[:, 0] *= gl
    ds[:, 1] *= gr
    hr = P.get("roughness.max_height_mm", 0.0)
    if hr > 0:
        m1, _ = rough_moments(R, hr)
        # grains are laid per mm of the wheel's horizontal progress (world.c reach_bumps advances
        # the odometer by `hor`): rotation = floor (1 + m1 / spacing), not floor = rotation (1 - ..)
        ds /= 1.0 + m1 / P.get("roughness.spacing_mm", 20.0)
    drive = pr.driven[truck]
    k = P.get("slip.k_per_m_s2", 0.0) if drive else 0.0
    if k > 0:
        ds += slip_loss(pr, P, truck, k)
    for ev in pr.bumps:
        if ev["truck"] != truck:
            continue
        w = ev["wheel"]
        S = pr.S[:, truck, w]
        # the excess only grows while the wheel's travel is inside the bump's span
        h = min(max(ev["h"], 1e-9), 0.999 * R)
        span = 2.0 * R * math.acos(1.0 - h / R)
        i0 = max(int(np.searchsorted(S, ev["s0"], side="right")) - 1, 0)
        i1 = min(int(np.searchsorted(S, ev["s0"] + span, side="left")), S.size - 1)
        if i1 <= i0:
            continue
        e = bump_excess(R, ev["h"], S[i0 : i1 + 1] - ev["s0"])
        ds[i0:i1, w] -= np.sign(pr.ds[i0:i1, truck, w]) * np.diff(e)
    bt = b * P.get("eb.value", 1.0)
    lat = np.zeros(ds.shape[0])
    ks = P.get("skid.k_s", 0.0) if drive else 0.0
    if ks > 0:
        v = 0.5 * (ds[:, 0] + ds[:, 1]) / pr.dt
        om = (ds[:, 1] - ds[:, 0]) / bt / pr.dt
        ac = v * om * 1e-3
        ex = np.maximum(np.abs(ac) - P.get("skid.a0_m_s2", 0.3), 0.0)
        lat = -np.sign(ac) * ks * ex * 1e3 * pr.dt
    return ds, bt, lat


SLIP_SUB_S = 0.001  # sub-step of the slip integral (the catalog's law acts per physics step)


def drive_commands(v: np.ndarray, tau: float, M: int) -> tuple[np.ndarray, np.ndarray]:
    """The per-tick commands c and the drive's speed m at each tick's start behind the recorded
    mean speeds v (n, ...), for a drive that follows a command held over a tick of M sub-steps
    with a first-order lag: per sub-step speed += (c - speed) g, g = 1 - exp(-sub / tau)
    (host_sim world.c step_driven). Over a tick the mean is v_k = (1 - f) c_k + f m_k with
    f = mean of q^j (j = 1..M, q = 1 - g), and m_(k+1) = (1 - Q) c_k + Q m_k with Q = q^M: an LTI
    filter from c to v, inverted exactly (the drive starts at rest). Taking v_k - v_(k-1) as the
    command step, as before, split one step over two ticks ((1 - f) D, then f D): at the corners
    of a 7 x 4 m rectangle the slip law's cap and threshold then lost 0.25 deg per corner."""
    from scipy.signal import lfilter

    q = math.exp(-SLIP_SUB_S / tau)
    f = float(np.mean(q ** np.arange(1, M + 1)))
    Q = q**M
    c = lfilter([1.0, -Q], [1.0 - f, f * (1.0 - Q) - (1.0 - f) * Q], v, axis=0)
    m = lfilter([0.0, 1.0 - Q], [1.0, -Q], c, axis=0)
    return c, m


def slip_loss(pr: Prepared, P: dict, truck: int, k: float) -> np.ndarray:
    """(n-1, 2) floor travel the slip law adds per tick (negative: the wheel spun).

    The catalog's law (host_sim/src/world.c slip_factor) acts on the acceleration of the drive
    over each 1 ms physics step. A count over a whole tick cannot see that step, but the tick's
    command can be recovered behind the recorded mean speeds (`drive_commands`) for a drive with
    lag tau (slip.tau_s, a nuisance fitted with k; the blind check hides 2-8 ms), and the speed
    in every sub-step follows from it: slip fraction x speed is integrated sub-step by sub-step,
    spinning where the speed grows and dragging where it shrinks (a reversing wheel does both in
    one tick)."""
    tau = max(P.get("slip.tau_s", 0.004), 1e-4)
    a0 = P.get("slip.a0_m_s2", 0.5)
    cap = P.get("slip.max_fraction", 0.2)
    key = (truck, k, tau, a0, cap)
    hit = pr.slip_cache.get(key)
    if hit is not None:  # fits re-evaluate one (k, tau) for every other parameter they move
        return hit
    M = max(1, round(float(np.median(pr.dt)) / SLIP_SUB_S))
    v = pr.ds[:, truck, :] / pr.dt[:, None]  # mm/s, mean over each tick
    c, m0 = drive_commands(v, tau, M)
    g = 1.0 - math.exp(-SLIP_SUB_S / tau)
    out = np.zeros_like(v)
    # only ticks whose first (largest) sub-step acceleration exceeds a0 slip at all
    a_first = np.abs(c - m0) * (g / SLIP_SUB_S * 1e-3)
    sel = a_first > a0
    if sel.any():
        # the acceleration decays by q = 1 - g per sub-step: beyond J sub-steps none exceeds a0
        J = M
        if a0 > 0.0:
            J = int(min(M, 1 + math.ceil(math.log(a0 / a_first[sel].max()) / math.log(1.0 - g))))
        out[sel] = _slip_substeps(c[sel], m0[sel], g, J, k, a0, cap)
    if len(pr.slip_cache) > 16:
        pr.slip_cache.clear()
    pr.slip_cache[key] = out
    return out


def _slip_substeps(c, m0, g, J, k, a0, cap) -> np.ndarray:
    """Slip travel of the first J sub-steps of the selected ticks (see slip_loss)."""
    cs, ms = c[:, None], m0[:, None]
    qj = (1.0 - g) ** np.arange(J + 1)  # (J + 1,): sub-step j = 0 is the tick's start
    vm = cs + (ms - cs) * qj  # (nsel, M + 1) speed after each sub-step
    acc = np.abs(np.diff(vm, axis=1)) / SLIP_SUB_S * 1e-3  # m/s^2
    sfr = np.minimum(k * np.maximum(acc - a0, 0.0), cap)
    up = np.abs(vm[:, 1:]) >= np.abs(vm[:, :-1])
    per = np.where(up, -sfr, sfr / (1.0 - sfr)) * vm[:, 1:] * SLIP_SUB_S
    return per.sum(axis=-1)


def integrate(ds: np.ndarray, b: float, lat: np.ndarray, pose0=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Dead reckoning along the exact arc of each tick; returns (n, 3) x, y, theta."""
    d = 0.5 * (ds[:, 0] + ds[:, 1])
    dth = (ds[:, 1] - ds[:, 0]) / b
    th = pose0[2] + np.concatenate([[0.0], np.cumsum(dth)])
    half = 0.5 * dth
    with np.errstate(invalid="ignore", divide="ignore"):
        chord = np.where(np.abs(half) > 1e-9, d * np.sin(half) / np.where(half == 0, 1, half), d)
    mid = th[:-1] + half
    dx = chord * np.cos(mid) - lat * np.sin(mid)
    dy = chord * np.sin(mid) + lat * np.cos(mid)
    x = pose0[0] + np.concatenate([[0.0], np.cumsum(dx)])
    y = pose0[1] + np.concatenate([[0.0], np.cumsum(dy)])
    return np.column_stack([x, y, th])


def _track(pr: Prepared, P: dict, truck: int) -> np.ndarray:
    """One truck's dead-reckoned track from the origin under P (cached per run: a clapper's
    clamp needs both trucks for each, and fits ask for each truck in turn)."""
    key = (
        truck,
        tuple(sorted(P.items())),
        tuple((b["truck"], b["wheel"], b["s0"], b["h"]) for b in pr.bumps),
    )
    hit = pr.track_cache.get(key)
    if hit is None:
        if len(pr.track_cache) > 8:
            pr.track_cache.clear()
        hit = pr.track_cache[key] = integrate(*floor_travel(pr, P, truck))
    return hit


def dead_reckon(pr: Prepared, P: dict, truck: int = 0, pose0=(0.0, 0.0, 0.0)) -> np.ndarray:
    if tuple(pose0) == (0.0, 0.0, 0.0):
        p = _track(pr, P, truck)
    else:
        p = integrate(*floor_travel(pr, P, truck), pose0)
    if pr.link is None or len(pr.R) < 2:
        return p.copy()
    return _clamp_link(pr, p, _track(pr, P, 1 - truck), truck, pose0)


def _clamp_link(pr: Prepared, p: np.ndarray, q: np.ndarray, truck: int, pose0) -> np.ndarray:
    """A clapper's l stays within its mechanical range: world.c clamp_link pushes both trucks
    equally along the link when it would leave it (motion the wheels never see, e.g. when slip
    lets the trucks drift 100 mm apart on rect-7x4). Tracks that never leave the range come back
    unchanged; otherwise the clamp is replayed per tick from the first violation. `p` is
    `truck`'s track (from pose0), `q` the other truck's (from the origin)."""
    l0, a0, b0, lo, hi, gate = pr.link
    th_link = -a0  # A at the origin, heading 0; alpha = A's heading - the link's
    B0 = (-l0 * math.cos(th_link), -l0 * math.sin(th_link), th_link + b0)
    A0 = (0.0, 0.0, 0.0)

    def place(tr: np.ndarray, start: tuple, at: tuple) -> np.ndarray:
        # rigid move of a track that started at `start` so that it starts at `at`
        d = at[2] - start[2]
        c, s_ = math.cos(d), math.sin(d)
        x, y = tr[:, 0] - start[0], tr[:, 1] - start[1]
        return np.column_stack([at[0] + c * x - s_ * y, at[1] + s_ * x + c * y, tr[:, 2] + d])

    p0 = tuple(pose0)
    pa = place(p, p0, A0) if truck == 0 else place(q, A0, A0)
    pb = place(q, A0, B0) if truck == 0 else place(p, p0, B0)
    ln = np.hypot(pa[:, 0] - pb[:, 0], pa[:, 1] - pb[:, 1])
    out_of = (ln < lo) | (ln > hi)
    if gate is not None:
        out_of &= gate[: ln.size]
    bad = np.flatnonzero(out_of)
    if bad.size == 0:
        return p.copy()
    i0 = max(int(bad[0]), 1)
    da, db = np.diff(pa[:, :2], axis=0), np.diff(pb[:, :2], axis=0)
    xa, ya = float(pa[i0 - 1, 0]), float(pa[i0 - 1, 1])
    xb, yb = float(pb[i0 - 1, 0]), float(pb[i0 - 1, 1])
    push = np.zeros((pa.shape[0], 2))  # cumulative push of truck A (B: the opposite)
    ox = oy = 0.0
    for i in range(i0, pa.shape[0]):
        xa += da[i - 1, 0]
        ya += da[i - 1, 1]
        xb += db[i - 1, 0]
        yb += db[i - 1, 1]
        dx, dy = xa - xb, ya - yb
        li = math.hypot(dx, dy)
        if (li < lo or li > hi) and (gate is None or gate[i]):
            half = 0.5 * ((lo if li < lo else hi) - li)
            ux, uy = (dx / li, dy / li) if li > 0 else (1.0, 0.0)
            xa += half * ux
            ya += half * uy
            xb -= half * ux
            yb -= half * uy
            ox += half * ux
            oy += half * uy
        push[i] = (ox, oy)
    sgn = 1.0 if truck == 0 else -1.0
    d = p0[2] - (A0 if truck == 0 else B0)[2]  # back into the track's own frame
    c, s_ = math.cos(d), math.sin(d)
    out = p.copy()
    out[:, 0] += sgn * (c * push[:, 0] - s_ * push[:, 1])
    out[:, 1] += sgn * (s_ * push[:, 0] + c * push[:, 1])
    return out


def link_bias(P: dict, alpha: np.ndarray, beta: np.ndarray) -> tuple:
    """What rotary_bias / link_bias add to the true linkage readings (deg, deg, mm)."""
    ba = P.get("rotary_bias.alpha_deg", 0.0)
    bb = P.get("rotary_bias.beta_deg", 0.0)
    bl = P.get("link_bias.const_mm", 0.0) + P.get("link_bias.ecc_mm", 0.0) * (
        1 - np.cos(alpha - beta)
    )
    return ba, bb, bl


def wrap_deg(a: np.ndarray) -> np.ndarray:
    return (np.asarray(a) + 180.0) % 360.0 - 180.0


def wrap_rad(a: np.ndarray) -> np.ndarray:
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi
