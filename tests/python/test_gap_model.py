"""odo-gap's model side against the simulator's own laws (issue 7): the linkage encoders'
quantisation, the slip law under a lagging drive, and the false alarm they caused on the
two-truck vehicles (a no-effect clapper/set run must come out "no significant gap")."""

from __future__ import annotations

import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from gap_support import BUILD, SRC


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def test_censored_residual_is_zero_inside_the_encoder_cell() -> None:
    from odo_tools.gap.modes import _censored

    step = 2 * math.pi / 1024
    code = np.array([0.0, 0.0, 0.0, 10 * step, 2 * math.pi - step])
    x = np.array([0.0, 0.5 * step, 1.5 * step, 9.0 * step, -0.25 * step])
    r = _censored(x, code, step, True)
    # inside (including the lower edge, and across the wrap): zero; outside: the distance
    assert np.allclose(r, [0.0, 0.0, -0.5 * step, step, 0.0], atol=1e-12)
    lin = _censored(np.array([1000.0, 1000.25]), np.array([1000.0, 1000.0]), 0.1, False)
    assert np.allclose(lin, [0.0, -0.15])


def _slip_reference(v_ticks: np.ndarray, tau: float, k: float, a0: float, cap: float):
    """host_sim/src/world.c step_driven + slip_factor transcribed as a plain loop: 1 ms steps,
    a first-order lag behind a command held for each 40 ms tick. Returns, per tick, the mean
    speed the counts show and floor - surface travel."""
    dt, v, prev, means, lost = 0.001, 0.0, 0.0, [], []
    for c in v_ticks:
        acc = loss = 0.0
        for _ in range(40):
            v += (c - v) * (1.0 - math.exp(-dt / tau))
            a = abs(v - prev) / dt * 1e-3
            s = min(k * (a - a0 if a > a0 else 0.0), cap)
            f = 1.0 - s if abs(v) >= abs(prev) else 1.0 / (1.0 - s)
            loss += v * dt * (f - 1.0)
            acc += v * dt
            prev = v
        means.append(acc)
        lost.append(loss)
    return np.array(means), np.array(lost)


RAMP = np.concatenate([np.linspace(0, 600, 16), np.full(20, 600.0), np.linspace(600, 0, 16)])
# an arc's entry and exit (one-tick steps of the command) and a wheel reversing within a tick
STEPS = np.array([0, 100, 100, 300, 300, -200, -200, 0, 0, 250, 50, 50, 0.0])


@pytest.mark.parametrize("tau", [0.002, 0.008, 0.02])
@pytest.mark.parametrize("cmd", [RAMP, STEPS], ids=["ramp", "steps"])
def test_slip_loss_matches_the_simulators_law_seen_through_40ms_counts(
    tau: float, cmd: np.ndarray
) -> None:
    """The commands behind the counts are recovered exactly (model.drive_commands), so the slip
    the model predicts from 40 ms counts is the simulator's, tick by tick."""
    from odo_tools.gap.model import Prepared, slip_loss

    means, ref = _slip_reference(cmd, tau, 0.6, 0.5, 0.2)
    ds = means[:, None, None] * np.ones((1, 1, 2))
    pr = Prepared(None, np.arange(len(means) + 1) * 0.04, ds, np.zeros((len(means) + 1, 1, 2)),
                  [340.0], [75.0], np.full(len(means), 0.04))
    got = slip_loss(pr, {"slip.k_per_m_s2": 0.6, "slip.tau_s": tau}, 0, 0.6)[:, 0]
    assert np.abs(ref).max() > 0.05
    assert np.allclose(got, ref, rtol=1e-9, atol=1e-12)
    # a lag the model gets wrong predicts a different loss: the test can tell them apart
    off = slip_loss(pr, {"slip.k_per_m_s2": 0.6, "slip.tau_s": 1.5 * tau}, 0, 0.6)[:, 0]
    assert not np.allclose(off, ref, rtol=1e-3)


