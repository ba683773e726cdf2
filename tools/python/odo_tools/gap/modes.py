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

import numpy as np

from .io import Robot
from .model import Prepared, dead_reckon, link_bias, rough_moments, wrap_rad

WINDOW_S = 0.4  # truth increments: window length
HORIZON_S = 1.0  # linkage mode: prediction horizon


def _body_inc(p: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    dx, dy = p[j, 0] - p[i, 0], p[j, 1] - p[i, 1]
    c, s = np.cos(p[i, 2]), np.sin(p[i, 2])
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, p[j, 2] - p[i, 2]])


class TruthMode:
    name = "truth"

    def __init__(self, pr: Prepared, robot: Robot) -> None:
        tr = pr.run.truth
        assert tr is not None
        self.pr, self.robot = pr, robot
        t0, t1 = max(tr.t_s[0], pr.t[0]), min(tr.t_s[-1], pr.t[-1])
        sel = (tr.t_s >= t0 - 1e-9) & (tr.t_s <= t1 + 1e-9)
        self.tt = tr.t_s[sel]
        self.tpose = tr.pose[sel]
        self.tlink = tr.link[sel] if tr.link is not None else None
        dt = float(np.median(np.diff(self.tt)))
        W = max(1, round(WINDOW_S / dt))
        self.i = np.arange(0, self.tt.size - W, W)
        self.j = self.i + W
        self.trucks = robot.n_trucks
        self.tinc = [_body_inc(self.tpose[:, t], self.i, self.j) for t in range(self.trucks)]
        # where the model's ticks fall among the truth samples
        self.exact = self.tt.size <= pr.t.size and np.allclose(
            np.interp(self.tt, pr.t, pr.t), self.tt, atol=1e-6
        )
        lg = pr.run.log
        self.has_link = self.tlink is not None and lg.alpha_deg is not None
        if self.has_link:
            self.meas = np.column_stack(
                [
                    np.interp(self.tt, pr.t, lg.alpha_deg),
                    np.interp(self.tt, pr.t, lg.beta_deg),
                    np.interp(
                        self.tt, pr.t, lg.l_mm if lg.l_mm is not None else np.zeros_like(pr.t)
                    ),
                ]
            )
        bits = robot.linkage.get("rotary_bits", robot.trailer.get("rotary_bits", 10))
        self.q_rad = 2 * math.pi / (1 << bits) / math.sqrt(12)
        self.q_l_mm = max(robot.linkage.get("linear_resolution_mm", 0.1), 1e-3) / math.sqrt(12)
        if self.has_link:  # the encoders truncate: code k reads the middle of its step
            self.meas += [math.degrees(self.q_rad) * math.sqrt(3)] * 2 + [
                self.q_l_mm * math.sqrt(3)
            ]
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

    def model_pose(self, P: dict, truck: int) -> np.ndarray:
        p = dead_reckon(self.pr, P, truck)
        return np.column_stack([np.interp(self.tt, self.pr.t, p[:, k]) for k in range(3)])

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

    def residuals(self, P: dict) -> np.ndarray:
        cols = []
        for t in range(self.trucks):
            m = _body_inc(self.model_pose(P, t), self.i, self.j)
            cols.append(self.tinc[t] - m)
        if self.has_link:
            tl = self.tlink[self.i]
            ba, bb, bl = link_bias(P, tl[:, 0], tl[:, 1])
            ra = wrap_rad(np.radians(self.meas[self.i, 0] - ba) - tl[:, 0])
            if self.robot.vehicle == "clapper":
                rb = wrap_rad(np.radians(self.meas[self.i, 1] - bb) - tl[:, 1])
                rl = self.meas[self.i, 2] - bl - tl[:, 2]
                cols.append(np.column_stack([ra, rb, rl]))
            else:
                cols.append(ra[:, None])
        return np.hstack(cols)

    def extra_var(self, P: dict) -> np.ndarray | None:
        h = P.get("roughness.max_height_mm", 0.0)
        if h <= 0:
            return None
        sp = P.get("roughness.spacing_mm", 20.0)
        out = np.zeros((self.i.size, len(self.channels())))
        for t in range(self.trucks):
            _, m2 = rough_moments(self.pr.R[t], h)
            n = (self.wtravel[t, 0] + self.wtravel[t, 1]) / sp
            out[:, 3 * t] = n * m2 / 4.0
            out[:, 3 * t + 2] = n * m2 / self.pr.b[t] ** 2
        return out

    def stationary(self) -> np.ndarray:
        return np.all(self.wtravel.reshape(-1, self.i.size) < 1e-9, axis=0)

    def gap(self, P: dict) -> float:
        """RMS position error (mm) of truck A along the run, model started at the truth's pose."""
        p = dead_reckon(
            self.pr,
            P,
            0,
            tuple(np.interp(self.pr.t[0], self.tt, self.tpose[:, 0, k]) for k in range(3)),
        )
        m = np.column_stack([np.interp(self.tt, self.pr.t, p[:, k]) for k in range(2)])
        return float(np.sqrt(np.mean(np.sum((m - self.tpose[:, 0, :2]) ** 2, axis=1))))

    def error_track(self, P: dict) -> tuple[np.ndarray, np.ndarray]:
        p = dead_reckon(
            self.pr,
            P,
            0,
            tuple(np.interp(self.pr.t[0], self.tt, self.tpose[:, 0, k]) for k in range(3)),
        )
        m = np.column_stack([np.interp(self.tt, self.pr.t, p[:, k]) for k in range(3)])
        return self.tt, m - self.tpose[:, 0, :]


class ReturnsMode:
    name = "returns"

    def __init__(self, pr: Prepared, robot: Robot) -> None:
        assert pr.run.ret is not None
        self.pr, self.ret = pr, pr.run.ret

    def channels(self) -> list[str]:
        return ["x_mm", "y_mm", "theta_rad"]

    def residuals(self, P: dict) -> np.ndarray:
        p = dead_reckon(self.pr, P, 0)[-1]
        return np.array([[self.ret[0] - p[0], self.ret[1] - p[1], wrap_rad(self.ret[2] - p[2])]])

    def extra_var(self, P: dict) -> None:
        return None

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
        ba, bb, _ = link_bias(P, 0.0, 0.0)
        a0 = wrap_rad(self.a[i] - math.radians(ba))
        xa, ya, tha = ia[:, 0], ia[:, 1], ia[:, 2]  # A starts at the origin, heading 0
        if self.clapper:
            b0 = wrap_rad(self.b[i] - math.radians(bb))
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
            pa_ = a1 + math.radians(ba)
            pb_ = b1 + math.radians(bb)
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
        pa_ = wrap_rad(tha - tht) + math.radians(ba)
        return np.column_stack([wrap_rad(self.a[j] - pa_), along, perp])

    @staticmethod
    def _lbias(P: dict, a, b):
        return P.get("link_bias.const_mm", 0.0) + P.get("link_bias.ecc_mm", 0.0) * (
            1 - np.cos(a - b)
        )

    def residuals(self, P: dict) -> np.ndarray:
        return self._pred(P)

    def extra_var(self, P: dict) -> None:
        return None

    def gap(self, P: dict) -> float:
        r = self._pred(P)
        L = self.robot.linkage.get("length_mm", self.robot.trailer.get("trailer_length_mm", 1000.0))
        mm = np.column_stack([r[:, 0] * L, r[:, 1] * (L if self.clapper else 1.0), r[:, 2]])
        return float(np.sqrt(np.mean(np.sum(mm**2, axis=1))))


MODES = {"truth": TruthMode, "returns": ReturnsMode, "linkage": LinkageMode}
