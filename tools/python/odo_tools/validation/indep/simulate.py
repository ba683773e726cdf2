"""Simulating a case: the runs of one session, then what the sensors recorded.

simulate_case(case, real, seed) writes into a fresh folder `real` (assembled in a temporary
folder beside it and renamed into place):
  robot.json                 the nominal description (what the firmware believes)
  run-<label>-NN.log         candump -l of the sensor frames (can/odometry.dbc)
  run-<label>-NN.truth.csv   motion capture, stamped in the robot's clock (gap/io.py read_truth)
  returns.csv                000 Eq. 3.1: measured and onboard-calculated end poses
"""

from __future__ import annotations

import json
import math
import os
import shutil
import time
from pathlib import Path

import numpy as np

from . import floor as fl
from . import imprint, laws, paths
from .cases import limits
from .control import Controller
from .world import Cable, World, truck_models

ID_A, ID_B, ID_ROT, ID_LIN = 0x110, 0x111, 0x120, 0x121
DLC = {ID_A: 8, ID_B: 8, ID_ROT: 6, ID_LIN: 6}


def _refs(case: dict) -> tuple[list[list[paths.Ref]], list[int]]:
    """Per run: the reference of each driven truck; and its last reference tick."""
    rob = case["robot"]
    veh = rob["vehicle"]
    T = case["tick_ms"] / 1000.0
    step = round(T / paths.DT_REF)
    out, ends = [], []
    for p in case["plan"]:
        lim = limits(case, p)
        segs = [tuple(s) for s in p["segs"]]
        if veh == "clapper":
            L = rob["linkage"]["length_mm"]
            ra = paths.build(segs, lim, lead_in_mm=L + 200.0)
            out.append([ra, paths.follow(ra, L)])
        else:
            out.append([paths.build(segs, lim)])
        ends.append(math.ceil((out[-1][0].t.size - 1) / step))
    return out, ends


def _sample(refs: list[list[paths.Ref]], K: int, step: int, truck: int) -> dict:
    R = len(refs)
    res = {k: np.zeros((R, K)) for k in ("x", "y", "th", "v", "w", "bd")}
    for r, rr in enumerate(refs):
        ref = rr[truck]
        idx = np.minimum(np.arange(K) * step, ref.t.size - 1)
        for k in ("x", "y", "th", "v", "w"):
            res[k][r] = getattr(ref, k)[idx]
        if truck == 1:  # the rear truck's angle to the link along the reference
            a = rr[0]
            thl = np.arctan2(a.y[idx] - ref.y[idx], a.x[idx] - ref.x[idx])
            res["bd"][r] = laws.wrap(ref.th[idx] - thl)
        past = np.arange(K) * step > ref.t.size - 1
        res["v"][r, past] = 0.0
        res["w"][r, past] = 0.0
    return res


def _travel(refs: list[list[paths.Ref]], rob: dict) -> float:
    """Longest wheel travel of any run (mm), with a margin, for the roughness tables."""
    best = 0.0
    for rr in refs:
        for i, ref in enumerate(rr):
            b = rob["trucks"]["AB"[i]]["wheelbase_mm"]
            d = np.sum(np.abs(ref.v) + np.abs(ref.w) * b / 2) * paths.DT_REF
            best = max(best, d)
    return 1.5 * best + 5000.0


def _rough_tables(case, trucks, R, U, rng) -> np.ndarray:
    """Per run, truck and wheel: cumulative roughness excess per mm of travel (background plus
    the roughness effect where it is on)."""
    tabs = np.zeros((R, len(trucks), 2, U + 1))
    laws_ = [case["true"]["background"]]
    ef = case["true"]["effects"].get("roughness")
    if ef:
        laws_.append(ef)
    for r in range(R):
        for ti, tm in enumerate(trucks):
            for w in range(2):
                rad = float(tm.r0[w])
                for lw in laws_:
                    if lw["law"] == "grains":
                        tabs[r, ti, w] += fl.grains(
                            rng, U, rad, lw["rate_per_m"], lw["height_mm"], lw["shape_w"]
                        )
                    else:
                        tabs[r, ti, w] += fl.surface(rng, U, rad, lw["sigma_mm"], lw["corr_mm"])
    return tabs