@pytest.mark.parametrize("vehicle", ["clapper", "set"])
def test_a_no_effect_two_truck_vehicle_is_no_significant_gap(vehicle: str, tmp_path: Path) -> None:
    from odo_tools.gap.diagnose import diagnose
    from odo_tools.validation import blind

    case = {"case": 0, "vehicle": vehicle, "kind": "none", "effects": [], "params": {},
            "hidden": {}, "n_bumps": 0,
            "fidelity": {"motor_tau_s": 0.005, "truth_noise_mm": 0.3, "truth_noise_rad": 3e-4,
                         "physics_dt_s": 0.001}}
    real = tmp_path / "real"
    blind.simulate_case(case, real, 11)
    for mode in ("truth", "linkage"):
        rep = diagnose(real, real / "robot.json", 0.5, 1, mode)
        assert rep["verdict"]["effect"] == "no significant gap", (mode, rep["verdict"])
    # and a rotary encoder bias on the same vehicle is found, sized, in both modes
    case["kind"], case["effects"] = "single", ["rotary_bias"]
    case["params"] = {"rotary_bias.alpha_deg": -1.3}
    shutil.rmtree(real)
    blind.simulate_case(case, real, 12)
    for mode in ("truth", "linkage"):
        rep = diagnose(real, real / "robot.json", 0.5, 1, mode)
        v = rep["verdict"]
        assert v["effect"] == "rotary_bias", (mode, v)
        assert v["params"]["rotary_bias.alpha_deg"] == pytest.approx(-1.3, abs=0.1)


def _two_trucks(ds_a: np.ndarray, ds_b: np.ndarray, link=None, driven=(True, True)):
    from odo_tools.gap.model import Prepared

    ds = np.stack([ds_a, ds_b], axis=1)  # (n-1, 2 trucks, 2 wheels)
    n = ds.shape[0] + 1
    S = np.concatenate([np.zeros((1, 2, 2)), np.cumsum(np.abs(ds), axis=0)])
    return Prepared(
        None, np.arange(n) * 0.04, ds, S, [340.0, 340.0], [75.0, 75.0], np.full(n - 1, 0.04),
        driven=list(driven), link=link,
    )  # fmt: skip


def test_clapper_link_clamp_pushes_both_trucks_half_way() -> None:
    """world.c clamp_link: A drives 300 mm away from a standing B on a 1000 mm link with range
    [900, 1100]; the 200 mm beyond the range are taken up half by each truck."""
    from odo_tools.gap.model import dead_reckon

    a = np.full((30, 2), 10.0)
    pr = _two_trucks(a, np.zeros((30, 2)), link=(1000.0, 0.0, 0.0, 900.0, 1100.0, None))
    pa, pb = dead_reckon(pr, {}, 0), dead_reckon(pr, {}, 1)
    assert pa[-1, 0] == pytest.approx(200.0, abs=1e-9) and pb[-1, 0] == pytest.approx(100.0)
    assert np.allclose(pa[:, 1], 0.0) and np.allclose(pb[:, 2], 0.0)
    # inside the range nothing moves the trucks but their wheels
    pr = _two_trucks(a[:5], np.zeros((5, 2)), link=(1000.0, 0.0, 0.0, 900.0, 1100.0, None))
    assert dead_reckon(pr, {}, 0)[-1, 0] == pytest.approx(50.0) and np.allclose(
        dead_reckon(pr, {}, 1), 0.0
    )
    # a reading that is not at the range's end (gate) forbids the clamp
    gate = np.zeros(31, dtype=bool)
    pr = _two_trucks(a, np.zeros((30, 2)), link=(1000.0, 0.0, 0.0, 900.0, 1100.0, gate))
    assert dead_reckon(pr, {}, 0)[-1, 0] == pytest.approx(300.0)


