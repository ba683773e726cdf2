"""The independent world for odo-gap's blind check (issue 13 item 1): its laws against their
equations, computed here from the recorded counts and truth (not from the world's internals);
its sensors (latency, counter width); and its files against the repo's readers and the DBC."""

from __future__ import annotations

import json
import math
import subprocess
import tempfile
from pathlib import Path

import cantools
import numpy as np
import pytest
from gap_support import PY, SRC, env, indep_case
from odo_tools.gap import io
from odo_tools.validation import indep
from odo_tools.validation.indep import cases, floor, laws


def _base(vehicle: str = "labmate", seed: int = 3) -> dict:
    """A drawn no-effect case of the vehicle, made quiet (perfect floor and sensors), with a
    40 ms cycle, 1 ms physics and a 24-bit LabMate-like drive."""
    rng = np.random.default_rng(seed)
    while True:
        c = indep.draw_case(rng, 0)
        if c["vehicle"] == vehicle and c["kind"] == "none":
            break
    c = cases.quiet(c)
    c["tick_ms"] = c["robot"]["tick_ms"] = 40
    c["fidelity"]["physics_dt_s"] = 0.001
    for t in c["robot"]["trucks"].values():
        t.update(counter_bits=24, invert_left=False, invert_right=False)
    return c


def _run(c: dict, tmp: Path, name: str = "real", seed: int = 1) -> tuple[Path, io.Robot, dict]:
    real = tmp / name
    extra = indep.simulate_case(c, real, seed)
    return real, io.read_robot(real / "robot.json"), extra


