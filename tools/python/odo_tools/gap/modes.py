"""The three evidence modes: residuals of the counts-driven model against what was recorded.

- truth:   windowed increments (longitudinal, lateral, heading per truck; linkage readings against
           the true linkage) of the model vs a continuous ground-truth track. Local increments do
           not accumulate drift, so windows are close to independent and a likelihood is honest.
- returns: the true return pose of each run (returns.csv, 000 Eq. 3.1) vs where the model ends.
- linkage: no truth at all: from the linkage state measured at a window's start, dead-reckon both
           trucks (or truck and trailer) by their counts over the window and compare the linkage
           the model predicts at its end with what the encoders read (clapper, set).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from .io import Robot
from .model import (
    Prepared,
    TrackAt,
    dead_reckon,
    interp_track,
    link_bias,
    rough_moments,
    rough_window_var,
    truck_view,
    wrap_rad,
)

WINDOW_S = 0.4  # truth increments: window length
HORIZON_S = 1.0  # linkage mode: prediction horizon
QUANT_DRAWS = 64  # linkage mode: draws of the instruments' quantisation per run
ANCHOR_S = 2.0  # truth mode: the start pose is fitted over this much of the run


class EvidenceMode(Protocol):
    """What every evidence mode offers the fits, the held-out evaluation and the plots. One
    object per run; `P` is a hypothesis (catalog parameters 'effect.param', absent = nominal)."""

    name: str
    pr: Prepared

    def channels(self) -> list[str]:
        """Names of the residual columns, with units in the suffix."""
        ...

    def residuals(self, P: dict) -> np.ndarray:
        """(rows, channels) recorded minus model."""
        ...

    def extra_var(self, P: dict) -> np.ndarray | None:
        """Variance a hypothesis adds to each residual (roughness), or None."""
        ...

    def own_var(self, sigma: np.ndarray) -> np.ndarray | None:
        """Variance this run's own geometry adds to each residual beyond sigma^2, whatever the
        hypothesis (returns: the start placement's heading over the run's reach), or None."""
        ...

    def noise_weights(self) -> np.ndarray:
        """Expected z^2 per value of each channel under noise alone."""
        ...

    def sys_z(self, P: dict, sigma: np.ndarray) -> np.ndarray:
        """Standardised residuals of the held-out gap (diagnose: systematic gap)."""
        ...

    def gap(self, P: dict) -> float:
        """The gap a person reads, in mm."""
        ...


def _body_inc(p: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    dx, dy = p[j, 0] - p[i, 0], p[j, 1] - p[i, 1]
    c, s = np.cos(p[i, 2]), np.sin(p[i, 2])
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, p[j, 2] - p[i, 2]])


def _censored(x: np.ndarray, code: np.ndarray, step: float, angle: bool) -> np.ndarray:
    """Residual of a truncating encoder: code k means the measured value lies in [k, k + step).

    The residual is how far the model's value x lies outside that cell (reading minus model,
    zero inside): interval-censored data. Replacing the cell by its centre is biased whenever the
    value rests for a while, e.g. a straight linkage at exactly 0 reads code 0 with zero error,
    not half a step (that bias was the clapper/set false alarm)."""
    d = x - code
    if angle:
        d = wrap_rad(d)
    tol = 1e-9 * max(step, 1.0) + 1e-7 * step
    return np.clip(d, -tol, step + tol) - d


def to_centre(
    pose: np.ndarray, lever_mm: list[tuple[float, float]], heading_offset_rad=None
) -> np.ndarray:
    """Tracked-point poses (n, trucks, 3) -> axle-centre poses: take the marker body's heading
    offset off the measured heading, then subtract the lever arm (x forward, y left, mm) rotated
    by that heading."""
    out = pose.copy()
    for t, o in enumerate(heading_offset_rad or []):
        if t < pose.shape[1] and o:
            out[:, t, 2] -= o
    for t in range(pose.shape[1]):
        ox, oy = lever_mm[t] if t < len(lever_mm) else (0.0, 0.0)
        if ox == 0.0 and oy == 0.0:
            continue
        c, s_ = np.cos(out[:, t, 2]), np.sin(out[:, t, 2])
        out[:, t, 0] -= c * ox - s_ * oy
        out[:, t, 1] -= s_ * ox + c * oy
    return out


def on_ticks(tt: np.ndarray, t: np.ndarray) -> bool:
    """Whether every time of tt (s) falls on one of the count ticks t (within 1 us)."""
    if tt.size == 0:
        return True
    k = np.clip(np.searchsorted(t, tt), 1, t.size - 1)
    return bool(np.all(np.minimum(np.abs(tt - t[k - 1]), np.abs(tt - t[k])) <= 1e-6))


def spot_ticks(pr: Prepared) -> np.ndarray:
    """(n-1, trucks): ticks whose wheels roll opposite ways (a turn on the spot)."""
    return (pr.ds[:, :, 0] * pr.ds[:, :, 1]) < 0.0


def link_from_poses(pose: np.ndarray, robot: Robot) -> np.ndarray:
    """(n, 3) alpha, beta (rad), l (mm) of a clapper (theta_L from B to A, 002 Eqs. 10, 11 as
    host_sim's world.c) or alpha and the bar length of a set (alpha = theta_A - theta_trailer),
    from the trucks' poses (n, 2, 3)."""
    a, b = pose[:, 0], pose[:, 1]
    if robot.vehicle == "clapper":
        thl = np.arctan2(a[:, 1] - b[:, 1], a[:, 0] - b[:, 0])
        return np.column_stack(
            [
                wrap_rad(a[:, 2] - thl),
                wrap_rad(b[:, 2] - thl),
                np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1]),
            ]
        )
    L = robot.trailer.get("trailer_length_mm", 0.0)
    return np.column_stack(
        [wrap_rad(a[:, 2] - b[:, 2]), np.zeros(a.shape[0]), np.full(a.shape[0], L)]
    )