def test_clapper_stop_in_libodosim_equals_a_tick_by_tick_replay_of_world_c() -> None:
    """model._clamp_push asks libodosim for world.c's stop over the whole track; a plain replay of
    the rule (each tick: move both trucks, then halve the excess along the link where the gate
    allows) gives the same pushes on random walks, gated or not, through both ends of the range."""
    from odo_tools.gap.model import _clamp_push

    def replay(pa, pb, lo, hi, gate):
        push, o = np.zeros((len(pa), 2)), np.zeros(2)
        for i in range(1, len(pa)):
            r = pa[i, :2] - pb[i, :2] + 2.0 * o
            ln = float(np.hypot(*r))
            if (ln < lo or ln > hi) and (gate is None or gate[i]):
                o += 0.5 * ((lo if ln < lo else hi) - ln) * r / ln
            push[i] = o
        return push

    rng = np.random.default_rng(5)
    ends = set()
    for k in range(12):
        n = int(rng.integers(50, 800))
        pa = np.cumsum(rng.normal(0.0, 3.0, (n, 3)), axis=0)
        pb = np.cumsum(rng.normal(0.0, 3.0, (n, 3)), axis=0) - [1000.0, 0.0, 0.0]
        gate = rng.random(n + 2) < 0.7 if k % 2 else None
        want = replay(pa, pb, 985.0, 1015.0, gate)
        got = _clamp_push(pa, pb, 985.0, 1015.0, gate)
        assert got is not None and np.allclose(got, want, atol=1e-9, rtol=0.0), k
        ln = np.hypot(*(pa[:, :2] - pb[:, :2]).T)
        ends |= {"lo" if ln.min() < 985.0 else "", "hi" if ln.max() > 1015.0 else ""}
    assert {"lo", "hi"} <= ends
    with pytest.raises(ValueError):
        _clamp_push(pa, pb, 1015.0, 985.0, None)


def test_drive_effects_do_not_act_on_a_passive_trailer() -> None:
    """world.c: slip and skid live in step_driven; a set's trailer rolls passively."""
    from odo_tools.gap.model import floor_travel

    v = np.concatenate([np.zeros(5), np.full(20, 20.0), np.zeros(5)])
    w = np.column_stack([v, 1.05 * v])
    P = {"slip.k_per_m_s2": 1.0, "skid.k_s": 0.3, "skid.a0_m_s2": 0.0}
    pr = _two_trucks(w, w, driven=(True, False))
    da, _, la, _ = floor_travel(pr, P, 0)
    db, _, lb, _ = floor_travel(pr, P, 1)
    assert not np.allclose(da, w) and np.abs(la).max() > 0  # the driven truck slips and skids
    assert np.allclose(db, w) and np.allclose(lb, 0.0)


def test_roughness_window_share_matches_a_direct_count() -> None:
    """A grain of horizontal span s, its excess spread evenly over it, at a uniform phase: the
    share f a window of L mm sees has E[f^2] L = L - s/3 (s <= L); counted here directly."""
    from odo_tools.gap.model import rough_window_var

    R, h = 75.0, 3.0
    s = 2.0 * math.sqrt(2 * R * h - h * h)
    for L in (120.0, 0.5 * s):
        u = np.linspace(-s, L, 200001)  # grain start relative to the window's start
        f = (np.clip(u + s, 0.0, L) - np.clip(u, 0.0, L)) / s
        direct = np.trapezoid(f * f, u) / L
        # one height: hmax tiny band around h via n=1 (midpoint of [0, hmax] = h)
        _, _, q = rough_window_var(R, 2 * h, np.array([L]), n=1)
        assert q[0] == pytest.approx(direct, rel=1e-3)