def _travel(real: Path, rob: io.Robot, run: str, truck: int = 0) -> np.ndarray:
    """Per-tick wheel travel (n-1, 2) in nominal mm from a run's logged counters, differenced
    modulo the frame's counter width (the low 24 bits of wider counters)."""
    log = _read_log(real / f"{run}.log", rob)
    t = rob.trucks[truck]
    m = 1 << min(t["counter_bits"], 24)
    d = (np.diff(log.counts[:, truck], axis=0) + m // 2) % m - m // 2
    sign = np.array([-1 if t["invert_left"] else 1, -1 if t["invert_right"] else 1])
    return d * sign * rob.mm_per_count(truck)


def _read_log(path: Path, rob: io.Robot) -> io.SensorLog:
    """gap/io.read_log; where it refuses frames of one sample that arrive at their real spacing on
    the bus (it wants them within 10 us of WHEEL_COUNTS_A; reported to the diagnosis), the same
    frames re-stamped with their sample's WHEEL_COUNTS_A time must read back."""
    try:
        return io.read_log(path, rob)
    except io.GapInputError as e:
        if "same tick" not in str(e):
            raise
    lines, t_a = [], None
    for ln in path.read_text().splitlines():
        t, rest = ln.split(" ", 1)
        if rest.split("#")[0].endswith("110"):
            t_a = t
        lines.append(f"{t_a} {rest}")
    with tempfile.TemporaryDirectory() as d:
        alt = Path(d) / path.name
        alt.write_text("\n".join(lines) + "\n")
        return io.read_log(alt, rob)


def _short(c: dict, n: int, max_s: float = 15.0) -> dict:
    """The case's first n runs, each shrunk to last at most max_s (keeps the tests quick)."""
    c["plan"] = c["plan"][:n]
    for p in c["plan"]:
        p["segs"] = [list(s) for s in cases._fit([tuple(s) for s in p["segs"]],
                                                 cases.limits(c, p), max_s, 300.0)]
    return c


def _plan(label: str, segs: list) -> dict:
    return {"label": label, "shape": label, "segs": [list(s) for s in segs],
            "name": f"run-{label}-01"}


def test_drawn_cases_follow_the_mix_and_every_case_has_a_floor() -> None:
    """About 10 % none, 60 % single, 10 % pairs, 20 % out of catalog; 60/20/20 % vehicles; every
    catalog effect reachable; a background floor roughness in every case; JSON keys."""
    rng = np.random.default_rng(123)
    n = 200
    cs = [indep.draw_case(rng, k) for k in range(n)]
    kinds = {k: sum(c["kind"] == k for c in cs) / n for k in ("none", "single", "pair", "ooc")}
    vehs = {v: sum(c["vehicle"] == v for c in cs) / n for v in ("labmate", "clapper", "set")}
    assert abs(kinds["none"] - 0.1) < 0.06 and abs(kinds["single"] - 0.6) < 0.1
    assert abs(kinds["pair"] - 0.1) < 0.06 and abs(kinds["ooc"] - 0.2) < 0.08
    assert abs(vehs["labmate"] - 0.6) < 0.1 and abs(vehs["clapper"] - 0.2) < 0.08
    seen = {e for c in cs for e in c["effects"]}
    assert set(indep.EFFECTS) | set(indep.OUT_OF_CATALOG) <= seen
    for c in cs:
        json.dumps(c)
        bg = c["true"]["background"]
        assert (bg.get("rate_per_m", 0) > 0 and bg.get("height_mm", 0) > 0) or bg.get(
            "sigma_mm", 0
        ) > 0
        assert 6 <= len(c["plan"]) <= 13 and {"cw", "ccw"} <= {p["label"] for p in c["plan"]}
        assert len({p["shape"] for p in c["plan"]}) >= 2
        # count loss shows only on the sprint: it is driven twice, so one run can be fitted and
        # the other judged (the same segments at the same speed); no other case has a sprint
        sprints = [p for p in c["plan"] if p["shape"] == "sprint"]
        if "count_loss" in c["effects"]:
            assert len(sprints) == 2 and sprints[0]["segs"] == sprints[1]["segs"]
            assert sprints[0]["v_mm_s"] == sprints[1]["v_mm_s"] > c["controller"]["v_mm_s"]
            assert {p["name"] for p in sprints} == {"run-sprint-01", "run-sprint-02"}
        else:
            assert not sprints
        assert sorted(c["effects"]) == c["effects"] and set(c["laws"]) == set(c["effects"])
        for e, law in c["laws"].items():
            assert law in indep.EFFECTS.get(e, [law]) or e in indep.OUT_OF_CATALOG
    # every catalog effect is drawn in every one of its laws, on a vehicle it applies to
    for e, laws_ in indep.EFFECTS.items():
        c = json.loads(json.dumps(next(c for c in cs if e in cases.catalog_choices(c["vehicle"]))))
        got = {cases.draw_effect(rng, e, c)[0]["law"] for _ in range(12)}
        assert got == set(laws_) and len(laws_) >= 2, (e, got)


def test_a_friction_circle_skid_acts_on_the_hardest_turns_and_not_on_starts() -> None:
    """The floor's limit lies below the lateral acceleration the plan's hardest turn asks and
    above the planner's starts and stops (by cases.FRICTION_START) and ice (FRICTION_MIN), and
    no run outlasts the time bound. A clapper's tightest arcs are gentle (its linkage): a floor
    taken above them never skidded at all (seed 2731 case 43); where no floor but ice lies
    below its turns, the skid is the cornering law's."""
    rng = np.random.default_rng(7)
    seen = set()
    for k in range(400):
        c = indep.draw_case(rng, k)
        e = c["true"]["effects"].get("skid")
        if not e or e["law"] != "friction":
            continue
        seen.add(c["vehicle"])
        a_lim = e["a_lim_m_s2"] * 1000
        ctl = c["controller"]
        assert max(ctl["a_mm_s2"], ctl["d_mm_s2"]) * cases.FRICTION_START <= a_lim * (1 + 1e-9)
        assert cases.FRICTION_MIN <= a_lim < 0.9 * cases._peak_plan(c)[1]
        for run in c["plan"]:
            lim = cases.limits(c, run)
            assert cases._duration(run["segs"], lim) <= cases._max_run_s(c["robot"]) + 1e-6
    assert "labmate" in seen and len(seen) >= 2, seen


def test_drawn_robots_pass_the_repos_robot_validator() -> None:
    """robot.json is the nominal description the firmware believes: libodosim must accept it."""
    import ctypes as C

    from odo_tools.gap.simlib import lib

    so = lib()
    rng = np.random.default_rng(7)
    err = C.create_string_buffer(512)
    scen = b'{"effects": {}}'
    for need in ("any", "high", "wheel", "geared") * 6:
        for veh in ("labmate", "clapper", "set"):
            rob = cases.draw_robot(rng, veh, need)
            s = so.odosim_setup_parse(json.dumps(rob).encode(), scen, err, 512)
            assert s, (rob, err.value.decode())
            so.odosim_setup_free(s)


def test_no_effect_straight_truth_and_onboard_agree_within_the_background(tmp_path: Path) -> None:
    """A robot with no effect on a drawn (rough) floor: truth and its own dead reckoning agree
    within the background: a little short (roughness) and a small heading walk."""
    rng = np.random.default_rng(11)
    while True:
        c = indep.draw_case(rng, 0)
        if c["vehicle"] == "labmate" and c["kind"] == "none":
            break
    c["plan"] = [_plan("straight", [("line", 4000.0)])]
    real, _, _ = _run(c, tmp_path)
    ret = io.read_returns(real / "returns.csv")[("straight", 1)]
    row = (real / "returns.csv").read_text().splitlines()[1].split(",")
    calc = np.array([float(row[5]), float(row[6]), math.radians(float(row[7]))])
    f = c["fidelity"]
    assert abs(calc[0] - 4000.0) < 5.0  # the robot thinks it drove the commanded 4 m
    short = calc[0] - ret[0]
    assert -4 * f["return_noise_mm"] - 1 < short < 0.003 * 4000 + 4 * f["return_noise_mm"]
    assert abs(ret[1] - calc[1]) < 15.0
    assert abs(ret[2] - calc[2]) < math.radians(0.4)


def test_ed_curves_a_commanded_straight_by_the_amount_geometry_predicts(tmp_path: Path) -> None:
    """000 App. A / Eq. 6.30: Ed = DR/DL with the mean kept; equal counted travel d on both
    wheels turns the truck by d (cR - cL) / b, cR = 2 Ed/(Ed+1), cL = 2/(Ed+1) (left if Ed > 1)."""
    c = _base()
    ed = 1.006
    c["true"]["effects"] = {"ed": {"law": "fixed", "truck": "A", "value": ed}}
    c["plan"] = [_plan("straight", [("line", 4000.0)])]
    real, rob, _ = _run(c, tmp_path)
    d = _travel(real, rob, "run-straight-01").sum(axis=0)
    b = rob.trucks[0]["wheelbase_mm"]
    want = (d[1] * 2 * ed / (ed + 1) - d[0] * 2 / (ed + 1)) / b
    tr = io.read_truth(real / "run-straight-01.truth.csv", rob)
    got = tr.pose[-1, 0, 2] - tr.pose[0, 0, 2]
    assert want > math.radians(0.5)
    assert abs(got - want) < 2e-4, (math.degrees(got), math.degrees(want))


def test_eb_scales_spot_turns_by_one_over_eb(tmp_path: Path) -> None:
    """000 Eq. 2.8: a true wheelbase Eb b turns the truck (dR - dL) / (Eb b): spot turns come out
    1/Eb of what the robot counted."""
    c = _base()
    eb = 1.025
    c["true"]["effects"] = {"eb": {"law": "fixed", "truck": "A", "value": eb}}
    c["plan"] = [_plan("spin", [("spin", 2 * math.pi), ("spin", math.pi)])]
    real, rob, _ = _run(c, tmp_path)
    d = _travel(real, rob, "run-spin-01").sum(axis=0)
    counted = (d[1] - d[0]) / rob.trucks[0]["wheelbase_mm"]
    tr = io.read_truth(real / "run-spin-01.truth.csv", rob)
    got = tr.pose[-1, 0, 2] - tr.pose[0, 0, 2]
    assert abs(counted - 3 * math.pi) < 0.01  # the robot turned what it was told, by its counts
    assert abs(got / counted - 1 / eb) < 5e-5  # a count's worth


@pytest.mark.parametrize("law", ["inv_radius", "torque"])
def test_scrub_effective_wheelbase_varies_with_radius_as_its_law_says(
    tmp_path: Path, law: str
) -> None:
    """A turn-radius-dependent wheelbase, nominal on spot turns: on circles of several radii the
    true heading change follows the law applied to each cycle's counted wheel travel:
    inv_radius: counted x (1 + 2c/b) / (1 + 2c/b s), s = |dR - dL| / (|dL| + |dR|) = b / 2R;
    torque: geometric wheelbase b (1 - s_sat), less s_sat tanh(r_t / R) of the mean travel."""
    c = _base()
    b = c["robot"]["trucks"]["A"]["wheelbase_mm"]
    e = {"law": law, "truck": "A"}
    e.update({"c_mm": 0.012 * b} if law == "inv_radius" else {"s_sat": 0.02, "r_t_mm": 1.5 * b})
    c["true"]["effects"] = {"scrub": e}
    radii = [1.2 * b, 3 * b, 8 * b]
    c["plan"] = [_plan("spin", [("spin", 2 * math.pi)])] + [
        {**_plan(f"circle{'abc'[i]}", [("arc", r, 2 * math.pi)])} for i, r in enumerate(radii)
    ]
    real, rob, _ = _run(c, tmp_path)
    for p in c["plan"]:
        d = _travel(real, rob, p["name"])  # per tick, nominal mm = true travel on this floor
        tr = io.read_truth(real / f"{p['name']}.truth.csv", rob)
        dth = tr.pose[-1, 0, 2] - tr.pose[0, 0, 2]
        dl, dr = d[:, 0], d[:, 1]
        s = np.abs(dr - dl) / np.maximum(np.abs(dl) + np.abs(dr), 1e-12)
        if law == "inv_radius":
            eps = 2 * e["c_mm"] / b
            want = np.sum((dr - dl) / b * (1 + eps) / (1 + eps * s))
        else:  # tanh(r_t / R) with R = b/2 (dR + dL) / (dR - dL); spot turns nominal
            bg = b * (1 - e["s_sat"])  # the geometric wheelbase
            ratio = 2 * e["r_t_mm"] * np.abs(dr - dl) / np.maximum(bg * np.abs(dr + dl), 1e-12)
            kin = (dr - dl) / bg
            loss = e["s_sat"] * np.tanh(ratio) * (np.abs(dl) + np.abs(dr)) / bg
            want = np.sum(kin - np.sign(kin) * np.minimum(loss, np.abs(kin)))
        assert abs(dth / want - 1) < 3e-4, (p["name"], dth, want)
        beff = np.sum(dr - dl) / dth
        if p["label"] == "spin":
            assert abs(beff / b - 1) < 3e-4  # spot turns are nominal
    # and the law really depends on the radius: the widest circle is not the spot turn
    assert abs(beff / b - 1) > 0.005


def test_decoders_count_every_edge_below_their_rate_and_lose_counts_above() -> None:
    """rate_limit: an interrupt-driven decoder handles at most f_max edges/s; below that it
    counts every edge, above it counts f_max per second (the rest coalesce and are lost).
    missed: the probability that a state is too short to register rises with the edge rate."""
    fmax, dt = 200_000.0, 0.001
    slots = np.full(1000, int(fmax * dt))
    for rate in (50_000.0, 150_000.0, 199_000.0, 230_000.0, 390_000.0):
        for sign in (1, -1):
            e = np.full(1000, sign * int(rate * dt))
            got, lost = laws.decode_saturating(e, slots)
            assert got.sum() == sign * min(rate, fmax) * 1.0
            assert lost.all() == (rate > fmax) and lost.any() == (rate > fmax)
    p = laws.missed_prob(np.array([1e3, 5e4, 1e5, 2e5]), 1e5, 1e4, 0.02)
    assert np.all(np.diff(p) > 0) and p[0] < 2e-6 and abs(p[2] - 0.01) < 1e-12


def test_accel_slip_spins_when_speeding_up_and_drags_when_slowing_either_way() -> None:
    """The accel law's stated physics in both directions of travel: a wheel speeding up covers
    less floor than it rolled, one slowing down more, whether it runs forwards or backwards."""
    k1, p, cap = 0.05, 2.0, 0.3
    for sign in (1.0, -1.0):
        ds = np.full(4, sign * 2.0)
        speeding_up = laws.slip_accel(ds, np.full(4, sign * 2000.0), k1, p, cap)
        slowing = laws.slip_accel(ds, np.full(4, -sign * 2000.0), k1, p, cap)
        kap = k1 * 2.0**p
        assert np.allclose(np.abs(speeding_up), 2.0 * (1.0 - kap))
        assert np.allclose(np.abs(slowing), 2.0 * (1.0 + kap))
        assert np.all(np.sign(speeding_up) == sign) and np.all(np.sign(slowing) == sign)
    hard = laws.slip_accel(np.ones(1), np.full(1, 50_000.0), k1, p, cap)
    assert hard[0] == pytest.approx(1.0 - cap)


def test_count_loss_only_loses_counts_above_its_rate(tmp_path: Path) -> None:
    """In the world: a straight that accelerates through the decoder's rate. Per tick the
    counted travel equals the true travel where the encoder's edge rate is below f_max and is
    f_max / rate of it above."""
    c = _base()
    c["fidelity"]["truth_rate_hz"] = 240.0
    t = c["robot"]["trucks"]["A"]
    t.update(encoder_lines=1000, gear_ratio=19.5)
    cpr = 4 * 1000 * 19.5
    r = t["wheel_diameter_mm"] / 2
    c["controller"]["v_mm_s"] = v = min(0.6 * c["robot"]["max_wheel_speed_mm_s"], 700.0)
    fmax = 0.8 * v / (2 * math.pi * r) * cpr
    c["true"]["effects"] = {"count_loss": {"law": "rate_limit", "truck": "A", "f_max_hz": fmax}}
    c["plan"] = [_plan("straight", [("line", 3000.0)])]
    real, rob, _ = _run(c, tmp_path)
    d = _travel(real, rob, "run-straight-01").mean(axis=1)
    tr = io.read_truth(real / "run-straight-01.truth.csv", rob)
    log = _read_log(real / "run-straight-01.log", rob)
    true = np.diff(np.interp(log.t_s, tr.t_s, tr.pose[:, 0, 0]))
    rate = true / rob.tick_s / (2 * math.pi * r) * cpr
    slow = (rate > 0.2 * fmax) & (rate < 0.95 * fmax)
    fast = rate > 1.05 * fmax
    assert slow.sum() > 10 and fast.sum() > 10
    assert np.abs(d[slow] / true[slow] - 1).max() < 0.01
    assert np.abs(d[fast] / true[fast] - fmax / rate[fast]).max() < 0.02
    # lost edges raise the Status bits of their sample
    db = cantools.database.load_file(str(SRC / "can" / "odometry.dbc"))
    st = [db.decode_message(0x110, bytes.fromhex(ln.split("#")[1]))["Status"]
          for ln in (real / "run-straight-01.log").read_text().splitlines() if " 110#" in ln]
    assert max(st) & 3 and min(st) == 0


def test_counters_wrap_at_their_width(tmp_path: Path) -> None:
    """A 16-bit decoder on a fine encoder wraps many times in a run; its values stay below 2^16
    and, differenced modulo 2^16, give back the true travel."""
    c = _base()
    c["robot"]["trucks"]["A"].update(counter_bits=16, encoder_lines=2048, gear_ratio=10.0)
    c["plan"] = [_plan("shuttle", [("line", 3000.0), ("line", -3000.0)])]
    real, rob, _ = _run(c, tmp_path)
    log = _read_log(real / "run-shuttle-01.log", rob)
    raw = log.counts[:, 0]
    assert raw.max() < 1 << 16 and raw.min() >= 0
    wraps = np.abs(np.diff(raw, axis=0)) > 1 << 15
    assert wraps.sum() >= 10
    x = np.concatenate([[0.0], np.cumsum(_travel(real, rob, "run-shuttle-01").mean(axis=1))])
    tr = io.read_truth(real / "run-shuttle-01.truth.csv", rob)
    assert np.abs(np.interp(tr.t_s, log.t_s, x) - tr.pose[:, 0, 0]).max() < 3.0
    assert abs(x.max() - 3000.0) < 50.0  # the stop overshoots a little (motor lag)


@pytest.mark.parametrize("latency", [0.005, 0.03])
def test_truth_latency_shifts_the_track_by_the_stated_delay(tmp_path: Path, latency: float) -> None:
    """Motion capture stamped on arrival: the track lags the robot's own (counted) motion by the
    latency. Estimated by the shift that best aligns the truth x(t) with the dead-reckoned x(t)
    from the log (both in the robot's clock)."""
    c = _base()
    c["fidelity"].update(truth_latency_s=latency, truth_rate_hz=240.0)
    c["plan"] = [_plan("shuttle", [("line", 2000.0), ("line", -2000.0)])]
    real, rob, _ = _run(c, tmp_path)
    log = _read_log(real / "run-shuttle-01.log", rob)
    x_dr = np.concatenate([[0.0], np.cumsum(_travel(real, rob, "run-shuttle-01").mean(axis=1))])
    tr = io.read_truth(real / "run-shuttle-01.truth.csv", rob)
    shifts = np.arange(-0.06, 0.06, 0.0005)
    err = [np.mean((np.interp(tr.t_s - s, log.t_s, x_dr) - tr.pose[:, 0, 0]) ** 2)
           for s in shifts]
    best = shifts[int(np.argmin(err))]
    assert abs(best - latency) < 0.002, (best, latency)


def test_bump_turns_the_truck_by_the_exact_step_geometry(tmp_path: Path) -> None:
    """004 Eqs. 1-5, exact rigid wheel: a knife-thin step of height h under the right wheel makes
    it roll 2 (R acos(1 - h/R) - sqrt(2Rh - h^2)) more than it advances; driving counted-straight
    the truck turns right by that over b. The key's event sits on the cable."""
    c = _base()
    b = c["robot"]["trucks"]["A"]["wheelbase_mm"]
    R = c["robot"]["trucks"]["A"]["wheel_diameter_mm"] / 2
    h = 8.0
    cab = {"x": 1500.0, "y": -b / 2, "angle_deg": 90.0, "length_mm": 0.5 * b, "kind": "step",
           "h_mm": h, "width_mm": 0.0, "slope_deg": 0.0}
    c["true"]["effects"] = {"bumps": {"law": "steps", "truck": "vehicle", "cables": [cab]}}
    c["plan"] = [_plan("straight", [("line", 3000.0)])]
    real, rob, extra = _run(c, tmp_path)
    d = _travel(real, rob, "run-straight-01").sum(axis=0)
    tr = io.read_truth(real / "run-straight-01.truth.csv", rob)
    counted = (d[1] - d[0]) / b
    got = tr.pose[-1, 0, 2] - tr.pose[0, 0, 2] - counted
    want = -floor.thin_step_excess(h, R) / b
    assert abs(got / want - 1) < 0.01, (got, want)
    (ev,) = extra["events"]
    assert ev["wheel"] == "right" and ev["run"] == "run-straight-01"
    assert json.loads(json.dumps(extra))["events"] == [ev]  # the key's events are plain JSON
    assert abs(ev["x_mm"] - 1500.0) < 0.5 * math.sqrt(2 * R * h) + 5 and abs(ev["y_mm"] + b / 2) < 5


def test_envelope_matches_the_closed_form_of_a_thin_step() -> None:
    for R, h in ((75.0, 10.0), (25.0, 5.0), (150.0, 1.0)):
        m = floor.bump_map("step", h, 0.0, 0.0, R, 1.0)
        assert abs(m.excess / floor.thin_step_excess(h, R) - 1) < 1e-4
        assert abs(m.span - 2 * math.sqrt(2 * R * h - h * h)) < 0.05


@pytest.fixture(scope="module")
def three(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, dict, dict]]:
    """One drawn case of each vehicle, as a user gets it (background and sensor noise)."""
    out = {}
    rng = np.random.default_rng(2024)
    tmp = tmp_path_factory.mktemp("three")
    k = 0
    while len(out) < 3:
        c = indep.draw_case(rng, k)
        k += 1
        if c["vehicle"] in out or c["kind"] not in ("single", "pair"):
            continue
        _short(c, 5)
        real = tmp / c["vehicle"]
        out[c["vehicle"]] = (real, c, indep.simulate_case(c, real, 99))
    return out