def _at_times(t: np.ndarray, link: np.ndarray, tq: np.ndarray) -> np.ndarray:
    """The linkage track (n, 3: two angles in rad, a length in mm) sampled at t, interpolated to
    the times tq (the angles unwrapped first)."""
    x = link.copy()
    x[:, :2] = np.unwrap(link[:, :2], axis=0)
    return interp_track(tq, t, x)


def _sample_noise(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Per column of x (n, k): white noise sigma of the samples, from second divided differences
    (robust: a median)."""
    h1, h2 = np.diff(t)[:-1], np.diff(t)[1:]
    ok = (h1 > 0) & (h2 > 0)
    if ok.sum() < 10:
        return np.zeros(x.shape[1])
    h1, h2 = h1[ok], h2[ok]
    w0, w2 = 1.0 / h1, 1.0 / h2
    w1 = w0 + w2
    d = (w2[:, None] * x[2:][ok] - w1[:, None] * x[1:-1][ok] + w0[:, None] * x[:-2][ok]) * np.sqrt(
        6.0 / (w0 * w0 + w1 * w1 + w2 * w2)
    )[:, None]
    med = np.median(d, axis=0)
    return 1.4826 * np.median(np.abs(d - med), axis=0) / math.sqrt(6.0)


def _grain_count_cv2(P: dict) -> float:
    """Squared coefficient of variation of the grain count: gaps spacing * (1 + jitter U(-1, 1))
    make a renewal count of variance n cv^2, cv^2 = jitter^2 / 3."""
    return P.get("roughness.jitter", 0.5) ** 2 / 3.0


@dataclass
class Instrument:
    """How the truth was measured, beyond its noise: where the tracked point sits on each truck
    (x forward, y left of the axle centre, mm) and how late each run's truth is against the
    robot's clock (s; the truth sample stamped t shows the pose at t - latency). Nuisances of the
    truth, estimated from the data (instrument.estimate), never part of a hypothesis."""

    lever_mm: list[tuple[float, float]] = field(default_factory=lambda: [(0.0, 0.0)] * 2)
    lever_se_mm: list[tuple[float, float]] = field(default_factory=lambda: [(0.0, 0.0)] * 2)
    latency_s: dict[str, float] = field(default_factory=dict)
    # per truck: the marker body's heading against the truck's (rad; measured = true + offset)
    heading_offset_rad: list[float] = field(default_factory=lambda: [0.0, 0.0])
    # per truck: the standard error of that offset (rad; 0 where it was not measured)
    heading_offset_se_rad: list[float] = field(default_factory=lambda: [0.0, 0.0])
    # one clock for every run was looked for under a slip candidate (diagnose._slip_not_latency)
    clock_scanned: bool = False
    # the one clock that scan gave every run (s), None where it kept the runs' own
    clock_s: float | None = None

    def copy(self) -> Instrument:
        return Instrument(
            list(self.lever_mm), list(self.lever_se_mm), dict(self.latency_s),
            list(self.heading_offset_rad), list(self.heading_offset_se_rad),
            self.clock_scanned, self.clock_s,
        )  # fmt: skip


class TruthMode:
    name = "truth"
    gof = True  # its noise is measured per sample (TruthMode.noise_diffs): a fit test holds

    def __init__(self, pr: Prepared, robot: Robot, instrument: Instrument | None = None) -> None:
        tr = pr.run.truth
        assert tr is not None
        self.pr, self.robot = pr, robot
        inst = instrument or Instrument()
        lat = inst.latency_s.get(pr.run.name, 0.0)
        t_true = tr.t_s - lat
        t0, t1 = max(t_true[0], pr.t[0]), min(t_true[-1], pr.t[-1])
        sel = (t_true >= t0 - 1e-9) & (t_true <= t1 + 1e-9)
        if sel.sum() < 10:
            raise ValueError(f"{pr.run.name}: fewer than 10 truth samples overlap the log")
        self.tt = t_true[sel]
        self.tpose = to_centre(tr.pose[sel], inst.lever_mm, inst.heading_offset_rad)
        # the true linkage from the two trucks' (centre) poses, with the same lever arms and
        # latency as the trucks: a linkage column the motion capture derived from its markers
        # carries their lever arms as offsets a rotary or link-length bias would take up (the
        # independent world's clapper); the simulator's exact columns agree with this to the
        # truth's noise
        self.tlink = link_from_poses(self.tpose, robot) if tr.link is not None else None
        dt = float(np.median(np.diff(self.tt)))
        W = max(1, round(WINDOW_S / dt))
        self.i = np.arange(0, self.tt.size - W, W)
        self.j = self.i + W
        self.trucks = robot.n_trucks
        self.tinc = [_body_inc(self.tpose[:, t], self.i, self.j) for t in range(self.trucks)]
        # the windows' end samples: the residuals need the model there only (np.interp is
        # pointwise, so interpolating at these alone gives the same numbers, W times cheaper)
        self._ends = np.union1d(self.i, self.j)
        self._ie = np.searchsorted(self._ends, self.i)
        self._je = np.searchsorted(self._ends, self.j)
        # whether every truth sample (after its latency) falls on a count tick: the model is
        # then compared where it is known, with no interpolation between ticks
        self.exact = on_ticks(self.tt, pr.t)
        # the model at the truth's samples and at the windows' ends (model.TrackAt): between
        # ticks a cubic through them; a truth taken at the ticks needs no interpolation
        self._at_all = TrackAt(self.tt, pr.t, self.exact)
        self._at_ends = TrackAt(self.tt[self._ends], pr.t, self.exact)
        lg = pr.run.log
        self.has_link = self.tlink is not None and lg.alpha_deg is not None
        bits = robot.linkage.get("rotary_bits", robot.trailer.get("rotary_bits", 10))
        self.step_rad = 2 * math.pi / (1 << bits)
        self.step_l_mm = max(robot.linkage.get("linear_resolution_mm", 0.1), 1e-3)
        self.q_rad = self.step_rad / math.sqrt(12)
        self.q_l_mm = self.step_l_mm / math.sqrt(12)
        if self.has_link:
            # the reading in force at each truth sample (zero-order hold: a code is not a
            # continuous signal, interpolating between codes would invent values)
            k = np.clip(np.searchsorted(pr.t, self.tt + 1e-9, side="right") - 1, 0, pr.t.size - 1)
            self.meas = np.column_stack(
                [
                    np.radians(lg.alpha_deg[k]),
                    np.radians(lg.beta_deg[k]) if lg.beta_deg is not None else np.zeros(k.size),
                    lg.l_mm[k] if lg.l_mm is not None else np.zeros(k.size),
                ]
            )
            # the true linkage is measured too (by the motion capture, from two markers): where
            # its own noise exceeds the encoder's cell the reading is compared with it as a
            # Gaussian channel (cell centre, noise + quantisation), else interval-censored (the
            # simulator's exact linkage). A 2.6 m link tracked at 0.5 mm per marker is ~0.7 mm
            # of noise against a 0.02 mm linear encoder cell: censoring read that as a misfit
            # 10^5 times the noise (the independent world's clapper).
            self.link_noise = _sample_noise(self.tt, self.tlink)
            # ... at the tick its reading was latched at: the truth interpolated to that tick
            # (after its latency), not taken at the later sample that sees the code still held.
            # A set's joint turning at 0.3 rad/s, read up to a 25 ms tick late, is 0.0075 rad
            # off, 5 x the truth's noise: a set with no effect went "unexplained" at 2.4 x the
            # background (independent world 2831 case 41; 0.74 x compared at the ticks)
            self.tlink = _at_times(self.tt, self.tlink, pr.t[k])
            steps = np.array([self.step_rad, self.step_rad, self.step_l_mm])
            self.link_gauss = self.link_noise > steps / math.sqrt(12.0)
        # nominal travel in each window (roughness variance; stationary detection)
        S = pr.S
        self.wtravel = np.stack(
            [
                [
                    np.interp(self.tt[self.j], pr.t, S[:, t, w])
                    - np.interp(self.tt[self.i], pr.t, S[:, t, w])
                    for w in (0, 1)
                ]
                for t in range(self.trucks)
            ]
        )  # (trucks, 2, nwin)
        # the part of it (both wheels summed) turned on the spot: the background walks at its
        # own rate there (background.py: the OptiOdom robot's walk lives on its spot turns)
        spot = spot_ticks(pr)  # (n-1, trucks)
        St = np.concatenate(
            [np.zeros((1, pr.ds.shape[1])), np.cumsum(np.abs(pr.ds).sum(axis=2) * spot, axis=0)]
        )
        self.wturn = np.stack(
            [
                np.interp(self.tt[self.j], pr.t, St[:, t])
                - np.interp(self.tt[self.i], pr.t, St[:, t])
                for t in range(self.trucks)
            ]
        )  # (trucks, nwin)

    def model_pose(self, P: dict, truck: int) -> np.ndarray:
        return self._at_all(dead_reckon(self.pr, P, truck)[:, :3])

    def channels(self) -> list[str]:
        ch = []
        for t in "AB"[: self.trucks]:
            ch += [f"{t}.longitudinal_mm", f"{t}.lateral_mm", f"{t}.heading_rad"]
        if self.has_link:
            ch += (
                ["alpha_rad", "beta_rad", "l_mm"]
                if self.robot.vehicle == "clapper"
                else ["alpha_rad"]
            )
        return ch

    def noise_weights(self) -> np.ndarray:
        """Expected z^2 per value of each channel under noise alone (fit.Problem.e0)."""
        w = np.ones(len(self.channels()))
        if self.has_link:  # censored linkage readings: zero inside the cell
            n = len(self.channels()) - 3 * self.trucks
            w[3 * self.trucks :] = self.link_gauss[:n].astype(float)
        return w

    def link_sigma(self) -> np.ndarray:
        """Per linkage channel: the truth's own noise plus the cell's quantisation where the
        channel is Gaussian; the quantisation where it is censored."""
        steps = np.array([self.step_rad, self.step_rad, self.step_l_mm]) / math.sqrt(12.0)
        return np.where(self.link_gauss, np.hypot(self.link_noise, steps), steps)

    def residuals(self, P: dict) -> np.ndarray:
        cols = []
        for t in range(self.trucks):
            mp = self._at_ends(dead_reckon(self.pr, P, t)[:, :3])
            m = _body_inc(mp, self._ie, self._je)
            cols.append(self.tinc[t] - m)
        if self.has_link:
            tl = self.tlink[self.i]
            ba, bb, bl = link_bias(P, tl[:, 0], tl[:, 1])
            m = self.meas[self.i]
            g = self.link_gauss

            def res(c: int, x: np.ndarray, step: float, angle: bool) -> np.ndarray:
                if not g[c]:
                    return _censored(x, m[:, c], step, angle)
                d = m[:, c] + 0.5 * step - x  # the cell's centre against the measured truth
                return wrap_rad(d) if angle else d

            ra = res(0, tl[:, 0] + np.radians(ba), self.step_rad, True)
            if self.robot.vehicle == "clapper":
                rb = res(1, tl[:, 1] + np.radians(bb), self.step_rad, True)
                rl = res(2, tl[:, 2] + bl, self.step_l_mm, False)
                cols.append(np.column_stack([ra, rb, rl]))
            else:
                cols.append(ra[:, None])
        return np.hstack(cols)

    def anchored(self, P: dict, truck: int) -> np.ndarray:
        """The model's pose track (at the truth's samples) placed where the truth starts.

        The start pose is the mean offset of the truth from the model over the first
        ANCHOR_S: a single motion-capture sample puts its 3e-4 rad of heading noise into every
        later position (2 mm after 7 m), more than the noise floor the gap is judged against."""
        m = self.model_pose(P, truck)
        tp = self.tpose[:, truck]
        k = self.tt <= self.tt[0] + ANCHOR_S
        th0 = float(np.mean(tp[k, 2] - m[k, 2]))
        c, s_ = math.cos(th0), math.sin(th0)
        x = c * m[:, 0] - s_ * m[:, 1]
        y = s_ * m[:, 0] + c * m[:, 1]
        x0 = float(np.mean(tp[k, 0] - x[k]))
        y0 = float(np.mean(tp[k, 1] - y[k]))
        return np.column_stack([x + x0, y + y0, m[:, 2] + th0])

    def sys_z(self, P: dict, sigma: np.ndarray) -> np.ndarray:
        """Standardised residuals for the systematic gap (diagnose._sysgap): the accumulated
        position error of each truck along the run (model started at the truth's first pose;
        sampled once per window, in units of the truth's position noise, sigma of a window's
        longitudinal increment / sqrt 2), and the linkage readings against the true linkage.
        Accumulated, because that is the gap a user sees; the windowed increments the fit uses
        are local on purpose (an honest likelihood) and so sit close to the noise per window."""
        cols = []
        for t in range(self.trucks):
            m = self.anchored(P, t)[self.i, :2]
            cols.append((m - self.tpose[self.i, t, :2]) / (sigma[3 * t] / math.sqrt(2)))
        if self.has_link:
            k = 3 * self.trucks
            cols.append(self.residuals(P)[:, k:] / sigma[k:])
        return np.hstack(cols)

    def own_var(self, sigma: np.ndarray) -> np.ndarray | None:
        """(nwin, channels) variance the wheel counters' quantisation adds to each window's
        body increment, whatever the hypothesis. A counter reads the floor of its wheel's
        travel, so a window's counted travel is off by c (f_j - f_i), the unread fractions at
        its ends: variance c^2 / 6 once the wheel has turned a count or more, less on a shorter
        turn (c^2 / 6 * u for u counts; nothing at rest). The truck's travel takes a quarter of
        the two wheels' sum, its heading their sum over b^2, and the heading error grows through
        the window and carries its travel sideways: (L / 2)^2 times the heading's.

        The truth's noise sigma is read robustly from the samples (`fit.estimate_sigma`), and a
        steady drive repeats its fractions window after window, so without this term the
        windows where they change read as slip: quieted LabMates of the independent world with
        0.9-7.8 mrad a count and no effect gave Delta BIC up to 87,000 for slip (dev seeds
        4061-4091; `background.counting_error` carries the same quantisation along the run for
        the allowance)."""
        got = self.__dict__.get("_cvar")
        if got is not None:
            return got
        out = np.zeros((self.i.size, len(self.channels())))
        for t in range(self.trucks):
            c = self.pr.edge_mm(t)
            if c <= 0:
                continue
            travel = np.abs(self.wtravel[t])  # (2, nwin) each wheel's travel in the window
            vs = (c * c / 6.0) * np.minimum(travel / c, 1.0).sum(axis=0)
            b = self.pr.b[t]
            L = 0.5 * travel.sum(axis=0)
            out[:, 3 * t] = vs / 4.0
            out[:, 3 * t + 1] = (0.5 * L) ** 2 * vs / b**2
            out[:, 3 * t + 2] = vs / b**2
        self._cvar = out
        return out

    def extra_var(self, P: dict) -> np.ndarray | None:
        h = max(truck_view(P, t).get("roughness.max_height_mm", 0.0) for t in range(self.trucks))
        if h <= 0:
            return None
        sp = P.get("roughness.spacing_mm", 20.0)
        out = np.zeros((self.i.size, len(self.channels())))
        # the mean grain is in the model (floor_travel), so a window's residual varies by the
        # grains' central moment, m2 - m1^2 (m2 alone overstated it ~2.8x for uniform heights and
        # left a mean shortfall an es had to make up), plus the grain count's own spread
        cv2 = _grain_count_cv2(P)
        for t in range(self.trucks):
            # each wheel: grains cut by the window's ends count by their share only
            # (model.rough_window_var; without it the variance was ~20 % too high on 0.4 s
            # windows and pulled the height down, an es making up the mean)
            h = truck_view(P, t).get("roughness.max_height_mm", 0.0)
            if h <= 0:
                continue
            m1, _ = rough_moments(self.pr.R[t], h)
            var = np.zeros(self.i.size)
            for w in (0, 1):
                L = self.wtravel[t, w]
                e2q, _, q = rough_window_var(self.pr.R[t], h, L)
                var += (L / sp) * (e2q - m1 * m1 * q + cv2 * m1 * m1 * q)
            b = self.pr.b[t]
            out[:, 3 * t] = var / 4.0
            out[:, 3 * t + 2] = var / b**2
            # a grain turns the truck by dd / b; the rest of the window's travel carries that
            # turn sideways: lateral variance var / b^2 * Lt^2 / 3 (grain phase uniform)
            Lt = 0.5 * (self.wtravel[t, 0] + self.wtravel[t, 1])
            out[:, 3 * t + 1] = var / b**2 * Lt**2 / 3.0
        return out

    def noise_diffs(self, truck: int) -> tuple[np.ndarray, np.ndarray]:
        """Second differences of the truth-minus-model track at the truth's own samples:
        (positions, x and y pooled; headings) of one truck, from evenly spaced triples only.

        The counts-driven nominal model removes the robot's motion, and what an effect adds
        changes slowly from sample to sample, so the second difference of the residual is the
        truth's sample noise n(k+1) - 2 n(k) + n(k-1), variance 6 sigma^2 for white noise; bumps
        and speed changes are a few outliers a robust spread ignores."""
        m = self.anchored({}, truck)
        r = self.tpose[:, truck, :] - m
        r[:, 2] = np.unwrap(r[:, 2])
        # unevenly spaced samples (a truth with timing jitter, or at its own rate): the second
        # divided difference, scaled so that white noise of variance sigma^2 gives 6 sigma^2 as
        # the plain second difference of even samples does
        h1, h2 = np.diff(self.tt)[:-1], np.diff(self.tt)[1:]
        ok = (h1 > 0) & (h2 > 0)
        h1, h2 = np.where(ok, h1, 1.0), np.where(ok, h2, 1.0)
        w0, w2 = 1.0 / h1, 1.0 / h2
        w1 = w0 + w2
        d = w2[:, None] * r[2:] - w1[:, None] * r[1:-1] + w0[:, None] * r[:-2]
        scale = np.sqrt(6.0 / (w0 * w0 + w1 * w1 + w2 * w2))
        d2 = (d * scale[:, None])[ok]
        return d2[:, :2].ravel(), d2[:, 2]

    def stationary(self) -> np.ndarray:
        return np.all(self.wtravel.reshape(-1, self.i.size) < 1e-9, axis=0)

    def gap(self, P: dict) -> float:
        """RMS position error (mm) of truck A along the run, model anchored at the truth's start."""
        m = self.anchored(P, 0)
        return float(np.sqrt(np.mean(np.sum((m[:, :2] - self.tpose[:, 0, :2]) ** 2, axis=1))))

    def error_track(self, P: dict) -> tuple[np.ndarray, np.ndarray]:
        return self.tt, self.anchored(P, 0) - self.tpose[:, 0, :]