def test_count_loss_at_a_rate_ceiling_recovers_the_hidden_speed() -> None:
    """model.count_loss_plateau: a decoder that counts at most 600 mm/s of wheel travel while the
    wheel runs up to 1000 mm/s at 2 m/s^2 and back; the counts' flat top is the ceiling
    (plateau_level), and with the true excess and acceleration the hidden travel comes back
    (to the tick where the wheel crosses the ceiling inside a tick). A slower run whose counts
    never reach the ceiling is left as it is."""
    from odo_tools.gap.model import Prepared, count_loss_plateau, plateau_level

    dt, a, vmax, ceil = 0.02, 2000.0, 1000.0, 600.0
    fine = np.arange(0.0, 2.0, 1e-4)
    ramp = np.minimum(np.minimum(a * fine, a * (fine[-1] - fine)), vmax)
    v = np.concatenate([np.zeros(2000), ramp, np.zeros(2000)])  # 1e-4 s samples
    per = round(dt / 1e-4)
    true = v.reshape(-1, per).sum(axis=1) * 1e-4  # mm per tick
    counted = np.minimum(v, ceil).reshape(-1, per).sum(axis=1) * 1e-4

    def prep(d: np.ndarray) -> Prepared:
        ds = d[:, None, None] * np.ones((1, 1, 2))
        n = d.size + 1
        S = np.concatenate([np.zeros((1, 1, 2)), np.cumsum(np.abs(ds), axis=0)])
        return Prepared(None, np.arange(n) * dt, ds, S, [400.0], [75.0], np.full(n - 1, dt))

    pr, slow = prep(counted), prep(0.5 * counted)
    assert plateau_level([pr, slow]) == pytest.approx(ceil, rel=1e-9)
    # ticks above the flat top, each at its own speed (a truck's frame late by a tick, the
    # next one doubled): the ceiling is still where the counts sit, not the fastest tick
    spiky = counted.copy()
    spiky[[5, 40, 90]] = ceil * dt * np.array([2.0, 1.3, 1.7])
    assert plateau_level([prep(spiky)]) == pytest.approx(ceil, rel=1e-9)
    # ... and a decoder that never saturated reads its top cruise, not a spike above it
    cruise = 0.5 * counted
    cruise[[7]] = 0.9 * ceil * dt
    assert plateau_level([prep(cruise)]) == pytest.approx(0.5 * ceil, rel=1e-9)
    P = {
        "count_loss@plateau.level_mm_s": ceil,
        "count_loss@plateau.excess_mm_s": vmax - ceil,
        "count_loss@plateau.a_m_s2": a / 1000.0,
    }
    got = count_loss_plateau(pr, pr.ds[:, 0, :].copy(), 0, P)[:, 0]
    assert true.sum() - counted.sum() > 200.0  # the counts lost 20 cm
    assert abs(got.sum() - true.sum()) < 0.01 * (true.sum() - counted.sum())
    assert np.abs(got - true).max() < 0.02 * vmax * dt  # tick by tick, edges included
    assert np.array_equal(count_loss_plateau(slow, slow.ds[:, 0, :].copy(), 0, P), slow.ds[:, 0, :])
    # a wrong acceleration predicts another travel: the test can tell them apart
    P["count_loss@plateau.a_m_s2"] = 1.0
    off = count_loss_plateau(pr, pr.ds[:, 0, :].copy(), 0, P)[:, 0]
    assert abs(off.sum() - true.sum()) > 0.1 * (true.sum() - counted.sum())



