"""Slip under the laws a real robot shows besides the catalog's (issue 13 item 3): one tyre
slipping more than the other while the truck speeds up, and traction shared with the turn's
lateral acceleration (the friction circle). The independent world draws both; each was
"unexplained" until the diagnosis' laws carried them."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from gap_support import BUILD, SRC, indep_case, indep_named


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def _ramp(n: int, dv: float, dt: float = 0.04) -> tuple[SimpleNamespace, np.ndarray]:
    """Both wheels speeding up by dv mm/s every tick from rest: (pr, counted travel per tick)."""
    v = dv * np.arange(1, n + 1, dtype=float)
    return SimpleNamespace(dt=np.full(n, dt)), np.column_stack([v * dt, v * dt])


def test_asymmetric_accel_slip_spins_one_wheel_more_and_turns_the_truck() -> None:
    """2.5 m/s^2 on both wheels, k 0.1 per m/s^2 above 0.5 m/s^2: each wheel's floor travel is
    short by k (1 -/+ asym) (a - a0) of what it counted, so asym 0.3 leaves the left wheel
    ahead (the truck turns right) and asym 0 leaves them level."""
    from odo_tools.gap.model import slip_accel

    pr, ds = _ramp(10, 100.0)
    P = {"slip@accel.k_per_m_s2": 0.1, "slip@accel.a0_m_s2": 0.5}
    level = slip_accel(pr, ds, P)
    assert np.allclose(level[:, 0], level[:, 1])
    out = slip_accel(pr, ds, {**P, "slip@accel.asym": 0.3})
    assert np.allclose(out[:, 0] / ds[:, 0], 1 - 0.1 * 0.7 * 2.0)
    assert np.allclose(out[:, 1] / ds[:, 1], 1 - 0.1 * 1.3 * 2.0)
    assert np.sum(out[:, 0]) > np.sum(out[:, 1])


def test_accel_slip_by_a_power_leaves_a_move_short_where_it_brakes_harder_than_it_starts() -> None:
    """A move from rest to 1 m/s at 2 m/s^2 and back to rest at 4 m/s^2 (40 ms ticks), k 0.05,
    no threshold. Linear in the acceleration (p 1) the spin while speeding up and the drag while
    slowing down cancel (each k v^2 / 2 = 25 mm, to within the drag's 1 / (1 - s)); squared
    (p 2) the drag, k a^2 over the braking's v^2 / (2 a), is twice the spin, and the floor
    travel comes out long by k v^2 (a_down - a_up) / 2 = 50 mm."""
    from odo_tools.gap.model import slip_accel

    dt = 0.04
    up = np.arange(1, 13) * 2000.0 * dt  # mm/s: 80 ... 960 (then 1000 from the next tick)
    v = np.concatenate([up, [1000.0] * 10, 1000.0 - np.arange(1, 7) * 4000.0 * dt, [0.0] * 3])
    v = np.minimum(v, 1000.0)
    ds = np.column_stack([v * dt, v * dt])
    pr = SimpleNamespace(dt=np.full(v.size, dt))
    P = {"slip@accel.k_per_m_s2": 0.05, "slip@accel.a0_m_s2": 0.0}
    linear = slip_accel(pr, ds, P).sum(axis=0) - ds.sum(axis=0)
    squared = slip_accel(pr, ds, {**P, "slip@accel.exponent": 2.0}).sum(axis=0) - ds.sum(axis=0)
    assert np.all(np.abs(linear) < 5.0), linear
    assert np.allclose(squared, 50.0, rtol=0.1), squared


def test_a_labmates_slip_on_its_spot_turns_is_named_slip_by_the_power_law(tmp_path: Path) -> None:
    """Independent world, dev seed 4501 case 44: a LabMate whose tyres slip by k |a|^p (p 1.25,
    k 15 % below and above its mean on the left and right). Most of its misfit lies in the spot
    turns, which the phases count as turns, so nothing proposed slip's other laws:
    "unexplained", the catalog's slip leaving the held-out runs at 3.3 x the background. Tried
    always and linear in the acceleration, the law left a heading step per turn that an Eb took
    up ("eb + slip"); with the power it is slip alone."""
    _, rep = indep_named(4501, 44, tmp_path, "labmate", {"slip": "accel"}, "slip", "accel")
    assert rep["verdict"]["params"]["slip@accel.exponent"] != 1.0
    hd = rep["heldout"]
    assert hd["ratio_after"] < 2.0 < hd["ratio_before"], hd


def test_traction_left_to_speed_up_shrinks_with_the_turns_lateral_acceleration() -> None:
    """Wheels speeding up by 1.25 and 1.875 m/s^2 under a 3 m/s^2 traction limit: the floor
    keeps up with both while the turn is slow; once the arc's lateral acceleration v w passes
    2.7 m/s^2 the friction circle leaves less than 1.3 m/s^2 to speed up, and both spin."""
    from odo_tools.gap.model import slip_traction

    b = 200.0
    pr, ds = _ramp(20, 50.0)
    assert np.allclose(slip_traction(pr, ds, 3.0, b), ds)  # straight: 1.25 m/s^2 < 3
    arc = ds * np.array([1.0, 1.5])
    v = arc / pr.dt[:, None]
    alat = 0.5 * (v[:, 0] + v[:, 1]) * (v[:, 1] - v[:, 0]) / b
    floor = slip_traction(pr, arc, 3.0, b)
    tight = alat > 2700.0
    assert tight.sum() >= 2
    assert np.all(floor[tight] < arc[tight] - 1e-9)
    loose = alat < 2000.0
    assert np.allclose(floor[loose], arc[loose])


def _counted_ramp(a: float, q: float, T: float, vmax: float = 500.0, tail: float = 2.0):
    """A wheel speeding up at a (mm/s^2) to vmax and holding, read by a counter of q mm edges
    every T s: (pr, counted travel per tick of both wheels)."""
    t = np.arange(0.0, vmax / a + tail + 1e-9, T)
    ta = vmax / a
    x = np.where(t < ta, 0.5 * a * t * t, 0.5 * a * ta * ta + vmax * (t - ta))
    d = np.diff(np.floor(x / q)) * q
    return SimpleNamespace(dt=np.full(d.size, T)), np.column_stack([d, d])


def test_whole_edges_do_not_spin_a_wheel_the_floor_grips() -> None:
    """A wheel speeding up at 0.6 m/s^2, counted in 0.35 mm edges every 40 ms: one edge more or
    less per tick moves the tick's speed change by up to 440 mm/s^2, past a 0.7 or 0.8 m/s^2
    grip the wheel never reached. Read tick by tick, the traction law spun it where the floor
    held; with each tick's speed weighed with its neighbours' it loses nothing. Beyond the
    grip (0.4 m/s^2), the loss is the rate-limited ramp's: the floor lags by (a - g) t and
    catches up at g, (a - g) t_a^2 / 2 (1 + (a - g) / g) = 104 mm."""
    from odo_tools.gap.model import slip_traction

    pr, ds = _counted_ramp(600.0, 0.35, 0.04)
    for grip in (0.7, 0.8):
        assert np.allclose(slip_traction(pr, ds, grip, 400.0), ds)
    a, g, ta = 600.0, 400.0, 500.0 / 600.0
    want = (a - g) * ta * ta / 2 * (1 + (a - g) / g)
    lost = ds.sum(axis=0) - slip_traction(pr, ds, g / 1000.0, 400.0).sum(axis=0)
    assert lost == pytest.approx([want, want], rel=0.02)


def test_accel_slip_reads_short_ticks_over_a_span_not_their_edges() -> None:
    """A wheel speeding up at 1 m/s^2 to 0.5 m/s, counted in 0.6 mm edges every 10 ms: one edge
    more or less per tick is 60 mm/s of speed, several m/s^2 between neighbouring ticks, so a
    law read over three ticks spun the wheel on ticks it only cruised and lost 6.97 mm for the
    3.13 mm that k 0.05 per m/s^2 above 0.5 m/s^2 takes over the ramp: k (a - a0) v^2 / 2a.
    Read over +- 50 ms, it loses what the ramp does; on 40 ms ticks, as before."""
    from odo_tools.gap.model import slip_accel

    P = {"slip@accel.k_per_m_s2": 0.05, "slip@accel.a0_m_s2": 0.5}
    want = 0.05 * (1.0 - 0.5) * 500.0**2 / 2 / 1000.0
    for T in (0.01, 0.04):
        pr, ds = _counted_ramp(1000.0, 0.6, T)
        lost = ds.sum(axis=0) - slip_accel(pr, ds, P).sum(axis=0)
        assert lost == pytest.approx([want, want], rel=0.03), T


def test_traction_reads_coarse_edges_on_short_ticks_over_a_span() -> None:
    """The ramp above counted in 0.6 mm edges every 10 ms: one edge is 60 mm/s of speed, and
    the traction law, its speeds read over three ticks, spun the wheel by 11.2 mm under a 0.8
    m/s^2 grip it never reached and lost 122 mm for the ramp's 104 under a 0.4 m/s^2 one. Read
    over as many ticks as the edges need (model._grip_speeds), the floor keeps up where it grips
    and loses what the rate-limited ramp does; fine edges keep the three ticks' reading."""
    from odo_tools.gap.model import _grip_speeds, _wheel_speeds, slip_traction

    a, g, ta = 600.0, 400.0, 500.0 / 600.0
    want = (a - g) * ta * ta / 2 * (1 + (a - g) / g)
    for q in (0.6, 2.3):
        pr, ds = _counted_ramp(600.0, q, 0.01)
        assert np.all(ds.sum(axis=0) - slip_traction(pr, ds, 0.8, 400.0, q).sum(axis=0) < 2.0)
        lost = ds.sum(axis=0) - slip_traction(pr, ds, g / 1000.0, 400.0, q).sum(axis=0)
        assert lost == pytest.approx([want, want], rel=0.07), q
    pr, ds = _counted_ramp(600.0, 0.12, 0.01)
    assert np.array_equal(_grip_speeds(pr, ds, 0.12), _wheel_speeds(pr, ds))


def test_traction_slip_on_coarse_edges_and_short_ticks_is_named(tmp_path: Path) -> None:
    """Independent world, fresh seed 3281 case 12: a LabMate whose floor speed changes at most
    1.20 m/s^2, counted in 2.3 mm edges on 10 ms ticks. Its speeds read over three ticks, the
    traction law took the tracks further off at any grip and the verdict was "unexplained"
    (slip's acceleration law best, held out 1.91 -> 2.38 x the background); read over the
    ticks its edges need, the limit is fitted to 5 % and the held-out runs closed."""
    c, rep = indep_named(3281, 12, tmp_path, "labmate", {"slip": "traction"}, "slip", "traction")
    a = rep["verdict"]["params"]["slip@traction.a_max_m_s2"]
    assert a == pytest.approx(c["true"]["effects"]["slip"]["a_lim_m_s2"], rel=0.05)
    assert rep["verdict"]["evidence"]["heldout_ratio_after"] <= 1.5, rep["verdict"]["evidence"]


def test_accel_slip_on_short_ticks_is_named(tmp_path: Path) -> None:
    """Independent world, dev seed 4091 case 34: a LabMate on 10 ms ticks whose tyres slip
    k 0.040 at 1 m/s^2 (power 1.42, the left one 1.8 x the right). The acceleration law, its
    speeds read over three ticks, fitted its threshold to the edges' jitter and left the
    held-out runs at 8.6 x the background (7.8 nominal): "unexplained". Read over +- 50 ms it
    names the slip and closes them."""
    c, rep = indep_named(4091, 34, tmp_path, "labmate", {"slip": "accel"}, "slip", "accel")
    assert rep["verdict"]["evidence"]["heldout_ratio_after"] <= 3.0, rep["verdict"]["evidence"]
    asym = rep["verdict"]["params"]["slip@accel.asym"]
    assert asym == pytest.approx(c["true"]["effects"]["slip"]["asym"], abs=0.15)


def test_asymmetric_accel_slip_is_named(tmp_path: Path) -> None:
    """Independent world, seed 2701 case 2: a LabMate whose right tyre slips 1.8 x as much as
    its left under acceleration (k 0.079 at 1 m/s^2, power 1.46). Symmetric, the accel law left
    the held-out misfit at 5.9 x the background ("unexplained"); with asym it is slip."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(2701, 2, real, "labmate", {"slip": "accel"})
    v = diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] == "slip", v


def test_traction_slip_on_arcs_is_not_read_as_truth_latency(tmp_path: Path) -> None:
    """Independent world, seed 2701 case 21: a LabMate whose floor speed changes at most
    0.92 m/s^2 (traction law, the friction circle's share on arcs) under a controller that asks
    1.09. Its starts lag the counts like a 100 ms late truth; read as latency, the traction law
    left 34 x the background ("unexplained"). As slip, with the circle, it is named."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(2701, 21, real, "labmate", {"slip": "traction"})
    rep = diagnose(real, real / "robot.json").to_dict()
    assert rep["verdict"]["effect"] == "slip", rep["verdict"]
    assert max(abs(v) for v in rep["instrument"]["latency_s"].values()) < 0.05


def test_a_clock_no_run_fixed_is_found_under_slip_and_kept(tmp_path: Path) -> None:
    """Independent world, dev seed 2851 case 25: a set with no effect whose truth runs 14.8 ms
    late on 50 ms ticks, too little for any run's track to fix. With no latency, the slip laws
    took the shift (slip@accel 201 BIC above nominal) and the verdict was "unexplained" at
    2.44 x the background. The one clock is now scanned under slip, 15 ms is found, and the
    judge keeps it for the runs whose tracks fix none: no significant gap."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    c = indep_case(2851, 25, real, "set", {})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]
    true = c["fidelity"]["truth_latency_s"]
    assert all(abs(v - true) < 0.005 for v in rep["instrument"]["latency_s"].values())


def test_a_short_read_in_a_session_that_disagrees_keeps_the_scanned_clock(tmp_path: Path) -> None:
    """Independent world, dev seed 2821 case 9: a set with no effect whose truth runs 31 ms late
    on 20 ms ticks, its robot's encoders coarse (7 mm a count). The scan under slip chose one
    clock, 30 ms; the judge read each run again under the best candidate (scrub), three runs
    read 39-40 ms and six less than 1.5 ticks, so the session had no one clock and the short
    reads were taken as none. The held-out runs then sat 6.98 x the background in their
    accelerations: "unexplained". A short read now takes the clock the scan chose (none where
    no scan chose one): no significant gap."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    c = indep_case(2821, 9, real, "set", {})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]
    true = c["fidelity"]["truth_latency_s"]
    lat = rep["instrument"]["latency_s"].values()
    assert all(abs(v - true) < 0.01 for v in lat), rep["instrument"]


def test_slip_read_as_latency_is_told_apart_before_the_pairs(tmp_path: Path) -> None:
    """Simulator world, seed 2712 case 28: a clapper with catalog slip (k 0.98 per m/s^2) and a
    truth without latency, whose starts read as 97 ms on four runs. With slip among the top
    singles the ranking asks at once whether the latency is the slip, drops it, and ranks again
    before fitting any pair (it used to fit pairs and a triple first: 34 s of 10-run diagnosis
    for 18 s); the verdict is slip either way. Once each truth window carried its counting
    variance the single's own start stopped at k 0.43 and scrub + slip won; the single refitted
    from that pair (diagnose._polish) is slip at k 0.89 again."""
    from gap_support import sim_case
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    sim_case(2712, 28, real, "clapper", ["slip"])
    said: list[str] = []
    rep = diagnose(real, real / "robot.json", mode="truth", progress=said.append).to_dict()
    assert rep["verdict"]["effect"] == "slip", rep["verdict"]
    told = said.index("latency and slip told apart: ranking again")
    assert not any(m.startswith("fitting") and "+" in m for m in said[:told]), said[:told]
    assert said.count("latency and slip told apart: ranking again") == 1
    assert max(abs(v) for v in rep["instrument"]["latency_s"].values()) == 0.0


def test_a_clock_screened_with_bumps_held_is_checked_against_none(tmp_path: Path) -> None:
    """Simulator world, seed 2962 case 55: a clapper with floor bumps and catalog slip, and a
    truth without latency whose starts read as 217-296 ms on four runs. The clocks were screened
    with the bumps placed under those latencies held, and 20 ms screened best, though fitted to
    the end it was far worse than none; the next ranking's slip single asked again, chose none,
    and a third ranking followed. None is now fitted to the end beside the screen's best: the
    latency and slip are told apart once, and the clock is none."""
    from gap_support import sim_case
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    sim_case(2962, 55, real, "clapper", ["bumps", "slip"])
    said: list[str] = []
    rep = diagnose(real, real / "robot.json", mode="truth", progress=said.append).to_dict()
    assert rep["verdict"]["effect"] == "bumps+slip", rep["verdict"]
    assert said.count("latency and slip told apart: ranking again") == 1, said
    assert max(abs(v) for v in rep["instrument"]["latency_s"].values()) == 0.0


def test_traction_slip_the_phases_do_not_propose_is_still_tried(tmp_path: Path) -> None:
    """Independent world, seed 2791 case 51: a LabMate whose floor speed changes at most
    0.84 m/s^2. It loses so much on every start that the track is off everywhere after the first,
    the phases propose no family, and the catalog's slip alone left the held-out runs worse than
    the nominal model ("unexplained", 19.9 -> 28.3 x the background). The traction laws are tried
    on every robot (hypotheses.ALWAYS): slip under the traction law, near its true limit."""
    from gap_support import indep_named

    c, rep = indep_named(2791, 51, tmp_path, "labmate", {"slip": "traction"}, "slip", "traction")
    assert rep["proposals"] == {}
    a = rep["verdict"]["params"]["slip@traction.a_max_m_s2"]
    assert a == pytest.approx(c["true"]["effects"]["slip"]["a_lim_m_s2"], rel=0.05)
    h = rep["heldout"]
    assert h["ratio_after"] < 0.25 * h["ratio_before"]


def test_traction_limit_is_started_below_the_runs_demand(tmp_path: Path) -> None:
    """Independent world, seed 2981 case 24 (traced after that seed was measured): a LabMate
    whose floor speed changes at most 0.74 m/s^2, while its counts never ask the centre for more
    than 1.9 m/s^2. The traction law started at its catalog 2 m/s^2, where the limit touched no
    tick: no gradient, and from the return errors alone the slip went "unexplained" at 21 x the
    background with Ed's growth law best. Started below the hardest demand the counts show
    (fit.GRIP_LIMITS, as the friction circle's skid), the return errors name slip under the
    traction law."""
    from odo_tools.gap.diagnose import diagnose, load
    from odo_tools.gap.model import accel_demand

    real = tmp_path / "real"
    c = indep_case(2981, 24, real, "labmate", {"slip": "traction"})
    ds = load(real, real / "robot.json", "returns")
    assert accel_demand(ds.prs, 100.0) < 2.0  # the catalog start sat above every demand
    rep = diagnose(real, real / "robot.json", mode="returns").to_dict()
    v = rep["verdict"]
    assert (v["effect"], v["best_hypothesis"]) == ("slip", "slip@traction")
    h = rep["heldout"]
    assert h["ratio_after"] < 0.25 * h["ratio_before"]
    a = v["params"]["slip@traction.a_max_m_s2"]
    assert a == pytest.approx(c["true"]["effects"]["slip"]["a_lim_m_s2"], rel=0.25)


def test_accel_slip_is_named_from_return_errors(tmp_path: Path) -> None:
    """Independent world, dev seed 4021 case 26: a LabMate (b 800 mm, 100 ms cycle) whose tyres
    slip by a power (1.87) of their acceleration. From its return errors alone the catalog's and
    the traction laws closed none of the squares' gap, an Eb half of it with a circle 40 mm off
    ("unexplained" at 7.9 x the spread of repeated runs). The acceleration law is tried in
    returns mode too, and names it."""
    indep_named(4021, 26, tmp_path, "labmate", {"slip": "accel"}, "slip", "accel", "returns")


def test_a_slip_the_windows_cannot_size_is_fitted_on_the_tracks(tmp_path: Path) -> None:
    """Independent world, dev seed 4501 case 9: a LabMate whose tyres slip k 0.031 at 1 m/s^2
    (power 1.57, the left one 1.7 x the right) under a motion capture whose heading is noisy
    (0.26 deg). The windows' best was a slip, below the nominal by BIC; the tracks, to which
    only geometry was fitted, stayed at 2.5 x the background, and the held-out runs at 2.84 x
    whatever was fitted: "unexplained". The slip's laws fitted to the accumulated tracks take
    them to 1.3 x, and the acceleration law, its asymmetry the world's, closes the held-out
    runs."""
    c, rep = indep_named(4501, 9, tmp_path, "labmate", {"slip": "accel"}, "slip", "accel")
    assert rep["verdict"]["evidence"]["heldout_ratio_after"] <= 1.2, rep["verdict"]["evidence"]
    asym = rep["verdict"]["params"]["slip@accel.asym"]
    assert asym == pytest.approx(c["true"]["effects"]["slip"]["asym"], abs=0.1)