def test_every_file_reads_back_through_the_repo_readers_and_cantools(three) -> None:
    db = cantools.database.load_file(str(SRC / "can" / "odometry.dbc"))
    for real, c, _ in three.values():
        rob = io.read_robot(real / "robot.json")
        assert rob.vehicle == c["vehicle"] and rob.tick_s == c["tick_ms"] / 1000
        rets = io.read_returns(real / "returns.csv")
        for p in c["plan"]:
            log = _read_log(real / f"{p['name']}.log", rob)
            tr = io.read_truth(real / f"{p['name']}.truth.csv", rob)
            assert (p["label"], int(p["name"][-2:])) in rets
            assert tr.t_s[0] >= log.t_s[0] and tr.t_s[-1] <= log.t_s[-1] + 0.05
            frames = 0
            a_counts = []
            for ln in (real / f"{p['name']}.log").read_text().splitlines():
                fid, data = ln.split()[2].split("#")
                msg = db.decode_message(int(fid, 16), bytes.fromhex(data), scaling=False)
                frames += 1
                if fid == "110":
                    a_counts.append((msg["LeftCount"], msg["RightCount"]))
            got = np.array(a_counts)
            assert np.array_equal(got, log.counts[:, 0][: got.shape[0]]) or len(got) < len(
                log.counts
            )
            assert frames > 0
            if rob.n_trucks == 2:
                assert log.alpha_deg is not None and tr.link is not None
                if c["vehicle"] == "clapper":
                    assert log.l_mm is not None


