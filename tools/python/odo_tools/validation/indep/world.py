"""The independent world: rigid-body planar physics of every run of a case at once.

All runs of a case are stepped together (arrays over runs), one control tick at a time; inside a
tick the physics runs at its own step (the case's physics_dt_s), vectorised over the substeps:
the motors' response to the held command is in closed form, wheel travel goes through the
rolling radius, slip and the floor, and the truck's pose is integrated along exact arcs per
substep. What is genuinely sequential (a friction limit, a backlash, a trailer's or castor's
heading) runs as a loop over the substeps only where such an effect is on; the trailer and
castor headings are solved by Picard iteration, vectorised.

Units: mm, s, rad. Wheels are indexed 0 = left, 1 = right. A truck's wheel speeds are held as
wheel-side angular speeds (the motor's speed divided by the gear ratio).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import floor as fl
from . import laws

G = laws.G


def _scoped(case: dict, truck: str) -> dict[str, dict]:
    """The effects (catalog and out-of-catalog) that act on one truck, by name."""
    out = {}
    for name, e in case["true"]["effects"].items():
        sc = e.get("truck", "A")
        if sc in (truck, "both", "vehicle"):
            out[name] = e
    return out


@dataclass
class TruckModel:
    """What one truck is, nominally and truly."""

    name: str
    driven: bool
    r_nom: float
    b_nom: float
    cpr: float  # counts per wheel turn, 4 x lines x gear
    gear: float
    bits: int
    invert: tuple[bool, bool]
    r0: np.ndarray  # true static rolling radii (left, right), mm
    b: float  # true geometric wheelbase, mm
    eff: dict = field(default_factory=dict)


def truck_models(case: dict) -> list[TruckModel]:
    rob = case["robot"]
    names = ["A"] if rob["vehicle"] == "labmate" else ["A", "B"]
    out = []
    for nm in names:
        t = rob["trucks"][nm]
        r = t["wheel_diameter_mm"] / 2.0
        eff = _scoped(case, nm)
        driven = nm == "A" or rob["vehicle"] == "clapper"
        r0 = np.array([r, r])
        b = float(t["wheelbase_mm"])
        if "es" in eff:
            e = eff["es"]
            if e["law"] == "diameter":
                r0 = r0 / e["value"]
            else:  # uniform deflection: effective rolling radius r - delta/3
                r0 = r0 - e["deflection_mm"] / 3.0
        if "ed" in eff:
            e = eff["ed"]
            ed = e["value"] if e["law"] == "fixed" else e["value0"]
            r0 = r0 * np.array([2.0 / (1.0 + ed), 2.0 * ed / (1.0 + ed)])
        if "eb" in eff:
            e = eff["eb"]
            b *= e["value"] if e["law"] == "fixed" else e["value0"]
        if "scrub" in eff and eff["scrub"]["law"] == "torque":
            b *= 1.0 - eff["scrub"]["s_sat"]
        tm = TruckModel(
            nm,
            driven,
            r,
            float(t["wheelbase_mm"]),
            4.0 * t["encoder_lines"] * t["gear_ratio"],
            float(t["gear_ratio"]),
            int(t["counter_bits"]),
            (bool(t.get("invert_left", False)), bool(t.get("invert_right", False))),
            r0,
            b,
            eff,
        )
        if "tire_compression" in eff:
            e = eff["tire_compression"]
            if e["law"] == "linear":
                y = e["lateral_offset_mm"] / b  # lever rule: the left wheel carries 1/2 + y
                tm.r0 = tm.r0 - e["k_mm_per_kg"] * e["load_kg"] * np.array([0.5 + y, 0.5 - y])
        out.append(tm)
    return out


@dataclass
class Cable:
    x: float
    y: float
    ang: float  # direction of the cable's axis, rad
    length: float
    kind: str
    h: float
    width: float
    slope_deg: float


@dataclass
class Hist:
    """Substep history of the true state, for the truth track."""

    t: list = field(default_factory=list)
    pose: list = field(default_factory=list)  # (R, trucks, 3, n) per tick


class World:
    """R runs of one case, advanced one control tick at a time."""

    def __init__(
        self,
        case: dict,
        trucks: list[TruckModel],
        start: np.ndarray,  # (R, trucks, 3) true start poses (truck B of a set: the axle)
        rough: np.ndarray,  # (R, trucks, 2, U+1) cumulative roughness excess per mm of travel
        cables: list[Cable],
        rng: np.random.Generator,
        t_session0: np.ndarray,  # (R,) session time at each run's start, s
    ):
        self.case = case
        self.vehicle = case["robot"]["vehicle"]
        self.trucks = trucks
        fid = case["fidelity"]
        self.T = case["tick_ms"] / 1000.0
        self.dt = fid["physics_dt_s"]
        self.n = round(self.T / self.dt)
        self.tk = self.dt * np.arange(1, self.n + 1)
        self.decay = np.exp(-self.tk / case["true"]["motor"]["tau_s"])
        self.R = start.shape[0]
        R, nt = self.R, len(trucks)
        self.pose = start.copy()
        self.start = start.copy()
        self.t = 0.0
        self.t_sess0 = t_session0
        self.motor = case["true"]["motor"]
        self.om = np.zeros((R, nt, 2))
        self.phi_m = np.zeros((R, nt, 2))  # motor angle, wheel side
        self.phi_w = np.zeros((R, nt, 2))  # wheel angle (differs by the backlash)
        self.s_net = np.zeros((R, nt, 2))  # floor-net rolled travel (driven) / horizontal (passive)
        self.u_abs = np.zeros((R, nt, 2))  # unsigned travel for the roughness tables
        self.vg = np.zeros((R, nt, 2))  # ground speed of the contacts (traction law)
        self.vw_last = np.zeros((R, nt, 2))
        self.V = np.zeros((R, nt, 2))  # velocity of the truck's centre (friction-circle skid)
        self.U = rough.shape[-1] - 1
        self.rough_flat = [np.ascontiguousarray(rough[:, ti]).reshape(-1) for ti in range(nt)]
        self.rough_base = (np.arange(R)[:, None] * 2 + np.arange(2)[None, :]) * (self.U + 1)
        self.E_last = rough[..., 0].copy()
        self.cables = cables
        self.bump = {}  # (run, truck, wheel) -> [map, s0, dir, cable index, centre logged]
        self._cache: dict = {}
        self.events: list[dict] = []
        self.clamps = np.zeros(R, dtype=np.int64)
        enc = case["true"]["encoder"]
        self.q_amp = enc["state_error"]
        self.q_ph = rng.uniform(0, 2 * np.pi, (R, nt, 2))
        self.c0 = rng.uniform(0, 1, (R, nt, 2))  # disc phase in counts
        self.edges = np.zeros((R, nt, 2), dtype=np.int64)
        self.decoded = np.zeros((R, nt, 2), dtype=np.int64)
        self.dec_phase = rng.uniform(0, 1, (R, nt, 2))
        self.rng = rng
        self.status = np.zeros((R, nt), dtype=np.int64)
        self.hist = Hist()
        self.hist_every = max(1, round(0.001 / self.dt))
        # trailer (set): heading of the trailer bar, hitch geometry
        if self.vehicle == "set":
            tr = case["robot"]["trailer"]
            self.hitch = tr["hitch_offset_mm"]
            self.bar = tr["trailer_length_mm"]
        # castor (out of catalog): swivel angle per run
        self.castor = trucks[0].eff.get("castor_swivel")
        if self.castor:
            self.psi = start[:, 0, 2].copy()
        self.edges[:] = self._edge_count(self.phi_m[..., None])[..., 0]
        self._events_on = case["true"]["effects"].get("bumps") is not None

    # --------------------------------------------------------------------------------------------
    def _radius(self, ti: int, om: np.ndarray, tabs: np.ndarray) -> np.ndarray:
        """True rolling radius of both wheels of truck ti over the substeps (R, 2, n)."""
        tm = self.trucks[ti]
        r = np.broadcast_to(tm.r0[None, :, None], om.shape).copy()
        eff = tm.eff
        if "ed" in eff and eff["ed"]["law"] == "speed":
            e = eff["ed"]
            v = om * tm.r0[None, :, None] / 1000.0  # m/s
            g = np.array([e["g_left"], e["g_right"]])[None, :, None]
            r = r * (1.0 + g * v * v)
        if "tire_compression" in eff and eff["tire_compression"]["law"] == "hertz":
            e = eff["tire_compression"]
            rn = tm.r_nom
            v = (om[:, 0] + om[:, 1]) * rn / 2.0
            w = (om[:, 1] - om[:, 0]) * rn / tm.b_nom
            alat = v * w  # mm/s^2, + turning left: load moves to the right wheel
            m = e["load_kg"]
            share_l = 0.5 + e["lateral_offset_mm"] / tm.b - alat * e["cg_height_mm"] / (G * tm.b)
            nl = np.maximum(m * 9.81 * share_l, 0.0)
            nr = np.maximum(m * 9.81 - nl, 0.0)
            c = e["c_mm_per_N23"]
            r = r - c * np.stack([nl ** (2 / 3), nr ** (2 / 3)], axis=1)
        if "diameter_drift" in eff:
            e = eff["diameter_drift"]
            ts = self.t_sess0[:, None, None] + tabs[None, None, :]
            beta = np.array([e["beta_left"], e["beta_right"]])[None, :, None]
            r = r * (1.0 + beta * (1.0 - np.exp(-ts / e["tau_s"])))
        return r

    def _edge_count(self, enc_angle: np.ndarray) -> np.ndarray:
        """Integer edge count of every encoder for encoder-shaft angles in wheel-side radians
        (R, trucks, 2, n): a disc of 4 x lines states per motor turn, states slightly unequal."""
        out = np.empty(enc_angle.shape, dtype=np.int64)
        for ti, tm in enumerate(self.trucks):
            c = enc_angle[:, ti] * (tm.cpr / (2 * np.pi)) + self.c0[:, ti, :, None]
            ecc = tm.eff.get("encoder_eccentricity")
            if ecc:
                amp = np.radians(np.array([ecc["amp_deg_left"], ecc["amp_deg_right"]]))
                ph = np.array([ecc["phase_left"], ecc["phase_right"]])
                c = c + (tm.cpr / (2 * np.pi)) * amp[None, :, None] * np.sin(
                    enc_angle[:, ti] * tm.gear + ph[None, :, None]
                )
            c = c + self.q_amp * np.sin(np.pi / 2 * c + self.q_ph[:, ti, :, None])
            out[:, ti] = np.floor(c).astype(np.int64)
        return out

    # --------------------------------------------------------------------------------------------
    def advance(self, cmd: np.ndarray) -> None:
        """One control tick with wheel speed commands cmd (R, trucks, 2) rad/s (wheel side;
        ignored for a passive trailer)."""
        R, n = self.R, self.n
        tabs = self.t + self.tk
        nt = len(self.trucks)
        poses = np.zeros((R, nt, 3, n + 1))
        enc = np.zeros((R, nt, 2, n))
        for ti, tm in enumerate(self.trucks):
            if not tm.driven:
                continue
            mot = self.motor
            om, ang, acc = laws.motor(
                self.om[:, ti], cmd[:, ti], mot["tau_s"], mot["accel_rad_s2"], self.tk, self.decay
            )
            self.om[:, ti] = om[..., -1]
            phm = self.phi_m[:, ti, :, None] + ang
            bl = tm.eff.get("gear_backlash")
            if bl:
                phw = laws.play(phm, self.phi_w[:, ti], math.radians(bl["play_deg"]) / 2)
            else:
                phw = phm
            dphw = laws.diff0(phw, self.phi_w[:, ti])
            self.phi_m[:, ti] = phm[..., -1]
            self.phi_w[:, ti] = phw[..., -1]
            enc[:, ti] = phm
            r = self._radius(ti, om, tabs)
            ds = r * dphw
            eff = tm.eff
            if "slip" in eff:
                e = eff["slip"]
                if e["law"] == "accel":
                    k1 = e["k_at_1"] * np.array([1 - e["asym"], 1 + e["asym"]])[None, :, None]
                    ds = laws.slip_accel(ds, acc * r, k1, e["p"], e["cap"])
                else:
                    ds = self._traction(ti, ds, r, om, e)
            dh = self._floor(ti, ds, driven=True)
            poses[:, ti] = self._integrate(ti, dh, tabs)
        if self.vehicle == "set":
            poses[:, 1], enc[:, 1] = self._trailer(poses[:, 0], tabs)
        if self.vehicle == "clapper":
            self._clamp(poses)
        dE = self._encoders(enc)
        self._decode(dE, tabs)
        self.pose = poses[..., -1].copy()
        self.t = float(tabs[-1])
        k = self.hist_every
        self.hist.t.append(tabs[k - 1 :: k])
        self.hist.pose.append(poses[..., k::k].copy())
        if self._events_on:
            self._log_events(poses, tabs)

    # --------------------------------------------------------------------------------------------
    def _traction(self, ti, ds, r, om, e) -> np.ndarray:
        """Friction-circle traction limit on a driven truck's wheels (sequential only when the
        limit is reached or the wheels are still catching up)."""
        dt = self.dt
        vw = ds / dt
        vg0 = self.vg[:, ti]
        tm = self.trucks[ti]
        v = (om[:, 0] + om[:, 1]) * tm.r_nom / 2.0
        w = (om[:, 1] - om[:, 0]) * tm.r_nom / tm.b_nom
        alat = np.abs(v * w)[:, None, :]
        amax = e["a_lim_m_s2"] * 1000.0
        along = np.sqrt(np.maximum(amax * amax - alat * alat, (0.05 * amax) ** 2))
        along = np.broadcast_to(along, vw.shape)
        dv = laws.diff0(vw, self.vw_last[:, ti])
        self.vw_last[:, ti] = vw[..., -1]
        gripping = np.abs(vg0 - (vw[..., 0] - dv[..., 0])) < 1e-9  # no spin left from before
        if (np.abs(dv) <= along * dt).all() and gripping.all():
            self.vg[:, ti] = vw[..., -1]  # gripping throughout
            return ds
        vg = laws.traction(vw, vg0, along, dt)
        self.vg[:, ti] = vg[..., -1]
        return vg * dt

    def _floor(self, ti: int, ds: np.ndarray, driven: bool) -> np.ndarray:
        """Floor: a driven wheel's rolled travel -> its hub's horizontal progress; a pushed
        (passive) wheel's horizontal progress -> the distance it rolls."""
        u = self.u_abs[:, ti, :, None] + np.cumsum(np.abs(ds), axis=-1)
        uu = np.minimum(u, self.U - 1)
        i = uu.astype(np.int64)
        flat = self.rough_flat[ti]
        base = self.rough_base[..., None]
        e_lo = flat[base + i]
        E = e_lo + (uu - i) * (flat[base + i + 1] - e_lo)
        dE = laws.diff0(E, self.E_last[:, ti])
        self.E_last[:, ti] = E[..., -1]
        self.u_abs[:, ti] = u[..., -1]
        sg = np.sign(ds)
        out = ds - sg * dE if driven else ds + sg * dE
        if self.cables:
            out = self._bumps(ti, out, driven)
        return out

    def _bumps(self, ti: int, d: np.ndarray, driven: bool) -> np.ndarray:
        """Obstacles: detect which wheels reach one within this tick, then map their travel."""
        tm = self.trucks[ti]
        s_prev = self.s_net[:, ti].copy()
        s = s_prev[..., None] + np.cumsum(d, axis=-1)
        self.s_net[:, ti] = s[..., -1]
        # detection from the pose at the start of the tick and this tick's travel
        mv = d.sum(axis=-1)  # (R, 2)
        sgn = np.where(mv >= 0, 1.0, -1.0)
        th = self.pose[:, ti, 2, None]
        hy = np.array([tm.b / 2, -tm.b / 2])[None, :]  # left hub at +b/2 in the body frame
        px = self.pose[:, ti, 0, None] - hy * np.sin(th)
        py = self.pose[:, ti, 1, None] + hy * np.cos(th)
        ux, uy = sgn * np.cos(th), sgn * np.sin(th)
        cx, cy, nx, ny, half, st0 = self._cable_arrays(ti)
        dn = (px[..., None] - cx) * nx + (py[..., None] - cy) * ny  # (R, 2, C)
        cosi = ux[..., None] * nx + uy[..., None] * ny
        ok = np.abs(cosi) >= 0.3
        lc = -dn / np.where(ok, cosi, 1.0)
        first = lc + st0[None] / np.maximum(np.abs(cosi), 0.3)
        reach = (np.abs(d).sum(axis=-1) + 2.0)[..., None]
        ok &= (first >= 0) & (first <= reach) & (np.abs(mv)[..., None] > 1e-6)
        along = (px[..., None] + ux[..., None] * lc - cx) * (-ny) + (
            py[..., None] + uy[..., None] * lc - cy
        ) * nx
        ok &= np.abs(along) <= half
        for r, w, ci in zip(*np.nonzero(ok), strict=True):
            if (r, ti, w) in self.bump:
                continue
            c = self.cables[ci]
            stretch = round(1.0 / abs(float(cosi[r, w, ci])), 2)
            bm = fl.bump_map(c.kind, c.h, c.width, c.slope_deg, float(tm.r0[w]), stretch)
            f0 = float(lc[r, w, ci]) + bm.start
            self.bump[(r, ti, w)] = [bm, s_prev[r, w] + sgn[r, w] * f0, sgn[r, w], ci, False]
        if not self.bump:
            return d
        out = d.copy()
        done = []
        for key, st in self.bump.items():
            r, t2, w = key
            if t2 != ti:
                continue
            bm, s0, sgn, _, _ = st
            sig = sgn * (np.concatenate([[s_prev[r, w]], s[r, w]]) - s0)
            if driven:
                out[r, w] = sgn * np.diff(bm.progress(sig))
            else:
                out[r, w] = sgn * np.diff(bm.rolled(sig))
            if sig[-1] > bm.sigma[-1] + 1.0 or sig[-1] < -60.0:
                done.append(key)
        for key in done:
            del self.bump[key]
        return out

    def _cable_arrays(self, ti: int):
        """Cable centres, normals, half lengths and unstretched first-contact offsets for the
        wheels of truck ti (cached)."""
        key = ("cables", ti)
        if key not in self._cache:
            tm = self.trucks[ti]
            cs = self.cables
            ang = np.array([c.ang for c in cs])
            st0 = np.array(
                [
                    [fl.bump_map(c.kind, c.h, c.width, c.slope_deg, float(tm.r0[w]), 1.0).start
                     for c in cs]
                    for w in range(2)
                ]
            )
            self._cache[key] = (
                np.array([c.x for c in cs]),
                np.array([c.y for c in cs]),
                -np.sin(ang),
                np.cos(ang),
                np.array([c.length / 2 for c in cs]),
                st0,
            )
        return self._cache[key]

    def _integrate(self, ti: int, dh: np.ndarray, tabs: np.ndarray) -> np.ndarray:
        """Truck pose over the substeps from its wheels' horizontal progress (R, 3, n+1)."""
        tm = self.trucks[ti]
        eff = tm.eff
        dl, dr = dh[:, 0], dh[:, 1]
        dt = self.dt
        b = tm.b
        dxb = (dl + dr) / 2.0
        if "eb" in eff and eff["eb"]["law"] == "load_patch":
            w0 = (dr - dl) / b / dt
            alat = np.abs(dxb / dt * w0)
            b = b * (1.0 + eff["eb"]["zeta"] * alat / G)
        dth = (dr - dl) / b
        if "scrub" in eff:
            e = eff["scrub"]
            if e["law"] == "inv_radius":
                dth = dth * laws.scrub_factor_inv_radius(dl, dr, e["c_mm"] / tm.b_nom)
            else:
                dth = laws.scrub_torque(dth, dl, dr, b, e["s_sat"], e["r_t_mm"])
        dyb = None
        skid = eff.get("skid")
        if skid and skid["law"] == "cornering":  # linear cornering stiffness: sideslip a_lat / c
            alat = (dxb / dt) * (dth / dt)
            dyb = -dxb * alat / (skid["c_alpha_m_s2"] * 1000.0)
        if self.castor and ti == 0:
            dth = dth + self._castor(dxb, dth)
        th0 = self.pose[:, ti, 2]
        out = np.empty((self.R, 3, self.n + 1))
        out[:, :, 0] = self.pose[:, ti]
        th = np.cumsum(dth, axis=-1)
        th += th0[:, None]
        out[:, 2, 1:] = th
        thm = th - dth * 0.5
        c, s = np.cos(thm), np.sin(thm)
        ds = dxb * (1.0 - dth * dth / 24.0)  # chord of the arc per substep (|dth| < 0.01)
        if dyb is None:
            ddx, ddy = ds * c, ds * s
        else:
            ddx, ddy = ds * c - dyb * s, ds * s + dyb * c
        if skid and skid["law"] == "friction":
            ddx, ddy = self._friction(ti, ddx, ddy, skid["a_lim_m_s2"] * 1000.0)
        np.cumsum(ddx, axis=-1, out=out[:, 0, 1:])
        np.cumsum(ddy, axis=-1, out=out[:, 1, 1:])
        out[:, 0, 1:] += self.pose[:, ti, 0, None]
        out[:, 1, 1:] += self.pose[:, ti, 1, None]
        return out

    def _friction(self, ti: int, ddx: np.ndarray, ddy: np.ndarray, alim: float):
        """The friction-circle skid (laws.friction_circle) on the truck's centre; only runs the
        sequential limiter in ticks where some run's wheels ask for more than the floor gives."""
        dt = self.dt
        tx, ty = ddx / dt, ddy / dt
        v0 = self.V[:, ti]
        jx = laws.diff0(tx, v0[:, 0])
        jy = laws.diff0(ty, v0[:, 1])
        if (np.hypot(jx, jy) <= alim * dt).all():
            self.V[:, ti, 0], self.V[:, ti, 1] = tx[:, -1], ty[:, -1]
            return ddx, ddy
        v = laws.friction_circle(tx, ty, v0, alim, dt)
        prev = np.concatenate([v0[..., None], v[..., :-1]], axis=-1)
        mid = (v + prev) * (0.5 * dt)
        self.V[:, ti] = v[..., -1]
        return mid[:, 0], mid[:, 1]

    def _castor(self, dxb: np.ndarray, dth: np.ndarray) -> np.ndarray:
        """Out of catalog: a trailing castor swivels after every change of the direction of
        travel; while it swivels, its contact scrubs sideways and yaws the truck
        (k tanh(relative swivel rate / 1 rad/s)). Returns the extra heading per substep."""
        e = self.castor
        dt = self.dt
        th = self.pose[:, 0, 2, None] + np.cumsum(dth, axis=-1)
        thp = np.concatenate([self.pose[:, 0, 2, None], th], axis=-1)
        thm = (thp[:, 1:] + thp[:, :-1]) / 2
        xc, trail = e["x_mm"], e["trail_mm"]
        # pivot velocity in the world frame per substep
        vx = (dxb * np.cos(thm) - xc * dth * np.sin(thm)) / dt
        vy = (dxb * np.sin(thm) + xc * dth * np.cos(thm)) / dt
        psi0 = self.psi
        psi = np.repeat(psi0[:, None], self.n + 1, axis=1)
        for _ in range(4):
            pm = (psi[:, 1:] + psi[:, :-1]) / 2
            rate = (-vx * np.sin(pm) + vy * np.cos(pm)) / trail
            psi = np.concatenate([psi0[:, None], psi0[:, None] + np.cumsum(rate * dt, axis=-1)], 1)
        self.psi = psi[:, -1]
        rel = np.diff(psi, axis=-1) / dt - dth / dt
        return e["k_rad_s"] * np.tanh(rel) * dt

    def _trailer(self, pa: np.ndarray, tabs: np.ndarray):
        """A passive trailer behind truck A: hitch hitch_offset behind A's centre, axle bar
        behind the hitch, no sideways motion of the axle (dphi/dt = (dH/dt . n(phi)) / bar),
        solved per tick by Picard iteration. Returns its pose (R, 3, n+1) and encoder angles."""
        tm = self.trucks[1]
        hx = pa[:, 0] - self.hitch * np.cos(pa[:, 2])
        hy = pa[:, 1] - self.hitch * np.sin(pa[:, 2])
        dhx, dhy = np.diff(hx, axis=-1), np.diff(hy, axis=-1)
        phi0 = self.pose[:, 1, 2]
        phi = np.repeat(phi0[:, None], self.n + 1, axis=1)
        for _ in range(6):  # contracts by |dH| / bar per tick: a few iterations reach 1e-12
            pm = (phi[:, 1:] + phi[:, :-1]) * 0.5
            dphi = (dhy * np.cos(pm) - dhx * np.sin(pm)) * (1.0 / self.bar)
            new = np.cumsum(dphi, axis=-1)
            new += phi0[:, None]
            done = np.abs(new - phi[:, 1:]).max() < 1e-12
            phi[:, 1:] = new
            if done:
                break
        ax = hx - self.bar * np.cos(phi)
        ay = hy - self.bar * np.sin(phi)
        pm = (phi[:, 1:] + phi[:, :-1]) / 2
        dphi = np.diff(phi, axis=-1)
        along = np.diff(ax, axis=-1) * np.cos(pm) + np.diff(ay, axis=-1) * np.sin(pm)
        hw = np.stack([along - dphi * tm.b / 2, along + dphi * tm.b / 2], axis=1)  # (R, 2, n)
        rolled = self._floor(1, hw, driven=False)
        r = self._radius(1, np.zeros_like(rolled), tabs)
        phw = self.phi_w[:, 1, :, None] + np.cumsum(rolled / r, axis=-1)
        self.phi_w[:, 1] = phw[..., -1]
        self.phi_m[:, 1] = phw[..., -1]
        return np.stack([ax, ay, phi], axis=1), phw

    def _clamp(self, poses: np.ndarray) -> None:
        """The clapper's compliant link is force-free within its mechanical range; at an end
        stop it pushes both trucks apart (or together) along the link, which no wheel sees."""
        lo, hi = self.case["robot"]["linkage"]["range_mm"]
        dx = poses[:, 0, 0] - poses[:, 1, 0]
        dy = poses[:, 0, 1] - poses[:, 1, 1]
        ln = np.hypot(dx, dy)
        over = np.maximum.accumulate(np.maximum(ln - hi, 0.0), axis=-1)
        under = np.maximum.accumulate(np.maximum(lo - ln, 0.0), axis=-1)
        c = over - under
        if not c.any():
            return
        self.clamps += (c[:, -1] != 0).astype(np.int64)
        ux, uy = dx / ln, dy / ln
        poses[:, 0, 0] -= c / 2 * ux
        poses[:, 0, 1] -= c / 2 * uy
        poses[:, 1, 0] += c / 2 * ux
        poses[:, 1, 1] += c / 2 * uy

    def _encoders(self, enc: np.ndarray) -> np.ndarray:
        e = self._edge_count(enc)
        dE = laws.diff0(e, self.edges)
        self.edges = e[..., -1]
        return dE

    def _decode(self, dE: np.ndarray, tabs: np.ndarray) -> None:
        """Decoders: count the edges, or lose some (count_loss laws); skipped states raise the
        Status bits of the sample."""
        self.status[:] = 0
        for ti, tm in enumerate(self.trucks):
            d = dE[:, ti]
            cl = tm.eff.get("count_loss")
            if cl is None:
                self.decoded[:, ti] += d.sum(axis=-1)
                continue
            if cl["law"] == "rate_limit":
                fs = cl["f_max_hz"]
                ph = self.dec_phase[:, ti, :, None]
                tt = np.concatenate([[tabs[0] - self.dt], tabs])
                clk = np.floor(tt[None, None, :] * fs + ph)
                got, skip = laws.decode_saturating(d, np.diff(clk, axis=-1).astype(np.int64))
            else:
                rate = np.abs(d) / self.dt
                p = laws.missed_prob(rate, cl["r50_hz"], cl["width_hz"], cl["p_max"])
                miss = self.rng.binomial(np.abs(d), np.clip(p, 0, 1))
                lost = np.minimum(2 * miss, np.abs(d))
                got = d - np.sign(d) * lost
                skip = miss > 0
            self.decoded[:, ti] += got.sum(axis=-1)
            sk = skip.any(axis=-1)  # (R, 2)
            self.status[:, ti] |= sk[:, 0].astype(np.int64) | (sk[:, 1].astype(np.int64) << 1)

    def counters(self) -> np.ndarray:
        """The decoders' counters as the firmware reads them (R, trucks, 2), int64 unwrapped,
        sign as wired (an inverted encoder counts down going forward)."""
        out = self.decoded.copy()
        for ti, tm in enumerate(self.trucks):
            for w in range(2):
                if tm.invert[w]:
                    out[:, ti, w] = -out[:, ti, w]
        return out

    def _log_events(self, poses: np.ndarray, tabs: np.ndarray) -> None:
        for key, st in self.bump.items():
            r, ti, w = key
            if st[4]:
                continue
            bm, s0, sgn, ci, _ = st
            sig = sgn * (self.s_net[r, ti, w] - s0)
            if sig < bm.sigma[-1] / 2:
                continue
            st[4] = True
            tm = self.trucks[ti]
            hy = tm.b / 2 if w == 0 else -tm.b / 2
            x, y, th = poses[r, ti, 0, -1], poses[r, ti, 1, -1], poses[r, ti, 2, -1]
            self.events.append(
                {
                    "run_index": r,
                    "truck": ti,
                    "wheel": w,
                    "x_mm": float(x - hy * math.sin(th)),
                    "y_mm": float(y + hy * math.cos(th)),
                    "t_s": float(tabs[-1]),
                    "cable": ci,
                    "excess_mm": bm.excess,
                }
            )

    def history(self) -> tuple[np.ndarray, np.ndarray]:
        """Times (m,) and true poses (R, trucks, 3, m) at the history's sample rate."""
        return np.concatenate(self.hist.t), np.concatenate(self.hist.pose, axis=-1)