def test_a_rate_ceiling_is_reached_at_the_rate_the_counts_show() -> None:
    """model.count_loss_plateau: one wheel reaches the decoder's ceiling twice, from rest at its
    drive's 2 m/s^2 and from a cruise just below it at 0.2 m/s^2 (a gentler speed change), to
    the same hidden speed each time. Each stretch's hidden speed goes on at the rate its own
    counts came in and go out at, so with the drive's a and the true excess both stretches'
    lost travel comes back; one rate for both (the law before) misses one or the other."""
    from odo_tools.gap.model import Prepared, count_loss_plateau, plateau_level

    dt, ceil, vmax, step = 0.04, 600.0, 800.0, 1e-4

    def ramp(v0: float, v1: float, a: float) -> np.ndarray:
        return v0 + np.sign(v1 - v0) * np.minimum(np.arange(0.0, 4.0, step) * a, abs(v1 - v0))

    def hold(v: float, s: float) -> np.ndarray:
        return np.full(round(s / step), v)

    v = np.concatenate([hold(0.0, 0.4), ramp(0.0, vmax, 2000.0)[: round(0.4 / step)],
                        hold(vmax, 2.0), ramp(vmax, 300.0, 2000.0)[: round(0.25 / step)],
                        hold(300.0, 1.0), ramp(300.0, 560.0, 2000.0)[: round(0.13 / step)],
                        hold(560.0, 1.0), ramp(560.0, vmax, 200.0)[: round(1.2 / step)],
                        hold(vmax, 3.0), ramp(vmax, 0.0, 2000.0)[: round(0.4 / step)],
                        hold(0.0, 0.8)])  # fmt: skip
    per = round(dt / step)
    v = v[: v.size // per * per]
    true = v.reshape(-1, per).sum(axis=1) * step  # mm per tick
    counted = np.minimum(v, ceil).reshape(-1, per).sum(axis=1) * step
    ds = counted[:, None, None] * np.ones((1, 1, 2))
    n = counted.size + 1
    S = np.concatenate([np.zeros((1, 1, 2)), np.cumsum(np.abs(ds), axis=0)])
    pr = Prepared(None, np.arange(n) * dt, ds, S, [400.0], [75.0], np.full(n - 1, dt))
    assert plateau_level([pr]) == pytest.approx(ceil, rel=1e-9)
    second = np.arange(true.size) * dt > 4.5  # the gentle stretch and what follows
    lost = [
        true[~second].sum() - counted[~second].sum(),
        true[second].sum() - counted[second].sum(),
    ]
    assert min(lost) > 150.0  # each stretch lost 15 cm or more

    def travel(a: float) -> list[float]:
        P = {"count_loss@plateau.level_mm_s": ceil, "count_loss@plateau.excess_mm_s": vmax - ceil,
             "count_loss@plateau.a_m_s2": a}  # fmt: skip
        got = count_loss_plateau(pr, pr.ds[:, 0, :].copy(), 0, P)[:, 0]
        return [
            got[~second].sum() - counted[~second].sum(),
            got[second].sum() - counted[second].sum(),
        ]

    for got, want in zip(travel(2.0), lost, strict=True):
        assert got == pytest.approx(want, rel=0.03)
    # the one-rate law (2 m/s^2 on both ramps: E T - E^2 / a over a stretch of length T)
    # over-counts the gentle stretch by about 9 cm
    E, T = vmax - ceil, dt * np.count_nonzero(second & (counted >= ceil * dt * (1 - 1e-9)))
    assert abs(E * T - E * E / 2000.0 - lost[1]) > 0.1 * lost[1]
    # a run of one tick or none has no stretch and no ramp to read: its counts come back
    P = {"count_loss@plateau.level_mm_s": ceil, "count_loss@plateau.excess_mm_s": vmax - ceil}
    for m in (1, 0):
        d = np.zeros((m, 1, 2))
        few = Prepared(None, np.arange(m + 1) * dt, d, np.zeros((m + 1, 1, 2)), [400.0], [75.0],
                       np.full(m, dt))  # fmt: skip
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # the median tick of no tick
            assert count_loss_plateau(few, d[:, 0, :].copy(), 0, P).shape == (m, 2)


def test_a_rate_ceiling_whose_flat_top_scatters_hides_one_sprint_on_both_wheels() -> None:
    """model.count_loss_plateau: a straight sprint, both wheels at 1130 mm/s behind a decoder
    that counts 950, reached at 0.5 m/s^2. Each wheel's flat top scatters up to 0.6 % under
    its top, tick by tick and wheel by wheel (whole counts and stamps; dev seed 4532 case 39),
    so only some ticks lie within PLATEAU_TOL of the ceiling. The sprint is one on each wheel,
    its hidden speed rises from where the counts' ramp crosses the ceiling, and both wheels
    get back the travel they lost: the robot does not turn where no count says it did."""
    from odo_tools.gap.model import PLATEAU_TOL, Prepared, count_loss_plateau, plateau_level

    dt, a, vmax, ceil, step = 0.025, 500.0, 1130.0, 950.0, 1e-4
    fine = np.arange(0.0, 6.0, step)
    ramp = np.minimum(np.minimum(a * (fine + 1.0), a * (fine[-1] + 1.0 - fine)), vmax)
    v = np.concatenate([np.zeros(4000), ramp, np.zeros(4000)])
    per = round(dt / step)
    v = v[: v.size // per * per]
    true = v.reshape(-1, per).sum(axis=1) * step
    counted = np.minimum(v, ceil).reshape(-1, per).sum(axis=1) * step
    top = counted >= ceil * dt * (1 - 1e-9)
    rng = np.random.default_rng(3)
    ds = np.repeat(counted[:, None, None], 2, axis=2)
    ds[top, 0, :] *= 1.0 - rng.uniform(0.0, 0.006, (int(top.sum()), 2))
    n = counted.size + 1
    S = np.concatenate([np.zeros((1, 1, 2)), np.cumsum(np.abs(ds), axis=0)])
    pr = Prepared(None, np.arange(n) * dt, ds, S, [400.0], [75.0], np.full(n - 1, dt))
    level = plateau_level([pr])
    on = ds[:, 0, :] / dt >= level * (1.0 - PLATEAU_TOL)
    assert 0.2 < on[top].mean() < 0.8  # the flat top falls into many stretches on each wheel
    assert np.count_nonzero(np.diff(on[:, 0].astype(int)) == 1) > 10
    P = {
        "count_loss@plateau.level_mm_s": level,
        "count_loss@plateau.excess_mm_s": vmax - level,
        "count_loss@plateau.a_m_s2": a / 1000.0,
    }
    got = count_loss_plateau(pr, ds[:, 0, :].copy(), 0, P) - ds[:, 0, :]
    lost = true.sum() - counted.sum()
    assert lost > 500.0  # half a metre hidden on each wheel
    for w in (0, 1):
        assert got[:, w].sum() == pytest.approx(lost, rel=0.03)
    assert abs(got[:, 0].sum() - got[:, 1].sum()) < 0.01 * lost  # no turn the counts never made


def test_a_rate_ceiling_is_found_under_jittered_stamps() -> None:
    """model.counted_speed: a decoder at its ceiling counts the same per tick; a log stamped on
    arrival jitters the recorded tick lengths (here +-0.7 % on 10 ms) without the counts
    following them. The ceiling and every saturated tick are found on the nominal tick, and the
    hidden travel comes back; where the counts do follow the recorded lengths (a clock that
    samples late), the recorded lengths are kept."""
    from odo_tools.gap.model import (
        Prepared,
        count_loss_plateau,
        counted_speed,
        plateau_level,
    )

    dt, a, vmax, ceil, mm = 0.01, 1000.0, 980.0, 750.0, 0.0025
    fine = np.arange(0.0, 4.0, 1e-4)
    ramp = np.minimum(np.minimum(a * fine, a * (fine[-1] - fine)), vmax)
    v = np.concatenate([np.zeros(1000), ramp, np.zeros(1000)])  # 1e-4 s samples
    per = round(dt / 1e-4)
    cum = np.concatenate([[0.0], np.cumsum(np.minimum(v, ceil) * 1e-4)])[::per]
    counted = np.diff(np.floor(cum / mm)) * mm  # whole counts per tick
    true = v.reshape(-1, per).sum(axis=1) * 1e-4
    n = counted.size + 1
    rng = np.random.default_rng(5)

    def prep(d: np.ndarray, stamps: np.ndarray) -> Prepared:
        ds = d[:, None, None] * np.ones((1, 1, 2))
        S = np.concatenate([np.zeros((1, 1, 2)), np.cumsum(np.abs(ds), axis=0)])
        return Prepared(
            None, stamps, ds, S, [400.0], [75.0], np.diff(stamps), count_mm=[mm]
        )

    stamps = np.arange(n) * dt + rng.uniform(-0.35e-4, 0.35e-4, n)  # read on arrival
    pr = prep(counted, stamps)
    rec = np.abs(pr.ds[:, 0, :]) / pr.dt[:, None]
    top = rec[rec > 0.98 * ceil]
    assert np.ptp(top) / ceil > 3 * 0.003  # the stamps spread the flat top beyond PLATEAU_TOL
    assert plateau_level([pr]) == pytest.approx(ceil, rel=5e-4)
    sat = np.abs(pr.ds[:, 0, 0]) >= ceil * dt * (1 - 1e-3)
    assert np.all(counted_speed(pr, 0)[sat, 0] >= plateau_level([pr]) * (1 - 0.003))
    P = {
        "count_loss@plateau.level_mm_s": plateau_level([pr]),
        "count_loss@plateau.excess_mm_s": vmax - ceil,
        "count_loss@plateau.a_m_s2": a / 1000.0,
    }
    got = count_loss_plateau(pr, pr.ds[:, 0, :].copy(), 0, P)[:, 0]
    assert true.sum() - counted.sum() > 500.0  # the counts lost half a metre
    assert abs(got.sum() - true.sum()) < 0.02 * (true.sum() - counted.sum())
    # a clock whose ticks themselves vary: the counts follow the recorded lengths
    ticks = np.concatenate([[0.0], np.cumsum(dt * rng.uniform(0.99, 1.01, n - 1))])
    cum2 = np.interp(ticks, np.arange(cum.size) * dt, cum)
    pr2 = prep(np.diff(np.floor(cum2 / mm)) * mm, ticks)
    assert np.array_equal(counted_speed(pr2, 0), np.abs(pr2.ds[:, 0, :]) / pr2.dt[:, None])
    assert plateau_level([pr2]) == pytest.approx(ceil, rel=5e-4)