def _start_poses(case, R, rng) -> np.ndarray:
    rob = case["robot"]
    fid = case["fidelity"]
    veh = rob["vehicle"]
    nt = 1 if veh == "labmate" else 2
    st = np.zeros((R, nt, 3))
    st[:, 0, :2] = rng.normal(0, fid["placement_mm"], (R, 2))
    st[:, 0, 2] = np.radians(rng.normal(0, fid["placement_deg"], R))
    if veh == "clapper":
        L = rob["linkage"]["length_mm"] + rng.normal(0, 2 * fid["placement_mm"], R)
        th = st[:, 0, 2] + np.radians(rng.normal(0, 3 * fid["placement_deg"], R))
        st[:, 1, 0] = st[:, 0, 0] - L * np.cos(th)
        st[:, 1, 1] = st[:, 0, 1] - L * np.sin(th)
        st[:, 1, 2] = st[:, 0, 2] + np.radians(rng.normal(0, 3 * fid["placement_deg"], R))
    elif veh == "set":
        tr = rob["trailer"]
        phi = st[:, 0, 2] + np.radians(rng.normal(0, 5 * fid["placement_deg"], R))
        hx = st[:, 0, 0] - tr["hitch_offset_mm"] * np.cos(st[:, 0, 2])
        hy = st[:, 0, 1] - tr["hitch_offset_mm"] * np.sin(st[:, 0, 2])
        st[:, 1, 0] = hx - tr["trailer_length_mm"] * np.cos(phi)
        st[:, 1, 1] = hy - tr["trailer_length_mm"] * np.sin(phi)
        st[:, 1, 2] = phi
    return st


def link_true(case: dict, pose: np.ndarray) -> np.ndarray:
    """True linkage (alpha, beta, l) from poses (..., trucks, 3): the link's direction from B to
    A is theta_L (002 Eq. 16 convention); alpha = theta_A - theta_L, beta = theta_B - theta_L; a
    set's alpha is theta_A - theta_trailer, l its bar length."""
    veh = case["robot"]["vehicle"]
    A, B = pose[..., 0, :], pose[..., 1, :]
    if veh == "set":
        a = laws.wrap(A[..., 2] - B[..., 2])
        return np.stack(
            [a, np.zeros_like(a), np.full_like(a, case["robot"]["trailer"]["trailer_length_mm"])],
            axis=-1,
        )
    thl = np.arctan2(A[..., 1] - B[..., 1], A[..., 0] - B[..., 0])
    return np.stack(
        [
            laws.wrap(A[..., 2] - thl),
            laws.wrap(B[..., 2] - thl),
            np.hypot(A[..., 0] - B[..., 0], A[..., 1] - B[..., 1]),
        ],
        axis=-1,
    )


def link_measured(case: dict, pose: np.ndarray) -> np.ndarray:
    """What the linkage encoders read (alpha, beta in rad, l in mm), quantised: absolute rotary
    encoders truncate to their code, the linear encoder to its resolution."""
    lk = link_true(case, pose)
    eff = case["true"]["effects"]
    rob = case["robot"]
    a, bta, ln = lk[..., 0].copy(), lk[..., 1].copy(), lk[..., 2].copy()
    rb = eff.get("rotary_bias")
    if rb:
        if rb["law"] == "constant":
            a += math.radians(rb["alpha_deg"])
            bta += math.radians(rb["beta_deg"])
        else:
            for arr, k in ((a, "alpha"), (bta, "beta")):
                b0, a1, ph = rb[k]
                arr += np.radians(b0 + a1 * np.sin(arr + ph) - a1 * math.sin(ph))
    lb = eff.get("link_bias")
    if lb and rob["vehicle"] == "clapper":
        ln += lb["const_mm"]
        if lb["law"] == "eccentric":
            A, B = pose[..., 0, :], pose[..., 1, :]
            ln += laws.link_eccentric(
                A[..., 0], A[..., 1], A[..., 2], B[..., 0], B[..., 1], B[..., 2],
                lb["dA_mm"], lb["dB_mm"],
            )
    bits = (rob.get("linkage") or rob.get("trailer"))["rotary_bits"]
    q = 2 * math.pi / (1 << bits)
    out = np.stack([np.floor((a % (2 * math.pi)) / q) * q, np.floor((bta % (2 * math.pi)) / q) * q,
                    ln], axis=-1)
    if rob["vehicle"] == "clapper":
        res = rob["linkage"]["linear_resolution_mm"]
        out[..., 2] = np.floor(ln / res) * res
    return out


