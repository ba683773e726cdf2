"""The robot's own side: onboard dead reckoning with the NOMINAL description (the firmware's
view, in double) and a trajectory-tracking controller that drives from it.

The controller is Kanayama's tracking law (Kanayama et al., "A stable tracking control method
for an autonomous mobile robot", ICRA 1990): with the reference pose expressed in the robot's
frame (e_x, e_y, e_th),
    v = v_r cos e_th + k_x e_x,    w = w_r + k_y v_r e_y + k_h sin e_th,
k_y chosen for critical damping of the lateral error at the cruise speed. Wheel speeds are
saturated (keeping the curvature) and rate-limited per tick (the controller's acceleration
bound); the motors then add their own lag and torque limit (world.py).
"""

from __future__ import annotations

import numpy as np

from .laws import wrap

EX_MAX = 40.0  # mm, the along-track error the controller acts on at most
EH_MAX = 0.05  # rad, the heading error it acts on at most


class Odometry:
    """Dead reckoning of one truck per run from raw wrapping counters (midpoint heading,
    the firmware's default form)."""

    def __init__(self, truck: dict, R: int, counts0: np.ndarray):
        self.bits = int(truck["counter_bits"])
        self.mpc = np.pi * truck["wheel_diameter_mm"] / (
            4.0 * truck["encoder_lines"] * truck["gear_ratio"]
        )
        self.sign = np.array(
            [-1.0 if truck.get("invert_left") else 1.0, -1.0 if truck.get("invert_right") else 1.0]
        )
        self.b = float(truck["wheelbase_mm"])
        self.k = self.mpc * self.sign[None, :]
        self.prev = counts0 % (1 << self.bits)
        self.pose = np.zeros((R, 3))

    def update(self, counts: np.ndarray) -> None:
        """counts (R, 2) raw counter values (any width; reduced to the counter's)."""
        m = 1 << self.bits
        c = counts % m
        d = (c - self.prev + (m >> 1)) % m - (m >> 1)
        self.prev = c
        mm = d * self.k
        dd = (mm[:, 0] + mm[:, 1]) * 0.5
        dth = (mm[:, 1] - mm[:, 0]) / self.b
        p = self.pose
        thm = p[:, 2] + dth * 0.5
        p[:, 0] += dd * np.cos(thm)
        p[:, 1] += dd * np.sin(thm)
        p[:, 2] += dth


class Controller:
    """Tracks per-run references (arrays (R, K) at the control ticks) from onboard odometry."""

    def __init__(self, case: dict, refs: list[dict], counts0: np.ndarray, k_end: np.ndarray):
        rob = case["robot"]
        self.T = case["tick_ms"] / 1000.0
        self.names = ["A"] if rob["vehicle"] == "labmate" else ["A", "B"]
        self.driven = [True, rob["vehicle"] == "clapper"]
        R = counts0.shape[0]
        self.R = R
        self.odo = [Odometry(rob["trucks"][n], R, counts0[:, i]) for i, n in enumerate(self.names)]
        if rob["vehicle"] == "clapper":  # truck B starts the link's length behind A
            self.odo[1].pose[:, 0] = -rob["linkage"]["length_mm"]
        elif rob["vehicle"] == "set":  # the trailer's axle behind the hitch
            tr = rob["trailer"]
            self.odo[1].pose[:, 0] = -(tr["hitch_offset_mm"] + tr["trailer_length_mm"])
        self.refs = [{k: np.ascontiguousarray(a.T) for k, a in r.items()} for r in refs]  # (K, R)
        self.k_end = k_end
        c = case["controller"]
        self.vmax = rob["max_wheel_speed_mm_s"]
        self.acc = c["cmd_accel_mm_s2"]
        T = self.T
        self.kx = min(2.5, 0.25 / T)
        self.kh = min(4.0, 0.35 / T)
        self.ky = self.kh**2 / (4.0 * c["v_mm_s"] ** 2)
        self.klink = min(2.0, 0.2 / T)
        self.link_len = rob.get("linkage", {}).get("length_mm", 0.0)
        self.prev = np.zeros((R, len(self.names), 2))
        self.rn = [rob["trucks"][n]["wheel_diameter_mm"] / 2.0 for n in self.names]

    def step(self, k: int, counts: np.ndarray, link: np.ndarray | None) -> np.ndarray:
        """Counts (and the linkage encoders' readings, alpha, beta, l) sampled at tick k ->
        wheel speed commands (R, trucks, 2) in rad/s (wheel
        side) for the tick that follows."""
        live = k < self.k_end
        out = np.zeros((self.R, len(self.names), 2))
        for i, od in enumerate(self.odo):
            od.update(counts[:, i])
            if not self.driven[i]:
                continue
            ref = self.refs[i]
            xr, yr, thr, vr, wr = ref["x"][k], ref["y"][k], ref["th"][k], ref["v"][k], ref["w"][k]
            p = od.pose
            c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
            dx, dy = xr - p[:, 0], yr - p[:, 1]
            eth = wrap(thr - p[:, 2])
            if i == 1 and link is not None:
                # the rear truck follows A through the linkage, not its own odometry: the
                # linear encoder sets its speed (the link at its length), the rotary encoder
                # its turning (beta, its angle to the link, as the path's geometry wants it)
                v = vr * np.cos(eth) + self.klink * (link[:, 2] - self.link_len)
                w = wr - self.kh * wrap(link[:, 1] - ref["bd"][k])
            else:
                # bounded catch-up: a robot that lags its reference (its own view) drives at
                # most kx * EX_MAX faster than planned
                v = vr * np.cos(eth) + self.kx * np.clip(c * dx + s * dy, -EX_MAX, EX_MAX)
                w = wr + self.ky * vr * (c * dy - s * dx) + self.kh * np.clip(eth, -EH_MAX, EH_MAX)
            hb = od.b / 2
            vw = np.empty((self.R, 2))
            vw[:, 0] = v - w * hb
            vw[:, 1] = v + w * hb
            top = np.abs(vw).max(axis=1)
            if (top > self.vmax).any():
                vw *= np.minimum(1.0, self.vmax / np.maximum(top, 1e-9))[:, None]
            step = self.acc * self.T
            prev = self.prev[:, i]
            vw = prev + np.clip(vw - prev, -step, step)
            vw[~live] = 0.0
            self.prev[:, i] = vw
            out[:, i] = vw / self.rn[i]
        return out
