"""Nuisances of a truth track, estimated from the data before any hypothesis is fitted.

A motion-capture track is not the axle centre at the robot's clock: the marker sits somewhere on
the body (a lever arm of up to a few cm), and the two clocks are offset (latency, often different
per run). Both move the truth in ways no catalog effect should be asked to explain:

- **Lever arm** (per truck, x forward and y left of the axle centre): on a turn on the spot the
  centre stays put while the marker circles it, so the marker's increments there are
  (R(dtheta) - I) o, linear in o, with the measured heading change. Fitted on those windows only
  (on arcs an Eb or a scrub misfit is correlated with it); without spot turns it is left at zero
  and the report says so.
- **Latency** (per run): the time shift that best lines the truth's track up with the model's
  (a latency leaves the truth v L behind while moving, an effect's error grows with distance);
  kept where it lowers the track's misfit by 10 % and is at least half a count tick (below that
  it is inside the counts' own timing, and slip on a turn's start mimics it).

The OptiOdom circles carry ~0.1-0.3 s of latency between mocap and wheel counts (their heading
misfit follows the turn rate), the squares ~25 ms; the lever arm of its marker is ~1-2 cm.
"""

from __future__ import annotations

import math

import numpy as np

from .model import Prepared, dead_reckon
from .modes import ANCHOR_S, WINDOW_S, Instrument, _body_inc, to_centre

LATENCY_MAX_S = 0.5
LEVER_MIN_WINDOWS = 10
LEVER_SIGNIFICANT = 3.0  # |o| in standard errors below which the lever arm is left at zero
SPOT_TURN_RAD = 0.05  # a window turning at least this much ...
SPOT_TRAVEL = 0.1  # ... while its centre moves less than this x (b/2) x |dtheta|
TURN_RAD = 0.02  # without spot turns: every window that turns this much (arcs of both ways)


def estimate(prs: list[Prepared], trucks: int) -> tuple[Instrument, list[str]]:
    """(instrument, notes for the report) from the runs that have a truth track. The latency
    and the lever arm are estimated in turn, twice: each blurs the other (the independent
    world's 25 mm marker left its 27 ms latency within the 10 % a shift must gain)."""
    inst = Instrument(lever_mm=[(0.0, 0.0)] * trucks, lever_se_mm=[(0.0, 0.0)] * trucks)
    with_truth = [pr for pr in prs if pr.run.truth is not None]
    for _ in range(2):
        notes = []
        found = {pr.run.name: latency(pr, lever=inst.lever_mm[0]) for pr in with_truth}
        inst.latency_s.update(session_latencies(with_truth, found))
        for t in range(trucks):
            o, se, n = lever_arm(with_truth, t, inst)
            if o is None:
                notes.append(
                    f"truck {'AB'[t]}: lever arm of the tracked point not estimated ({n} "
                    "windows turning on the spot; needs 10): taken as zero"
                )
                continue
            inst.lever_se_mm[t] = se
            inst.lever_mm[t] = o if significant(o, se) else (0.0, 0.0)
    return inst, notes


def under(inst: Instrument, prs: list[Prepared], P: dict) -> Instrument:
    """The instrument with each run's latency estimated again under a candidate P, without the
    half-tick floor: once the candidate takes its own share of the heading misfit where the rate
    changes (slip does; a kinematic effect does not), what is left of a shift is the clock. The
    OptiOdom squares' ~25 ms, half their 50 ms tick, read as the truth's noise otherwise."""
    out = Instrument(list(inst.lever_mm), list(inst.lever_se_mm), dict(inst.latency_s))
    with_truth = [pr for pr in prs if pr.run.truth is not None]
    found = {
        pr.run.name: latency(pr, 0, P, min_tick=0.0, lever=inst.lever_mm[0]) for pr in with_truth
    }
    out.latency_s.update(session_latencies(with_truth, found))
    return out


def on_arcs(
    inst: Instrument, prs: list[Prepared], truck: int, P: dict
) -> tuple[tuple[float, float] | None, tuple[float, float], int]:
    """The lever arm where the robot never turns on the spot: on arcs of both directions, under a
    candidate P for the robot's geometry (the caller's preliminary kinematic fit). On an arc the
    marker's increments differ from the centre's by (R(dtheta) - I) o: a forward offset moves
    them sideways, a sideways one along - with arcs of both directions neither is a scale error
    or a skid. Without it the independent world's 30 mm markers read as roughness at its bound."""
    with_truth = [pr for pr in prs if pr.run.truth is not None]
    return lever_arm(with_truth, truck, inst, P, arcs=True)


def significant(o, se) -> bool:
    z = math.hypot(o[0] / max(se[0], 1e-9), o[1] / max(se[1], 1e-9))
    return z >= LEVER_SIGNIFICANT and math.hypot(*o) >= 1.0


def _windows(tt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    dt = float(np.median(np.diff(tt)))
    W = max(1, round(WINDOW_S / dt))
    i = np.arange(0, tt.size - W, W)
    return i, i + W


def _mad(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x)))) if x.size else 0.0