class ReturnsMode:
    name = "returns"

    def __init__(self, pr: Prepared, robot: Robot, accuracy: tuple | None = None) -> None:
        assert pr.run.ret is not None
        self.pr, self.ret = pr, pr.run.ret
        # the return measurement's accuracy (mm, rad), when the user states it: the noise floor
        # against which a spread of the returns is evidence (roughness) rather than noise
        self.accuracy = accuracy

    def channels(self) -> list[str]:
        return ["x_mm", "y_mm", "theta_rad"]

    def residuals(self, P: dict) -> np.ndarray:
        p = dead_reckon(self.pr, P, 0)[-1]
        return np.array([[self.ret[0] - p[0], self.ret[1] - p[1], wrap_rad(self.ret[2] - p[2])]])

    def own_var(self, sigma: np.ndarray) -> np.ndarray:
        """(1, 3): the start placement's heading error d turns the whole run about its start
        point, which moves the return point by J p_end d (J the 90 deg rotation, p_end the
        measured return position in the start frame). A closed path (UMBmark's squares, 000
        s. 3.3) returns to its start and shows d in its heading only, so the spread of its
        returns says nothing of it in x, y; a path that ends 11 m away carries 13 mm per 0.07
        deg (independent world, seed 2691 case 43: a no-effect robot's one 'drive' run 24 mm
        off and "unexplained"). sd(d) is taken as the returns' heading sigma, an upper bound
        (that spread also holds the end measurement's own noise)."""
        s = float(sigma[2])
        return np.array([[(s * self.ret[1]) ** 2, (s * self.ret[0]) ** 2, 0.0]])

    def extra_var(self, P: dict) -> np.ndarray | None:
        """Roughness's spread of the return pose, when the measurement's accuracy is known.

        Each grain shortens one wheel's floor travel by dd (central moment m2 - m1^2 plus the
        grain count's renewal spread, as in TruthMode.extra_var). A shortfall d of wheel w at
        tick k moves the truck back by d / 2 along its heading u_k and turns it by
        -/+ d / b (left / right), which carries the rest of the path sideways: the return pose
        moves by g = (-u_k / 2 -/+ J (p_end - p_k) / b, -/+ 1 / b) d, J the 90 deg rotation.
        Var(return) = sum over ticks and wheels of grains x var(dd) x g^2 (the diagonal)."""
        h = P.get("roughness.max_height_mm", 0.0)
        if h <= 0 or self.accuracy is None:
            return None
        m1, m2 = rough_moments(self.pr.R[0], h)
        cv2 = _grain_count_cv2(P)
        var_grain = m2 - m1 * m1 + cv2 * m1 * m1
        n_grain = np.abs(self.pr.ds[:, 0, :]) / P.get("roughness.spacing_mm", 20.0)  # (n-1, 2)
        p = dead_reckon(self.pr, P, 0)
        pm = 0.5 * (p[:-1] + p[1:])
        c, s_ = np.cos(pm[:, 2]), np.sin(pm[:, 2])
        rx, ry = p[-1, 0] - pm[:, 0], p[-1, 1] - pm[:, 1]  # to the return point
        b = self.pr.b[0]
        var = np.zeros(3)
        for w, sw in ((0, 1.0), (1, -1.0)):  # a left-wheel shortfall turns the truck left
            gx = -0.5 * c - sw * ry / b
            gy = -0.5 * s_ + sw * rx / b
            q = n_grain[:, w] * var_grain
            var += [np.sum(q * gx * gx), np.sum(q * gy * gy), np.sum(q) / b**2]
        return var[None, :]

    def noise_weights(self) -> np.ndarray:
        return np.ones(len(self.channels()))

    def sys_z(self, P: dict, sigma: np.ndarray) -> np.ndarray:
        return self.residuals(P) / np.sqrt(sigma**2 + self.own_var(sigma))

    def gap(self, P: dict) -> float:
        r = self.residuals(P)[0]
        return float(math.hypot(r[0], r[1]))