def run_world(case: dict, seed: int, progress=None) -> dict:
    """Simulate every run of the case; returns the per-tick records and the true histories."""
    ss = np.random.SeedSequence([seed, case["case"]])
    r_floor, r_world, r_start, r_sess = (np.random.default_rng(s) for s in ss.spawn(4))
    trucks = truck_models(case)
    R = len(case["plan"])
    T = case["tick_ms"] / 1000.0
    step = round(T / paths.DT_REF)
    refs, ends = _refs(case)
    settle = round(case["controller"]["settle_s"] / T)
    stop = max(2, round(1.0 / T))  # standing still at the end: what the returns measure
    k_end = np.array(ends) + settle  # last tick with a command
    K = int(k_end.max()) + stop + 1  # ticks simulated
    nt = len(trucks)
    ref_arr = [_sample(refs, K, step, i) for i in range(nt if case["vehicle"] == "clapper" else 1)]
    U = int(_travel(refs, case["robot"]))
    rough = _rough_tables(case, trucks, R, U, r_floor)
    cables = []
    bm = case["true"]["effects"].get("bumps")
    if bm:
        cables = [Cable(c["x"], c["y"], math.radians(c["angle_deg"]), c["length_mm"], c["kind"],
                        c["h_mm"], c["width_mm"], c["slope_deg"]) for c in bm["cables"]]
    gap = case["fidelity"]["session_gap_s"]
    durs = (k_end + stop) * T
    t0 = np.concatenate([[0.0], np.cumsum(durs[:-1] + r_sess.uniform(gap[0], gap[1], R - 1))])
    world = World(case, trucks, _start_poses(case, R, r_start), rough, cables, r_world, t0)
    counts = np.zeros((K, R, nt, 2), dtype=np.int64)
    status = np.zeros((K, R, nt), dtype=np.int64)
    link = np.zeros((K, R, 3))
    onboard = np.zeros((K, R, nt, 3))
    c0 = r_world.integers(0, 1 << 32, (R, nt, 2))
    world.decoded[:] = c0
    counts[0] = world.counters()
    ctrl = Controller(case, ref_arr, counts[0], k_end)
    two = nt == 2
    if two:
        link[0] = link_measured(case, world.pose)
    for k in range(K - 1):
        cmd = ctrl.step(k, counts[k], link[k] if case["vehicle"] == "clapper" else None)
        for i, od in enumerate(ctrl.odo):
            onboard[k, :, i] = od.pose
        world.advance(cmd)
        counts[k + 1] = world.counters()
        status[k + 1] = world.status
        if two:
            link[k + 1] = link_measured(case, world.pose)
        if progress and k % 500 == 0:
            progress(k, K)
    ctrl.step(K - 1, counts[K - 1], None)
    for i, od in enumerate(ctrl.odo):
        onboard[K - 1, :, i] = od.pose
    th, hp = world.history()
    return {
        "K": K,
        "k_last": k_end + stop,  # last recorded tick per run
        "counts": counts,
        "status": status,
        "link": link,
        "onboard": onboard,
        "hist_t": th,
        "hist": hp,
        "start": world.start,
        "t_session": t0,
        "events": world.events,
        "clamps": world.clamps,
        "trucks": trucks,
    }


# ------------------------------------------------------------------------------------------------
# what the sensors wrote
# ------------------------------------------------------------------------------------------------


def _frame_s(dlc: int, bitrate: float) -> float:
    return (47 + 8 * dlc) * 1.1 / bitrate  # with typical bit stuffing