def latency(
    pr: Prepared,
    truck: int = 0,
    P: dict | None = None,
    min_tick: float = 0.5,
    lever: tuple[float, float] = (0.0, 0.0),
) -> float:
    """The shift (s) that best lines the truth's track up with the model's (P, nominal by
    default), or 0 when it does not lower the track's misfit by 10 % or is shorter than
    `min_tick` count ticks.

    A latency leaves the truth behind by v L wherever the robot moves and nowhere when it stands,
    an effect of the robot's (a scale error, a slip's loss) grows with the distance: the track
    separates them where the windows' increments, which see a latency only where the speed
    changes, did not (on the independent world's squares they said 37 ms where the track wants
    50 ms, and the rest was taken for an effect)."""
    tr = pr.run.truth
    p = dead_reckon(pr, P or {}, truck)
    tt = tr.t_s
    tp = to_centre(tr.pose[:, truck : truck + 1], [lever])[:, 0]

    def rms(L: float) -> float:
        tm = tt - L
        ok = (tm >= pr.t[0]) & (tm <= pr.t[-1])
        if ok.sum() < 20:
            return float("inf")
        t_, q = tm[ok], tp[ok]
        m = np.column_stack([np.interp(t_, pr.t, p[:, k]) for k in range(3)])
        k0 = t_ <= t_[0] + ANCHOR_S
        th0 = float(np.mean(q[k0, 2] - m[k0, 2]))
        c, s_ = math.cos(th0), math.sin(th0)
        x = c * m[:, 0] - s_ * m[:, 1]
        y = s_ * m[:, 0] + c * m[:, 1]
        x += float(np.mean(q[k0, 0] - x[k0]))
        y += float(np.mean(q[k0, 1] - y[k0]))
        return float(np.sqrt(np.mean((x - q[:, 0]) ** 2 + (y - q[:, 1]) ** 2)))

    coarse = np.arange(-LATENCY_MAX_S, LATENCY_MAX_S + 1e-9, 0.01)
    cost = np.array([rms(L) for L in coarse])
    k = int(np.argmin(cost))
    if k in (0, coarse.size - 1):  # no minimum inside: a run that barely moves (a spin)
        return None
    fine = np.arange(coarse[k] - 0.01, coarse[k] + 0.01 + 1e-9, 0.001)
    fc = np.array([rms(L) for L in fine])
    L = float(fine[int(np.argmin(fc))])
    base = rms(0.0)
    if not np.isfinite(base) or fc.min() > 0.9 * base:
        return None
    if abs(L) < min_tick * float(np.median(pr.dt)):
        return 0.0
    return L


def session_latencies(prs: list[Prepared], found: dict[str, float | None]) -> dict[str, float]:
    """A run whose track does not fix its latency (a spin, a run an effect dominates) takes the
    median of its session's runs that do: the clock offset is the rig's (the independent
    world's squares with slip said nothing, its circles 30-37 ms, a spin 0.5 s at the grid's
    edge)."""
    out = {}
    for pr in prs:
        name = pr.run.name
        if found.get(name) is not None:
            out[name] = float(found[name])
            continue
        same = [found[p.run.name] for p in prs if p.run.session == pr.run.session]
        valid = [x for x in same if x is not None]
        out[name] = float(np.median(valid)) if valid else 0.0
    return out


def lever_arm(
    prs: list[Prepared], truck: int, inst: Instrument, P: dict | None = None, arcs: bool = False
) -> tuple[tuple[float, float] | None, tuple[float, float], int]:
    """Least squares of the marker's increments on spot turns (or, with `arcs`, on every window
    that turns at least TURN_RAD, the model under P): ((ox, oy), (se_x, se_y), windows)."""
    A_rows, r_rows = [], []
    for pr in prs:
        tr = pr.run.truth
        if truck >= tr.pose.shape[1]:
            continue
        tt = tr.t_s - inst.latency_s.get(pr.run.name, 0.0)
        i, j = _windows(tt)
        ok = (tt[i] >= pr.t[0]) & (tt[j] <= pr.t[-1])
        i, j = i[ok], j[ok]
        if i.size == 0:
            continue
        p = dead_reckon(pr, P or {}, truck)
        m = np.column_stack([np.interp(tt, pr.t, p[:, k]) for k in range(3)])
        inc_t = _body_inc(tr.pose[:, truck], i, j)
        inc_m = _body_inc(m, i, j)
        dth = inc_t[:, 2]
        travel = np.hypot(inc_m[:, 0], inc_m[:, 1])
        if arcs:
            spot = np.abs(dth) >= TURN_RAD
        else:
            spot = (np.abs(dth) >= SPOT_TURN_RAD) & (
                travel < SPOT_TRAVEL * 0.5 * pr.b[truck] * np.abs(dth)
            )
        if not spot.any():
            continue
        c, s_ = np.cos(dth[spot]), np.sin(dth[spot])
        # (R(dtheta) - I) o, rows for x and y
        A = np.stack(
            [np.column_stack([c - 1.0, -s_]), np.column_stack([s_, c - 1.0])], axis=1
        ).reshape(-1, 2)
        r = (inc_t[spot, :2] - inc_m[spot, :2]).reshape(-1)
        A_rows.append(A)
        r_rows.append(r)
    n = sum(a.shape[0] // 2 for a in A_rows)
    if n < LEVER_MIN_WINDOWS:
        return None, (0.0, 0.0), n
    A, r = np.vstack(A_rows), np.concatenate(r_rows)
    w = np.ones(r.size)
    o = np.zeros(2)
    for _ in range(5):  # Huber-weighted: a bump on a turn must not pull the marker around
        Aw = A * w[:, None]
        o = np.linalg.lstsq(Aw, r * w, rcond=None)[0]
        e = r - A @ o
        s = max(_mad(e), 1e-6)
        w = np.sqrt(np.minimum(1.0, 1.5 * s / np.maximum(np.abs(e), 1e-12)))
    e = r - A @ o
    s2 = float(np.sum((w * e) ** 2) / max(r.size - 2, 1))
    cov = np.linalg.pinv((A * w[:, None]).T @ (A * w[:, None])) * s2
    se = (float(math.sqrt(max(cov[0, 0], 0.0))), float(math.sqrt(max(cov[1, 1], 0.0))))
    return (float(o[0]), float(o[1])), se, n
