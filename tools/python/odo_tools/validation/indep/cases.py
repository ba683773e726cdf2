"""Drawing a case: the robot (nominal and true), the runs it drives, its effect(s) with the law
and size of each, and the fidelity of every sensor. Everything a case is lives in its key (a
JSON-serialisable dict); simulate.py turns a key and a seed into recorded data.
"""

from __future__ import annotations

import json
import math

import numpy as np

from . import paths

# catalog effect -> the laws this world implements for it (README.md has the equations)
EFFECTS: dict[str, list[str]] = {
    "ed": ["fixed", "speed"],
    "eb": ["fixed", "load_patch"],
    "es": ["diameter", "deflection"],
    "bumps": ["steps", "ramps"],
    "roughness": ["grains", "surface"],
    "slip": ["accel", "traction"],
    "skid": ["friction", "cornering"],
    "count_loss": ["rate_limit", "missed"],
    "scrub": ["inv_radius", "torque"],
    "tire_compression": ["linear", "hertz"],
    "rotary_bias": ["constant", "eccentric"],
    "link_bias": ["constant", "eccentric"],
}
OUT_OF_CATALOG: list[str] = [
    "diameter_drift",
    "gear_backlash",
    "encoder_eccentricity",
    "castor_swivel",
    "clock_drift",
]
OOC_LAW = {
    "diameter_drift": "thermal",
    "gear_backlash": "play",
    "encoder_eccentricity": "once_per_turn",
    "castor_swivel": "trailing",
    "clock_drift": "linear",
}
TWO_TRUCK_ONLY = {"rotary_bias": ("clapper", "set"), "link_bias": ("clapper",)}
DRIVE_EFFECTS = {"slip", "skid", "scrub"}  # act where a motor drives a wheel
FLOOR_EFFECTS = {"bumps", "roughness"}  # act on every wheel that rolls over the floor
TICKS_MS = [10, 20, 25, 40, 50, 100]
# Counter widths drawn: what the repo's robot validator (host_sim robot.c) accepts today; the
# firmware takes 8-32 already (odo_odometry.h), real decoders have 8, 12, 16, 24 or 32 bits.
COUNTER_BITS = [16, 24, 32]


def _f(x) -> float:
    return float(x)