def write_log(path: Path, case: dict, sim: dict, r: int, epoch: float, rng) -> int:
    """candump -l of one run's sensor frames: every sample's frames back to back on the bus
    after the sensor board's processing delay, stamped on reception (with jitter)."""
    from ...gap.io import encode_payload

    fid = case["fidelity"]
    rob = case["robot"]
    veh = rob["vehicle"]
    T = case["tick_ms"] / 1000.0
    n = int(sim["k_last"][r]) + 1
    k = np.arange(n)
    seq = (int(rng.integers(0, 256)) + k) % 256
    cnt = sim["counts"][:n, r]
    st = sim["status"][:n, r]
    kinds = [(ID_A, 0)]
    if veh != "labmate":
        kinds += [(ID_B, 1), (ID_ROT, None)]
    if veh == "clapper":
        kinds.append((ID_LIN, None))
    base = epoch + k * T + fid["can_proc_delay_s"]
    lines = []
    off = 0.0
    for fid_, tr in kinds:
        if tr is not None:
            bits = rob["trucks"]["AB"[tr]]["counter_bits"]
            width = min(bits, 24)
            vals = {
                "LeftCount": (cnt[:, tr, 0] % (1 << bits)) % (1 << width),
                "RightCount": (cnt[:, tr, 1] % (1 << bits)) % (1 << width),
                "Seq": seq,
                "Status": st[:, tr],
            }
        elif fid_ == ID_ROT:
            lk = sim["link"][:n, r]
            raw = np.round(np.degrees(lk[:, :2]) / (360.0 / 65536)).astype(np.int64) % 65536
            vals = {
                "Alpha": raw[:, 0] * (360.0 / 65536),
                "Beta": raw[:, 1] * (360.0 / 65536),
                "Seq": seq,
                "Status": np.full(n, 3 if veh == "clapper" else 1),
            }
        else:
            vals = {"Length": sim["link"][:n, r, 2], "Seq": seq, "Status": np.full(n, 4)}
        pay = encode_payload(fid_, vals)
        t = base + off + rng.uniform(0, fid["can_rx_jitter_s"], n)
        off += _frame_s(DLC[fid_], fid["can_bitrate"])
        keep = rng.uniform(size=n) >= fid["can_drop_rate"]
        keep[[0, -1]] = True
        hexall = pay[keep].astype("<u8").tobytes().hex().upper()
        w = 2 * DLC[fid_]
        head = f"can0 {fid_:03X}#"
        for i, ti in enumerate(t[keep].tolist()):
            lines.append((ti, f"({ti:.6f}) {head}{hexall[16 * i : 16 * i + w]}"))
    lines.sort(key=lambda x: x[0])
    path.write_text("\n".join(s for _, s in lines) + "\n")
    return len(lines)


def _interp_pose(t: np.ndarray, ht: np.ndarray, hp: np.ndarray) -> np.ndarray:
    """hp (trucks, 3, m) at times t -> (len(t), trucks, 3)."""
    out = np.empty((t.size, hp.shape[0], 3))
    for ti in range(hp.shape[0]):
        for c in range(3):
            out[:, ti, c] = np.interp(t, ht, hp[ti, c])
    return out


def write_truth(path: Path, case: dict, sim: dict, r: int, epoch: float, rng) -> dict:
    """Motion capture of one run: samples at the capture system's own rate and phase, each
    arriving latency (+ a jitter) after the instant it shows and stamped in the robot's clock;
    marker bodies possibly off the truck centres (lever arm) and a small heading offset."""
    fid = case["fidelity"]
    veh = case["robot"]["vehicle"]
    T = case["tick_ms"] / 1000.0
    t_end = int(sim["k_last"][r]) * T
    f = fid["truth_rate_hz"]
    tau = np.arange(rng.uniform(0, 1 / f), t_end, 1 / f)
    ht = np.concatenate([[0.0], sim["hist_t"]])
    hp = np.concatenate([sim["start"][r][..., None], sim["hist"][r]], axis=-1)
    pose = _interp_pose(tau, ht, hp)
    stamp = tau + fid["truth_latency_s"] + rng.uniform(0, fid["truth_jitter_s"], tau.size)
    cd = case["true"]["effects"].get("clock_drift")
    if cd:
        stamp = stamp + cd["offset_s"] + cd["ppm"] * 1e-6 * tau
    stamp = np.maximum.accumulate(stamp)
    stamp = stamp + np.arange(stamp.size) * 1e-9  # strictly increasing after rounding
    keep = (stamp >= 0) & (stamp <= t_end)
    stamp, pose = stamp[keep], pose[keep]
    m = stamp.size
    nt = pose.shape[1]
    rep = pose.copy()
    for ti in range(nt):
        dx, dy = fid["truth_lever_arm_mm"]["AB"[ti]]
        th = pose[:, ti, 2]
        rep[:, ti, 0] += dx * np.cos(th) - dy * np.sin(th) + rng.normal(0, fid["truth_noise_mm"], m)
        rep[:, ti, 1] += dx * np.sin(th) + dy * np.cos(th) + rng.normal(0, fid["truth_noise_mm"], m)
        rep[:, ti, 2] += math.radians(fid["truth_heading_offset_deg"]) + np.radians(
            rng.normal(0, fid["truth_noise_deg"], m)
        )
    deg = 180.0 / math.pi
    cols = [epoch + stamp, rep[:, 0, 0], rep[:, 0, 1], rep[:, 0, 2] * deg]
    head = "t_s,a_x_mm,a_y_mm,a_theta_deg"
    fmt = ["%.6f", "%.4f", "%.4f", "%.6f"]
    if nt == 2:
        lk = link_true(case, rep)
        if veh == "set":
            lk[:, 2] = case["robot"]["trailer"]["trailer_length_mm"]
        cols += [rep[:, 1, 0], rep[:, 1, 1], rep[:, 1, 2] * deg, lk[:, 0] * deg, lk[:, 1] * deg,
                 lk[:, 2]]
        head += ",b_x_mm,b_y_mm,b_theta_deg,alpha_deg,beta_deg,l_mm"
        fmt += ["%.4f", "%.4f", "%.6f", "%.6f", "%.6f", "%.4f"]
    line = ",".join(fmt)
    body = "\n".join(line % tuple(row) for row in np.column_stack(cols).tolist())
    path.write_text(head + "\n" + body + "\n")
    return {"samples": m}