class LinkageMode:
    name = "linkage"

    def __init__(self, pr: Prepared, robot: Robot) -> None:
        lg = pr.run.log
        assert lg.alpha_deg is not None and robot.n_trucks == 2
        self.pr, self.robot = pr, robot
        self.clapper = robot.vehicle == "clapper"
        if self.clapper and lg.l_mm is None:
            raise ValueError("no LINK_LINEAR frames")
        H = max(1, round(HORIZON_S / robot.tick_s))
        n = pr.t.size
        self.i = np.arange(0, n - H, H)
        self.j = self.i + H
        bits = robot.linkage.get("rotary_bits", robot.trailer.get("rotary_bits", 10))
        self.q_rad = 2 * math.pi / (1 << bits) / math.sqrt(12)
        half = math.pi / (1 << bits)  # the encoders truncate: code k reads the middle of its step
        self.a = np.radians(lg.alpha_deg) + half
        self.b = np.radians(lg.beta_deg) + half
        res = robot.linkage.get("linear_resolution_mm", 0.1)
        self.l = lg.l_mm + 0.5 * res if lg.l_mm is not None else None
        self.steps = (2 * half, 2 * half, res)
        q = self.q_rad
        self.floor = np.array([q, q, res / math.sqrt(12)] if self.clapper else [q, 0.05, 0.05])
        self.J = self._start_jac()
        self.nuisance_per_window = self.J.shape[2]

    def _start_jac(self) -> np.ndarray:
        """(nwin, 3 channels, n start readings): how each window's prediction moves with the
        start state (central differences of the nominal model)."""
        names = ("a", "b", "l") if self.clapper else ("a",)
        cols = []
        for nm, st in zip(names, self.steps, strict=False):
            arr = getattr(self, nm)
            h = 0.25 * st
            setattr(self, nm, arr + h)
            up = self._pred({})
            setattr(self, nm, arr - h)
            dn = self._pred({})
            setattr(self, nm, arr)
            cols.append((up - dn) / (2 * h))
        return np.stack(cols, axis=2)

    def _profile(self, r: np.ndarray) -> np.ndarray:
        """Residuals with each window's start state profiled out inside its encoder cells.

        The start (alpha, beta, l) is only known to lie in the cell [code, code + step) of each
        reading. Its true place in the cell is a nuisance: per window it is chosen to minimise the
        weighted residual (first order, box-constrained). Taking the cell centre instead is
        biased whenever the linkage rests (a straight clapper or trailer reads code 0 at exactly
        0: half a step of error, on every window, always the same sign), and on the spot turns
        carry a 0.35 deg start error into ~1 mm of predicted l, 70 linear encoder steps: that was
        the clapper/set false alarm. Costs one parameter per reading per window (see
        `nuisance_per_window`)."""
        J = self.J
        w, Jw, half, A, Adiag = self._profile_terms()
        rw = r * w[None, :]
        g = -np.einsum("nci,nc->ni", Jw, rw)
        d = np.clip(np.linalg.solve(A, g[..., None])[..., 0], -half, half)
        for _ in range(2):  # coordinate passes for the box (the clipped Newton step is close)
            for k in range(J.shape[2]):
                rest = rw + np.einsum("nci,ni->nc", Jw, d) - Jw[:, :, k] * d[:, k : k + 1]
                num = -np.einsum("nc,nc->n", Jw[:, :, k], rest)
                d[:, k] = np.clip(num / Adiag[k], -half[k], half[k])
        return r + np.einsum("nci,ni->nc", J, d)

    def _profile_terms(self) -> tuple:
        """What `_profile` needs that no hypothesis changes (the start Jacobian's weighted form
        and normal matrix), computed once per run instead of once per residual evaluation."""
        got = self.__dict__.get("_pterms")
        if got is None:
            J = self.J
            w = 1.0 / self.floor
            Jw = J * w[None, :, None]
            half = 0.5 * np.array(self.steps[: J.shape[2]])
            A = np.einsum("nci,ncj->nij", Jw, Jw)
            A = A + (1e-9 * np.trace(A, axis1=1, axis2=2) + 1e-9)[:, None, None] * np.eye(
                A.shape[1]
            )
            Adiag = [np.maximum(A[:, k, k], 1e-30) for k in range(J.shape[2])]
            got = self._pterms = (w, Jw, half, A, Adiag)
        return got

    def channels(self) -> list[str]:
        return (
            ["alpha_rad", "beta_rad", "l_mm"]
            if self.clapper
            else ["alpha_rad", "along_mm", "perp_mm"]
        )

    def _pred(self, P: dict) -> np.ndarray:
        pa, pb = dead_reckon(self.pr, P, 0), dead_reckon(self.pr, P, 1)
        i, j = self.i, self.j
        ia, ib = _body_inc(pa, i, j), _body_inc(pb, i, j)
        # the offsets at the read angles of both ends: an offset that varies once per turn of
        # the shaft (rotary_bias@eccentric) changes by far less between the read and the true
        # angle than between the two ends; a constant one is the same at both
        ba, bb, _ = link_bias(P, self.a[i], self.b[i] if self.clapper else 0.0)
        ea, eb_, _ = link_bias(P, self.a[j], self.b[j] if self.clapper else 0.0)
        a0 = wrap_rad(self.a[i] - np.radians(ba))
        xa, ya, tha = ia[:, 0], ia[:, 1], ia[:, 2]  # A starts at the origin, heading 0
        if self.clapper:
            b0 = wrap_rad(self.b[i] - np.radians(bb))
            l0 = self.l[i] - self._lbias(P, a0, b0)
            thl = -a0
            xb0, yb0 = -l0 * np.cos(thl), -l0 * np.sin(thl)
            thb0 = thl + b0
            c, s = np.cos(thb0), np.sin(thb0)
            xb, yb = xb0 + c * ib[:, 0] - s * ib[:, 1], yb0 + s * ib[:, 0] + c * ib[:, 1]
            thb = thb0 + ib[:, 2]
            thl1 = np.arctan2(ya - yb, xa - xb)
            a1, b1 = wrap_rad(tha - thl1), wrap_rad(thb - thl1)
            l1 = np.hypot(xa - xb, ya - yb)
            pa_ = a1 + np.radians(ea)
            pb_ = b1 + np.radians(eb_)
            pl = l1 + self._lbias(P, a1, b1)
            return np.column_stack(
                [wrap_rad(self.a[j] - pa_), wrap_rad(self.b[j] - pb_), self.l[j] - pl]
            )
        hoff = self.robot.trailer["hitch_offset_mm"]
        L = self.robot.trailer["trailer_length_mm"]
        tht0 = -a0
        xt0, yt0 = -hoff - L * np.cos(tht0), -L * np.sin(tht0)
        c, s = np.cos(tht0), np.sin(tht0)
        xt, yt = xt0 + c * ib[:, 0] - s * ib[:, 1], yt0 + s * ib[:, 0] + c * ib[:, 1]
        tht = tht0 + ib[:, 2]
        hx, hy = xa - hoff * np.cos(tha), ya - hoff * np.sin(tha)
        dx, dy = hx - xt, hy - yt
        along = np.hypot(dx, dy) - L
        perp = wrap_rad(np.arctan2(dy, dx) - tht) * L
        pa_ = wrap_rad(tha - tht) + np.radians(ea)
        return np.column_stack([wrap_rad(self.a[j] - pa_), along, perp])

    @staticmethod
    def _lbias(P: dict, a, b):
        return link_bias(P, a, b)[2]

    def residuals(self, P: dict) -> np.ndarray:
        return self._profile(self._pred(P))

    def extra_var(self, P: dict) -> None:
        return None

    def own_var(self, sigma: np.ndarray) -> np.ndarray:
        """(nwin, channels) variance the wheel counters' quantisation adds to each window's
        residual beyond the linkage encoders' own (`quantisation_var` less sigma's floor)."""
        got = self.__dict__.get("_qvar")
        if got is None:
            got = self._qvar = np.maximum(self.quantisation_var() - self.floor**2, 0.0)
        return got

    def quantisation_var(self, draws: int = QUANT_DRAWS) -> np.ndarray:
        """(nwin, channels) mean square of a window's profiled residual under the instruments'
        quantisation alone, drawn: the start readings' place in their cells, the end readings'
        truncation, and the wheel counters'. The prediction dead-reckons each wheel over the
        window from two counter readings truncated to whole counts, at fractions f_i and f_j of
        a count (independent once the wheel has counted, the same where it rests), whose effect
        is step (J_last f_j - J_first f_i) (the readings in between telescope). Taken as
        exact before, a clapper with 0.17 mm counts and a 0.01 mm linear encoder read a straight
        window's 0.07 mm of count noise as 25 times the noise, and three of eight clappers with
        no effect were "unexplained" (independent world, dev seeds 2602-2609). Drawn rather than
        propagated: the profile (`_profile`) absorbs an error only up to half a cell, so how
        much of the count noise it takes depends on the window's geometry."""
        pr = self.pr
        rng = np.random.default_rng(0)
        nw, nc = self.i.size, len(self.channels())
        cs = np.concatenate([np.zeros((1, *pr.ds.shape[1:])), np.cumsum(pr.ds, axis=0)])
        wheels = []
        for t, step in enumerate(pr.count_mm[: pr.ds.shape[1]]):
            for w in (0, 1):
                rests = np.abs(cs[self.j, t, w] - cs[self.i, t, w]) < 0.5 * step
                jf, jl = (self._travel_jac(t, w, k, step) for k in (self.i, self.j - 1))
                wheels.append((step, rests, jf, jl))
        half = 0.5 * np.array(self.steps[: self.J.shape[2]])
        end = np.zeros(nc)
        k = self.n_readings
        end[:k] = self.steps[:k]
        acc = np.zeros((nw, nc))
        for _ in range(draws):
            u = rng.uniform(-1.0, 1.0, (nw, half.size)) * half
            r = np.einsum("nci,ni->nc", self.J, u) + rng.uniform(-0.5, 0.5, (nw, nc)) * end
            for step, rests, jf, jl in wheels:
                fi = rng.uniform(0.0, 1.0, nw)
                fj = np.where(rests, fi, rng.uniform(0.0, 1.0, nw))
                r += step * (jl * fj[:, None] - jf * fi[:, None])
            acc += self._profile(r) ** 2
        return acc / draws

    def _travel_jac(self, t: int, w: int, ticks: np.ndarray, h: float) -> np.ndarray:
        """(nwin, channels): d prediction / d travel of wheel w of truck t in the given tick of
        each window (central differences of the nominal model over a copy of the run)."""
        pr = self.pr
        cols = []
        for sgn in (1.0, -1.0):
            ds = pr.ds.copy()
            ds[ticks, t, w] += sgn * h
            self.pr = replace(pr, ds=ds, bumps=[], slip_cache={}, track_cache={}, clamp_cache={})
            try:
                cols.append(self._pred({}))
            finally:
                self.pr = pr
        d = cols[0] - cols[1]
        k = self.n_readings - 1 if self.clapper else 1  # the angle channels
        d[:, :k] = wrap_rad(d[:, :k])
        return d / (2.0 * h)

    @property
    def n_readings(self) -> int:
        """Channels that are encoder readings (the first ones): a clapper's alpha, beta and l, a
        set's alpha (its other two are the hitch's predicted offsets)."""
        return 3 if self.clapper else 1

    def noise_weights(self) -> np.ndarray:
        return np.ones(len(self.channels()))

    def sys_z(self, P: dict, sigma: np.ndarray) -> np.ndarray:
        return self.residuals(P) / np.sqrt(sigma**2 + self.own_var(sigma))

    def gap(self, P: dict) -> float:
        r = self._pred(P)
        L = self.robot.linkage.get("length_mm", self.robot.trailer.get("trailer_length_mm", 1000.0))
        mm = np.column_stack([r[:, 0] * L, r[:, 1] * (L if self.clapper else 1.0), r[:, 2]])
        return float(np.sqrt(np.mean(np.sum(mm**2, axis=1))))


MODES = {"truth": TruthMode, "returns": ReturnsMode, "linkage": LinkageMode}