def test_the_key_never_lands_inside_the_recorded_data(three, tmp_path: Path) -> None:
    for real, c, extra in three.values():
        names = {p.name for p in real.iterdir()}
        want = {"robot.json", "returns.csv"} | {f"{p['name']}.log" for p in c["plan"]} | {
            f"{p['name']}.truth.csv" for p in c["plan"]}
        assert names == want
        rob = json.loads((real / "robot.json").read_text())
        assert set(rob) <= {"vehicle", "description", "tick_ms", "heading_form", "ipec",
                            "max_wheel_speed_mm_s", "trucks", "linkage", "trailer"}
        text = (real / "robot.json").read_text()
        for e in c["effects"]:
            assert f'"{e}"' not in text and f'"{c["laws"][e]}"' not in text
        assert json.dumps(extra)
    # the CLI refuses a key inside the data folder and an existing folder, writing nothing
    out = tmp_path / "x"
    r = subprocess.run([PY, "-m", "odo_tools.validation.indep", "--seed", "1", "--case", "0",
                        "--out", str(out), "--key", str(out / "key.json"), "--quiet"],
                       env=env(), capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "inside" in r.stderr and not out.exists()
    out.mkdir()
    r = subprocess.run([PY, "-m", "odo_tools.validation.indep", "--seed", "1", "--case", "0",
                        "--out", str(out), "--quiet"], env=env(), capture_output=True,
                       text=True, timeout=120)
    assert r.returncode != 0 and "exists" in r.stderr and not any(out.iterdir())


def test_same_seed_same_bytes_another_seed_differs(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    c = _short(indep.draw_case(rng, 0), 2, 10.0)
    a, b, d = tmp_path / "a", tmp_path / "b", tmp_path / "d"
    ka = indep.simulate_case(c, a, 17)
    kb = indep.simulate_case(c, b, 17)
    indep.simulate_case(c, d, 18)
    assert ka["events"] == kb["events"]
    files = sorted(p.name for p in a.iterdir())
    assert files == sorted(p.name for p in b.iterdir())
    for f in files:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f
    assert any((a / f).read_bytes() != (d / f).read_bytes() for f in files if f != "robot.json")
    with pytest.raises(FileExistsError):
        indep.simulate_case(c, a, 17)


def test_a_drawn_bump_cases_key_is_plain_json(tmp_path: Path) -> None:
    """The key's bump events come out of numpy arrays (cable indices were int64, and `--key`
    failed after the data were written); every value in the key must be plain JSON."""
    rng = np.random.default_rng(7)
    c = next(c for c in (indep.draw_case(rng, k) for k in range(60)) if c["effects"] == ["bumps"])
    c["plan"] = c["plan"][:1]
    extra = indep.simulate_case(c, tmp_path / "real", 7)
    assert extra["events"], "the first run crosses a cable"
    assert json.loads(json.dumps(extra)) == extra


def test_a_case_written_by_hand_is_the_case_blind_diagnosed(tmp_path: Path) -> None:
    """`python -m odo_tools.validation.indep --seed S --case K` writes, byte for byte, the data
    odo-gap blind simulates for case K of seed S (one data seed, validation.case_seed). The CLI
    once drew its noise from seed * 1000003 + K and the blind from seed * 1000 + K, so a miss
    traced by hand was another draw of the floor and the sensors than the one scored."""
    seed, k = 4, 1
    ref = tmp_path / "blind"
    indep_case(seed, k, ref, "set", {})  # as odo-gap blind draws and simulates it
    out = tmp_path / "cli"
    r = subprocess.run([PY, "-m", "odo_tools.validation.indep", "--seed", str(seed), "--case",
                        str(k), "--out", str(out), "--quiet"], env=env(), capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    files = sorted(p.name for p in ref.iterdir())
    assert files == sorted(p.name for p in out.iterdir())
    for f in files:
        assert (ref / f).read_bytes() == (out / f).read_bytes(), f