def simulate_case(case: dict, real: Path, seed: int, progress=None) -> dict:
    """Create `real` (must not exist) and write the recorded data of the case into it; return
    the key's extra fields (bump events and the run list). Deterministic for (case, seed)."""
    real = Path(real)
    if real.exists():
        raise FileExistsError(f"{real}: exists; the world writes only into a new folder")
    t_start = time.perf_counter()
    sim = run_world(case, seed, progress)
    twin = imprint.twin_case(case)  # the same case without its effects: how far they reach
    imp = imprint.measure(case, sim, None if twin is None else run_world(twin, seed))
    ss = np.random.SeedSequence([seed, case["case"], 1])
    rng_log, rng_truth, rng_ret, rng_ep = (np.random.default_rng(s) for s in ss.spawn(4))
    tmp = real.parent / f".{real.name}.tmp-{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir(parents=True)
    try:
        (tmp / "robot.json").write_text(json.dumps(case["robot"], indent=1) + "\n")
        epoch0 = 1.7e9 + float(rng_ep.integers(0, 30_000_000))
        fid = case["fidelity"]
        rets = []
        runs = []
        epochs = []
        for r, p in enumerate(case["plan"]):
            ep = round(epoch0 + float(sim["t_session"][r]), 3)
            epochs.append(ep)
            name = p["name"]
            nf = write_log(tmp / f"{name}.log", case, sim, r, ep, rng_log)
            tr = write_truth(tmp / f"{name}.truth.csv", case, sim, r, ep, rng_truth)
            kl = int(sim["k_last"][r])
            a_end = sim["hist"][r, 0, :, _hist_index(sim, kl, case)]
            a_0 = sim["start"][r, 0]
            dx, dy = a_end[0] - a_0[0], a_end[1] - a_0[1]
            dth = float(laws.wrap(a_end[2] - a_0[2]))
            ob = sim["onboard"][kl, r, 0]
            nm = fid["return_noise_mm"]
            rets.append(
                (
                    int(name.rsplit("-", 1)[1]),
                    p["label"],
                    dx + rng_ret.normal(0, nm),
                    dy + rng_ret.normal(0, nm),
                    math.degrees(dth) + rng_ret.normal(0, fid["return_noise_deg"]),
                    ob[0],
                    ob[1],
                    math.degrees(float(laws.wrap(ob[2]))),
                )
            )
            runs.append({"name": name, "frames": nf, "truth_samples": tr["samples"],
                         "duration_s": kl * case["tick_ms"] / 1000.0})
        with (tmp / "returns.csv").open("w") as f:
            f.write("run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,"
                    "x_calc_mm,y_calc_mm,theta_calc_deg\n")
            for row in rets:
                f.write("{},{},{:.3f},{:.3f},{:.4f},{:.3f},{:.3f},{:.4f}\n".format(*row))
        os.rename(tmp, real)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    events = []
    for e in sim["events"]:
        # plain Python values: the events go into the key, a JSON file (numpy ints are not JSON)
        e = {k: v.item() if isinstance(v, np.generic) else v for k, v in e.items()}
        r = e.pop("run_index")
        e["run"] = case["plan"][r]["name"]
        e["t_run_s"] = e["t_s"]  # since the run's start
        e["t_s"] = epochs[r] + e["t_s"]  # the robot's clock, as the log and truth are stamped
        e["truck"] = "AB"[e["truck"]]
        e["wheel"] = ("left", "right")[e["wheel"]]
        events.append(e)
    return {
        "events": events,
        "runs": runs,
        "link_clamps": [int(x) for x in sim["clamps"]],
        "imprint": imp,
        "generation_s": round(time.perf_counter() - t_start, 3),
    }


def _hist_index(sim: dict, k: int, case: dict) -> int:
    """Index in the history of the state at the end of tick k (k >= 1)."""
    T = case["tick_ms"] / 1000.0
    return int(np.searchsorted(sim["hist_t"], k * T - 1e-9))