def _logu(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _sign(rng: np.random.Generator) -> float:
    return float(rng.choice([-1.0, 1.0]))


def catalog_choices(vehicle: str) -> list[str]:
    return [e for e in EFFECTS if vehicle in TWO_TRUCK_ONLY.get(e, (vehicle,))]


def ooc_choices(vehicle: str) -> list[str]:
    if vehicle == "labmate":
        return list(OUT_OF_CATALOG)
    return [e for e in OUT_OF_CATALOG if e != "castor_swivel"]


# ------------------------------------------------------------------------------------------------
# the robot
# ------------------------------------------------------------------------------------------------


def _encoder(rng, need: str) -> tuple[int, float]:
    """(encoder_lines, gear_ratio) for a wanted kind of drive train."""
    if need == "wheel":  # encoder on the wheel shaft
        return int(rng.choice([256, 360, 512, 1000, 1024, 2048, 4096])), 1.0
    if need == "high":
        cpr = _logu(rng, 30000, 200000)
    elif need == "geared":
        cpr = _logu(rng, 2000, 100000)
    else:
        cpr = _logu(rng, 100, 200000)  # the firmware's parameter block wants >= 100
    gears = [1.0, 3.7, 5.0, 10.0, 14.0, 19.5, 30.0, 43.7, 50.0]
    if need == "geared":
        gears = gears[2:]
    g = float(rng.choice([x for x in gears if cpr / (4 * x) >= 4] or [1.0]))
    return max(4, math.ceil(max(cpr, 100.0) / (4 * g))), g


def _truck(rng, D: float, b: float, lines: int, gear: float, bits: int) -> dict:
    return {
        "wheel_diameter_mm": round(D, 2),
        "wheelbase_mm": round(b, 1),
        "encoder_lines": lines,
        "gear_ratio": gear,
        "counter_bits": bits,
        "decoder": "hctl1100",
        "invert_left": bool(rng.uniform() < 0.3),
        "invert_right": False,
    }


def _bits(rng, vmax: float, T: float, trucks: list[tuple[float, int, float]]) -> int:
    """One counter width for the robot (the firmware has one), wide enough that a cycle's count
    stays far below half its range on every truck."""
    per_tick = max(vmax * 1.5 * T / (math.pi * D) * 4 * ln * g for D, ln, g in trucks)
    return int(rng.choice([x for x in COUNTER_BITS if per_tick < (1 << (x - 1)) / 4]))


def draw_robot(rng: np.random.Generator, vehicle: str, need: str) -> dict:
    """The nominal description (what the firmware believes). need: encoder drive train."""
    D = _logu(rng, 50, 300)
    b = float(np.clip(D * rng.uniform(1.8, 6.0), 150, 800))
    tick = int(rng.choice(TICKS_MS))
    vmax = float(np.clip(rng.uniform(4.0, 12.0) * D, 500, 3000))  # wheel surface speed, mm/s
    lines, gear = _encoder(rng, need)
    T = tick / 1000
    drives = [(D, lines, gear)]
    if vehicle == "set":
        Db = _logu(rng, 50, 150)
        bb = float(np.clip(b * rng.uniform(0.6, 1.2), 150, 800))
        lb, gb = _encoder(rng, "wheel" if need != "high" else "high")
        drives.append((Db, lb, gb))
    bits = _bits(rng, vmax, T, drives)
    rob = {
        "vehicle": vehicle,
        "description": "A robot of the independent world (odo_tools.validation.indep).",
        "tick_ms": tick,
        "heading_form": "midpoint",
        "ipec": "off",
        "max_wheel_speed_mm_s": round(vmax),
        "trucks": {"A": _truck(rng, D, b, lines, gear, bits)},
    }
    if vehicle == "clapper":
        rob["trucks"]["B"] = dict(rob["trucks"]["A"])
        rob["trucks"]["B"]["invert_left"] = bool(rng.uniform() < 0.3)
        L = float(round(rng.uniform(2.0, 4.0) * b, -1))
        half = float(round(rng.uniform(0.08, 0.15) * L))
        rob["linkage"] = {
            "length_mm": L,
            "range_mm": [L - half, L + half],
            "rotary_bits": int(rng.choice([10, 11, 12, 14])),
            "linear_resolution_mm": float(rng.choice([0.01, 0.02, 0.05, 0.1])),
        }
    elif vehicle == "set":
        rob["trucks"]["B"] = _truck(rng, Db, bb, lb, gb, bits)
        rob["trailer"] = {
            "hitch_offset_mm": float(round(rng.uniform(0.3, 0.9) * b)),
            "trailer_length_mm": float(round(rng.uniform(1.2, 3.0) * bb)),
            "rotary_bits": int(rng.choice([10, 11, 12, 14])),
        }
    return rob


# ------------------------------------------------------------------------------------------------
# the runs
# ------------------------------------------------------------------------------------------------


def draw_controller(rng, rob: dict, effects: list[str]) -> dict:
    A = rob["trucks"]["A"]
    b = A["wheelbase_mm"]
    vw = rob["max_wheel_speed_mm_s"]
    v = min(rng.uniform(250, 800), 0.6 * vw)
    acc = rng.uniform(400, 1200)
    alat = rng.uniform(400, 1200)
    if "slip" in effects:
        acc = rng.uniform(900, 1600)
    dec = acc * rng.uniform(1.0, 1.6)
    if "skid" in effects:  # brisk turns, gentle starts and stops
        alat = rng.uniform(1300, 2500)
        v = min(max(v, 700.0), 0.7 * vw)
        acc = rng.uniform(300, 500)
        dec = acc * rng.uniform(1.0, 1.3)
    w_spin = min(rng.uniform(0.6, 2.0), 0.6 * vw / (b / 2))
    if "count_loss" in effects:
        v = min(max(v, 500.0), 0.7 * vw)
    return {
        "v_mm_s": _f(v),
        "a_mm_s2": _f(acc),
        "d_mm_s2": _f(dec),
        "jerk_s": _f(rng.uniform(0.05, 0.3)),
        "a_lat_mm_s2": _f(alat),
        "w_rad_s": _f(w_spin),
        "alpha_rad_s2": _f(rng.uniform(1.5, 5.0)),
        "pause_s": _f(rng.uniform(0.3, 1.0)),
        "cmd_accel_mm_s2": _f(2.5 * max(acc, alat)),
        "settle_s": 1.0,
    }


def limits(case: dict, run: dict | None = None) -> paths.Limits:
    """The planner's bounds; a run may ask for its own cruise speed (a sprint)."""
    c = case["controller"]
    A = case["robot"]["trucks"]["A"]
    return paths.Limits(
        v=(run or {}).get("v_mm_s", c["v_mm_s"]),
        a=c["a_mm_s2"],
        d=c["d_mm_s2"],
        jerk_s=c["jerk_s"],
        a_lat=c["a_lat_mm_s2"],
        w=c["w_rad_s"],
        alpha=c["alpha_rad_s2"],
        v_wheel=0.9 * case["robot"]["max_wheel_speed_mm_s"],
        b=A["wheelbase_mm"],
        pause=c["pause_s"],
    )


def _r(x: float) -> float:
    return float(round(x, -1))


def _duration(segs: list, lim: paths.Limits) -> float:
    return paths.duration([tuple(s) for s in segs], lim)


def _fit(segs: list, lim: paths.Limits, max_s: float, rmin: float) -> list:
    """Shrink a run (lengths and radii, radii not below rmin; then arc and spin angles) until
    it lasts at most max_s."""
    for _ in range(6):
        d = _duration(segs, lim)
        if d <= max_s:
            break
        f = max(0.5, 0.97 * max_s / d)
        out = []
        for sg in segs:
            if sg[0] == "line":
                out.append(("line", sg[1] * f))
            elif sg[0] == "arc":
                r = max(sg[1] * f, rmin)
                ang = sg[2] if r > rmin + 1e-9 else sg[2] * f
                out.append(("arc", r, ang))
            else:
                out.append(sg if abs(sg[1]) <= math.pi / 2 + 1e-9 else ("spin", sg[1] * f))
        segs = out
    return segs


def _rmin(rob: dict) -> float:
    """The tightest arc radius the plan drives (mm): what the vehicle's linkage or trailer and
    its wheelbase allow."""
    if rob["vehicle"] == "clapper":
        rmin = 0.8 * rob["linkage"]["length_mm"]
    elif rob["vehicle"] == "set":
        rmin = 1.2 * (rob["trailer"]["hitch_offset_mm"] + rob["trailer"]["trailer_length_mm"])
    else:
        rmin = 0.75 * rob["trucks"]["A"]["wheelbase_mm"]
    return max(rmin, 300.0)


def _max_run_s(rob: dict) -> float:
    return min(50.0, max(30.0, 2500 * rob["tick_ms"] / 1000))


def draw_plan(rng: np.random.Generator, case: dict, effects: list[str]) -> list[dict]:
    """6-13 runs of several shapes; UMBmark squares in both directions always among them (a
    case with count loss drives its sprint twice). A run lasts at most max(30 s, 2500 control
    cycles) and 50 s."""
    rob = case["robot"]
    veh = rob["vehicle"]
    b = rob["trucks"]["A"]["wheelbase_mm"]
    side = float(np.clip(round(rng.uniform(6, 14) * b, -2), 1000, 5000))
    rmin = _rmin(rob)
    corner = 0.0 if veh == "labmate" else _r(min(rng.uniform(1.0, 1.6) * rmin, side / 2.5))
    if corner:
        side = max(side, _r(2.6 * corner))
    n_sq = int(rng.integers(2, 4))
    plan = []
    for ccw in (False, True):
        for _ in range(n_sq):
            lab = "ccw" if ccw else "cw"
            plan.append({"label": lab, "shape": "square", "segs": paths.square(side, ccw, corner)})
    shapes = ["circle", "circle", "eight", "oval", "drive", "outback"]
    if veh == "labmate":
        shapes += ["spin", "shuttle", "spin"]
    if "scrub" in effects or "skid" in effects:
        shapes += ["circle", "circle", "eight"]
    n_more = int(rng.integers(max(6 - len(plan), 2), min(12 - len(plan), 6) + 1))
    for _ in range(n_more):
        sh = str(rng.choice(shapes))
        ccw = bool(rng.uniform() < 0.5)
        R = _r(_logu(rng, rmin, max(rmin * 1.01, min(8 * b, 3000.0, side))))
        if sh == "circle":
            plan.append({"label": "circleccw" if ccw else "circlecw", "shape": sh,
                         "segs": paths.circle(R, ccw, float(rng.choice([1.0, 1.5, 2.0])))})
        elif sh == "eight":
            plan.append({"label": "eight", "shape": sh, "segs": paths.eight(R, ccw)})
        elif sh == "oval":
            L = _r(rng.uniform(1.0, 2.5) * R)
            plan.append({"label": "oval", "shape": sh, "segs": paths.oval(L, R, ccw)})
        elif sh == "outback":
            L = _r(rng.uniform(0.6, 1.2) * side)
            segs = (
                paths.outback(L, ccw)
                if veh == "labmate"
                else [("line", L), ("arc", R, math.pi), ("line", L), ("arc", R, math.pi)]
            )
            plan.append({"label": "outback", "shape": sh, "segs": segs})
        elif sh == "shuttle":
            L = _r(rng.uniform(0.6, 1.2) * side)
            plan.append({"label": "shuttle", "shape": sh, "segs": paths.shuttle(L)})
        elif sh == "spin":
            angs = [float(_sign(rng) * rng.choice([math.pi, 1.5 * math.pi, 2 * math.pi]))
                    for _ in range(int(rng.integers(3, 6)))]
            plan.append({"label": "spin", "shape": sh, "segs": paths.spins(angs)})
        else:
            segs = paths.drive(rng, int(rng.integers(5, 10)), rmin, max(3 * rmin, 2000.0), side)
            plan.append({"label": "drive", "shape": sh, "segs": segs})
    if "skid" in effects:  # tight circles at speed: the turns that ask most of the floor
        for i in range(2):
            R = _r(rng.uniform(1.0, 1.6) * rmin)
            ccw = bool(rng.uniform() < 0.5)
            plan[-1 - i] = {"label": "circleccw" if ccw else "circlecw", "shape": "circle",
                            "segs": paths.circle(R, ccw, 2.0)}
    if "count_loss" in effects:  # a straight sprint: the one place the wheels run fastest
        L = _r(rng.uniform(0.8, 1.2) * side)
        sprint = {"label": "sprint", "shape": "sprint", "v_mm_s": _f(min(
            case["controller"]["v_mm_s"] * rng.uniform(1.4, 1.7),
            0.85 * rob["max_wheel_speed_mm_s"]))}
        sprint["segs"] = paths.shuttle(L) if veh == "labmate" else [("line", L)]
        plan[-1] = sprint
    max_s = _max_run_s(rob)
    for p in plan:
        p["segs"] = _fit(p["segs"], limits(case, p), max_s, rmin)
    order = rng.permutation(len(plan))
    plan = [plan[i] for i in order]
    if "count_loss" in effects:
        # the sprint is driven twice, like every path a diagnosis is to fit on one run and judge
        # on another: the only path fast enough to lose counts, driven once, was either fitted
        # or judged. Inserted after the draws, so every other run of every case is as before.
        i = next(i for i, p in enumerate(plan) if p["shape"] == "sprint")
        plan.insert(i + 1, {**plan[i], "segs": list(plan[i]["segs"])})
    counts: dict[str, int] = {}
    for p in plan:
        counts[p["label"]] = counts.get(p["label"], 0) + 1
        p["name"] = f"run-{p['label']}-{counts[p['label']]:02d}"
        p["segs"] = [[s[0], *map(float, s[1:])] for s in p["segs"]]
    return plan


# ------------------------------------------------------------------------------------------------
# the effects
# ------------------------------------------------------------------------------------------------


def _scope(rng, name: str, vehicle: str) -> str:
    if name in ("rotary_bias", "link_bias", "clock_drift") or name in FLOOR_EFFECTS:
        return "vehicle"
    if vehicle == "labmate":
        return "A"
    if vehicle == "set":
        if name in DRIVE_EFFECTS or name in OUT_OF_CATALOG:
            return "A"
        return str(rng.choice(["A", "B"]))
    if name in OUT_OF_CATALOG:
        return "A"
    return str(rng.choice(["A", "B", "both"]))


def _cables(rng, case: dict, law: str) -> list[dict]:
    """Obstacles on the floor where the runs pass: across leg 1 of the squares (every square
    and most shapes start there) and on the other legs, each under one wheel's track."""
    rob = case["robot"]
    b = rob["trucks"]["A"]["wheelbase_mm"]
    sq = next(p for p in case["plan"] if p["shape"] == "square")
    side = sq["segs"][0][1]
    n = int(rng.integers(2, 7))
    out = []
    for i in range(n):
        leg = 0 if i < max(1, n // 2) else int(rng.integers(1, 4))
        ccw = bool(rng.uniform() < 0.5)
        u = rng.uniform(0.25, 0.75) * side
        wheel_y = _sign(rng) * b / 2
        if leg == 0:
            x, y, ang = u, wheel_y, math.pi / 2
        else:
            sg = 1 if ccw else -1
            corners = [(side, 0.0), (side, sg * side), (0.0, sg * side)]
            dirs = [(0, sg), (-1, 0), (0, -sg)]
            cx, cy = corners[leg - 1]
            dx, dy = dirs[leg - 1]
            x, y = cx + dx * u - dy * wheel_y, cy + dy * u + dx * wheel_y
            ang = math.atan2(dy, dx) + math.pi / 2
        ang += math.radians(rng.uniform(-15, 15))
        if law == "steps":
            kind, h = "step", rng.uniform(3, 15)
            width, slope = rng.choice([0.0, rng.uniform(5, 40)]), 0.0
        elif rng.uniform() < 0.5:
            kind, h = "ramp", rng.uniform(8, 25)
            width, slope = rng.uniform(20, 80), rng.uniform(10, 30)
        else:
            kind, h, width, slope = "round", rng.uniform(4, 15), 0.0, 0.0
        out.append({"x": _f(x), "y": _f(y), "angle_deg": _f(math.degrees(ang)),
                    "length_mm": _f(0.5 * b), "kind": kind, "h_mm": _f(h),
                    "width_mm": _f(width), "slope_deg": _f(slope)})
    return out


FRICTION_START = 1.25  # a friction-circle floor gives starts and stops this margin at least
FRICTION_MIN = 200.0  # mm/s^2: the least grip a floor that is not ice gives (mu 0.02)


def draw_effect(rng, name: str, case: dict) -> tuple[dict, dict]:
    """One effect: (true law parameters, catalog-equivalent params)."""
    rob = case["robot"]
    veh = rob["vehicle"]
    law = str(rng.choice(EFFECTS[name])) if name in EFFECTS else OOC_LAW[name]
    e: dict = {"law": law, "truck": _scope(rng, name, veh)}
    tname = "B" if e["truck"] == "B" else "A"
    tr = rob["trucks"][tname]
    r = tr["wheel_diameter_mm"] / 2
    b = tr["wheelbase_mm"]
    mech = case["true"]["mech"]
    ctl = case["controller"]
    p: dict = {}
    if name == "ed":
        if law == "fixed":
            e["value"] = 1.0 + _sign(rng) * _logu(rng, 0.001, 0.01)
            p["ed.value"] = e["value"]
        else:
            e["value0"] = 1.0 + _sign(rng) * rng.uniform(0.0005, 0.005)
            g = _f(rng.uniform(0.002, 0.01))
            e["g_left"], e["g_right"] = (g, 0.0) if rng.uniform() < 0.5 else (0.0, g)
    elif name == "eb":
        if law == "fixed":
            e["value"] = 1.0 + _sign(rng) * _logu(rng, 0.005, 0.03)
            p["eb.value"] = e["value"]
        else:
            e["value0"] = 1.0 + _sign(rng) * rng.uniform(0.003, 0.02)
            e["zeta"] = _f(rng.uniform(0.05, 0.2))
            p["eb.value"] = e["value0"]
    elif name == "es":
        if law == "diameter":
            e["value"] = 1.0 + _sign(rng) * _logu(rng, 0.003, 0.02)
            p["es.value"] = e["value"]
        else:
            e["deflection_mm"] = _f(3 * r * rng.uniform(0.003, 0.015))
            p["es.value"] = r / (r - e["deflection_mm"] / 3)
    elif name == "bumps":
        e["cables"] = _cables(rng, case, law)
        p["bumps.height_mm"] = float(np.mean([c["h_mm"] for c in e["cables"]]))
    elif name == "roughness":
        if law == "grains":
            e.update(rate_per_m=_f(rng.uniform(25, 60)), height_mm=_f(rng.uniform(0.4, 1.0)),
                     shape_w=_f(rng.uniform(2, 6)))
        else:
            e.update(sigma_mm=_f(rng.uniform(0.3, 0.6)), corr_mm=_f(rng.uniform(4, 8)))
    elif name == "slip":
        if law == "accel":
            e.update(k_at_1=_f(rng.uniform(0.02, 0.08)), p=_f(rng.uniform(1.2, 2.5)), cap=0.3,
                     asym=_f(rng.uniform(-0.3, 0.3)))
        else:
            e["a_lim_m_s2"] = _f(rng.uniform(0.7, 0.95) * ctl["a_mm_s2"] / 1000)
    elif name == "skid":
        alat = _peak_plan(case)[1]  # the hardest turn of the plan, mm/s^2
        u = rng.uniform()  # one draw either law (the cases after this one stay as they were)
        a_lim = (0.6 + 0.25 * u) * alat
        if law == "friction" and a_lim < FRICTION_MIN:
            # no floor short of ice lies below this plan's turns (a set's or clapper's wide
            # arcs): its tyres' cornering stiffness is what skids there
            law = e["law"] = "cornering"
        if law == "friction":  # the hardest turns ask for more than the floor gives; starts do not
            e["a_lim_m_s2"] = _f(a_lim / 1000)
            a_long = max(ctl["a_mm_s2"], ctl["d_mm_s2"])
            if a_long * FRICTION_START > a_lim:
                # a plan whose tightest arcs are gentle (a clapper's long linkage) gets gentler
                # starts and stops, and its runs are shortened again to the time bound. Taking
                # the larger of the two instead left the floor above every turn: a skid that
                # never acted (seed 2731 case 43)
                f = a_lim / (a_long * FRICTION_START)
                ctl["a_mm_s2"], ctl["d_mm_s2"] = _f(ctl["a_mm_s2"] * f), _f(ctl["d_mm_s2"] * f)
                for run in case["plan"]:
                    run["segs"] = _fit(run["segs"], limits(case, run), _max_run_s(rob), _rmin(rob))
        else:
            e["c_alpha_m_s2"] = _f(alat / 1000 / math.radians(1 + 4 * u))
    elif name == "count_loss":
        # the fastest any wheel of the truck runs in the plan (edges/s): one wheel losing a
        # per cent of its counts in a turn costs degrees, so the losses are kept to the peaks
        cpr = 4 * tr["encoder_lines"] * tr["gear_ratio"]
        peak = _peak_plan(case)[0] / (2 * math.pi * r) * cpr
        if law == "rate_limit":
            fs = float(np.clip(rng.uniform(1.02, 1.1) * peak, 1e5 / 3, 2e6 / 3))
            e["f_max_hz"] = fs
            p["count_loss.f_clk_hz"] = 3 * fs
            top = fs * rng.uniform(1.05, 1.3)
        else:
            e.update(r50_hz=_f(rng.uniform(0.9, 1.2) * peak),
                     width_hz=_f(rng.uniform(0.03, 0.1) * peak),
                     p_max=_f(rng.uniform(0.0005, 0.003)))
            top = e["r50_hz"] + e["width_hz"] * rng.uniform(0.0, 2.0)
        for run in case["plan"]:  # the sprint runs just above the decoder's limit
            if run["shape"] == "sprint":
                v = top / cpr * 2 * math.pi * r
                run["v_mm_s"] = _f(min(v, 0.9 * rob["max_wheel_speed_mm_s"]))
    elif name == "scrub":
        if law == "inv_radius":
            # either sign: skid-steer-like turns make spot turns the widest (c > 0), while real
            # robots have also shown arcs wider than spot turns (c < 0, firmware k > 0)
            e["c_mm"] = _f(_sign(rng) * b * rng.uniform(0.0025, 0.015))
            p["scrub.k"] = -2 * e["c_mm"] / b
        else:
            e.update(s_sat=_f(rng.uniform(0.005, 0.025)), r_t_mm=_f(rng.uniform(1.5, 4) * b / 2))
    elif name == "tire_compression":
        load = _f(mech["mass_kg"] * rng.uniform(0.5, 1.5))
        off = _f(rng.uniform(-0.15, 0.15) * b)
        delta = r * rng.uniform(0.002, 0.008)  # mean deflection: Es 0.2-0.8 %
        if law == "linear":
            e.update(k_mm_per_kg=_f(delta / (load / 2)), load_kg=load, lateral_offset_mm=off)
            p.update({"tire_compression.k_mm_per_kg": e["k_mm_per_kg"],
                      "tire_compression.load_kg": load,
                      "tire_compression.lateral_offset_mm": off})
        else:
            n23 = (load * 9.81 / 2) ** (2 / 3)
            e.update(c_mm_per_N23=_f(delta / n23), load_kg=load,
                     lateral_offset_mm=off, cg_height_mm=_f(mech["cg_height_mm"]))
    elif name == "rotary_bias":
        two = veh == "clapper"
        if law == "constant":
            e["alpha_deg"] = _sign(rng) * rng.uniform(0.3, 3.0)
            e["beta_deg"] = _sign(rng) * rng.uniform(0.3, 3.0) if two else 0.0
            p["rotary_bias.alpha_deg"] = e["alpha_deg"]
            p["rotary_bias.beta_deg"] = e["beta_deg"]
        else:
            for k in ("alpha", "beta"):
                on = k == "alpha" or two
                e[k] = [_f(_sign(rng) * rng.uniform(0.2, 2.0)) if on else 0.0,
                        _f(rng.uniform(0.3, 2.0)) if on else 0.0, _f(rng.uniform(0, 2 * math.pi))]
    elif name == "link_bias":
        if law == "constant":
            e["const_mm"] = _sign(rng) * rng.uniform(0.5, 5.0)
        else:
            e["const_mm"] = _sign(rng) * rng.uniform(0.0, 3.0)
            for k in ("dA_mm", "dB_mm"):
                a = rng.uniform(0, 2 * math.pi)
                m = rng.uniform(2, 15)
                e[k] = [_f(m * math.cos(a)), _f(m * math.sin(a))]
        p["link_bias.const_mm"] = e["const_mm"]
    elif name == "diameter_drift":
        big = rng.uniform(0.003, 0.012) * _sign(rng)
        small = big * rng.uniform(0.0, 0.5)
        e["beta_left"], e["beta_right"] = (big, small) if rng.uniform() < 0.5 else (small, big)
        e["tau_s"] = _f(rng.uniform(100, 600))
    elif name == "gear_backlash":
        e["play_deg"] = _f(rng.uniform(1.5, 5.0))
    elif name == "encoder_eccentricity":
        e.update(amp_deg_left=_f(rng.uniform(1, 3)), amp_deg_right=_f(rng.uniform(1, 3)),
                 phase_left=_f(rng.uniform(0, 2 * math.pi)),
                 phase_right=_f(rng.uniform(0, 2 * math.pi)))
    elif name == "castor_swivel":
        e.update(x_mm=_f(-rng.uniform(0.3, 0.8) * b), trail_mm=_f(rng.uniform(20, 60)),
                 k_rad_s=_f(_sign(rng) * rng.uniform(0.02, 0.08)))
    elif name == "clock_drift":
        e.update(ppm=_f(_sign(rng) * rng.uniform(200, 1000)), offset_s=_f(rng.uniform(0.01, 0.05)))
    else:
        raise ValueError(name)
    for k, v in list(e.items()):
        if isinstance(v, (np.floating, np.integer)):
            e[k] = float(v)
    return e, {k: float(v) for k, v in p.items()}


def _peak_plan(case: dict) -> tuple[float, float]:
    """Largest wheel surface speed (mm/s) and lateral acceleration (mm/s^2) truck A's plan asks
    for, sprints aside."""
    if "_peak" not in case:
        v_w = a_lat = 0.0
        for p in case["plan"]:
            if p["shape"] == "sprint":
                continue
            lim = limits(case, p)
            ref = paths.build([tuple(s) for s in p["segs"]], lim)
            v_w = max(v_w, float(np.max(np.abs(ref.v) + np.abs(ref.w) * lim.b / 2)))
            a_lat = max(a_lat, float(np.max(np.abs(ref.v * ref.w))))
        case["_peak"] = (v_w, a_lat)
    return case["_peak"]


def visible(name: str, scope: str, vehicle: str) -> dict[str, bool]:
    """In which evidence modes the effect can be seen at all (returns are truck A's)."""
    two = vehicle != "labmate"
    return {
        "truth": True,
        "returns": name not in ("rotary_bias", "link_bias", "clock_drift") and scope != "B",
        "linkage": two and name != "clock_drift",
    }


# ------------------------------------------------------------------------------------------------
# the fidelity (sensors and background)
# ------------------------------------------------------------------------------------------------


def draw_fidelity(rng, rob: dict) -> dict:
    T = rob["tick_ms"] / 1000
    dts = [d for d in (0.0005, 0.001, 0.002) if abs(T / d - round(T / d)) < 1e-9 and T / d <= 50]
    lever = {}
    for t in rob["trucks"]:
        if rng.uniform() < 0.5:
            a, m = rng.uniform(0, 2 * math.pi), rng.uniform(0, 30)
            lever[t] = [_f(m * math.cos(a)), _f(m * math.sin(a))]
        else:
            lever[t] = [0.0, 0.0]
    return {
        "physics_dt_s": float(rng.choice(dts)),
        "truth_rate_hz": float(rng.choice([50, 100, 120, 180, 200, 240])),
        "truth_latency_s": _f(rng.uniform(0.005, 0.040)),
        "truth_jitter_s": _f(rng.uniform(0.0005, 0.003)),
        "truth_noise_mm": _f(rng.uniform(0.1, 1.0)),
        "truth_noise_deg": _f(rng.uniform(0.02, 0.3)),
        "truth_lever_arm_mm": lever,
        "truth_heading_offset_deg": _f(rng.uniform(-0.3, 0.3) if rng.uniform() < 0.5 else 0.0),
        "return_noise_mm": _f(rng.uniform(0.5, 3.0)),
        "return_noise_deg": _f(rng.uniform(0.03, 0.2)),
        "placement_mm": _f(rng.uniform(0.3, 2.0)),
        "placement_deg": _f(rng.uniform(0.02, 0.2)),
        "can_bitrate": float(rng.choice([125e3, 250e3, 500e3, 1e6])),
        "can_proc_delay_s": _f(rng.uniform(1e-4, 1e-3)),
        "can_rx_jitter_s": _f(rng.uniform(1e-5, 1e-4)),
        "can_drop_rate": _f(rng.uniform(1e-4, 1e-3) if rng.uniform() < 0.3 else 0.0),
        "session_gap_s": [20.0, 120.0],
    }


def draw_background(rng) -> dict:
    """The floor every case has: a faint roughness (never zero)."""
    if rng.uniform() < 0.5:
        return {"law": "grains", "rate_per_m": _f(rng.uniform(15, 40)),
                "height_mm": _f(rng.uniform(0.05, 0.10)), "shape_w": _f(rng.uniform(2, 6))}
    return {"law": "surface", "sigma_mm": _f(rng.uniform(0.03, 0.06)),
            "corr_mm": _f(rng.uniform(3, 8))}


# ------------------------------------------------------------------------------------------------
# the case
# ------------------------------------------------------------------------------------------------


def draw_case(rng: np.random.Generator, k: int) -> dict:
    """Case k's hidden key (JSON-serialisable); see the package docstring for its fields."""
    vehicle = str(rng.choice(["labmate"] * 3 + ["clapper", "set"]))
    kind = str(rng.choice(["none"] + ["single"] * 6 + ["pair"] + ["ooc"] * 2))
    names: list[str] = []
    if kind == "single":
        names = [str(rng.choice(catalog_choices(vehicle)))]
    elif kind == "pair":
        names = sorted(map(str, rng.choice(catalog_choices(vehicle), size=2, replace=False)))
    elif kind == "ooc":
        names = [str(rng.choice(ooc_choices(vehicle)))]
    need = "any"
    if "count_loss" in names:
        need = "high"
    elif "encoder_eccentricity" in names:
        need = "wheel"
    elif "gear_backlash" in names:
        need = "geared"
    rob = draw_robot(rng, vehicle, need)
    b = rob["trucks"]["A"]["wheelbase_mm"]
    mass = _f(np.clip(rng.uniform(40, 120) * (b / 340) ** 2, 3, 300))
    case: dict = {
        "case": k,
        "world": "independent",
        "vehicle": vehicle,
        "kind": kind,
        "effects": names,
        "laws": {},
        "params": {},
        "scope": {},
        "visible": {},
        "robot": rob,
        "tick_ms": rob["tick_ms"],
        "controller": draw_controller(rng, rob, names),
        "fidelity": draw_fidelity(rng, rob),
        "true": {
            "mech": {
                "mass_kg": mass,  # what the tyre laws load the wheels with
                "cg_height_mm": _f(rng.uniform(0.3, 1.0) * b),
            },
            "motor": {"tau_s": _f(rng.uniform(0.01, 0.06)),
                      "accel_rad_s2": _f(rng.uniform(2500, 5000) /
                                         (rob["trucks"]["A"]["wheel_diameter_mm"] / 2))},
            "encoder": {"state_error": _f(rng.uniform(0.0, 0.15))},
            "background": draw_background(rng),
            "effects": {},
        },
    }
    case["plan"] = draw_plan(rng, case, names)
    for n in names:
        e, p = draw_effect(rng, n, case)
        case.pop("_peak", None)
        case["true"]["effects"][n] = e
        case["laws"][n] = e["law"]
        case["params"].update(p)
        case["scope"][n] = e["truck"]
        case["visible"][n] = visible(n, e["truck"], vehicle)
    return case


def quiet(case: dict) -> dict:
    """The same case on a perfect floor with perfect sensors (no background roughness, no truth
    or return noise, no lever arm, latency or jitter, exact placement, no CAN delays, equal
    encoder states): for tests that check a law against its equation. draw_case never makes
    one; every drawn case has a background."""
    c = json.loads(json.dumps(case))
    c["true"]["background"] = {"law": "grains", "rate_per_m": 0.0, "height_mm": 0.0,
                               "shape_w": 4.0}
    c["true"]["encoder"]["state_error"] = 0.0
    f = c["fidelity"]
    for k in ("truth_latency_s", "truth_jitter_s", "truth_noise_mm", "truth_noise_deg",
              "truth_heading_offset_deg", "return_noise_mm", "return_noise_deg", "placement_mm",
              "placement_deg", "can_proc_delay_s", "can_rx_jitter_s", "can_drop_rate"):
        f[k] = 0.0
    f["truth_lever_arm_mm"] = {t: [0.0, 0.0] for t in f["truth_lever_arm_mm"]}
    return c
