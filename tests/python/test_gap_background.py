"""What the diagnosis measures before it judges (issue 13 item 2): the floor's heading walk and the
truth's noise (the background a verdict is judged against), the truth's instrument nuisances
(latency, lever arm of the tracked point), and the verdict rule read on held-out misfit ratios."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from gap_support import BUILD, SRC, each_run_its_own_latency, indep_case, odo_sim


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


@pytest.mark.parametrize("q_wheel", [0.0, 3e-3])
def test_walk_is_recovered_under_white_sample_noise(q_wheel: float) -> None:
    """Window residuals of a heading that random-walks q_wheel / b^2 per mm of wheel travel,
    seen through a truth with 3e-3 rad of white noise per sample (the OptiOdom robot's size), 16
    runs of 2 minutes: the multi-scale estimate finds q_wheel within 30 % (its scatter over seeds
    is ~20 %), and next to nothing where there is none."""
    from odo_tools.gap.background import walk

    rng = np.random.default_rng(3)
    b, sigma = 200.0, 3e-3
    runs = []
    for _ in range(16):
        E = rng.uniform(30.0, 120.0, 300)  # wheel travel per 0.4 s window (mm)
        w = np.concatenate([[0.0], np.cumsum(rng.normal(0, np.sqrt(q_wheel * E) / b))])
        n = rng.normal(0, sigma, w.size)  # the truth's sample noise at the window ends
        runs.append((np.diff(w + n), E))
    q = walk(runs, b)
    if q_wheel == 0:
        assert q < 3e-4
    else:
        assert q == pytest.approx(q_wheel, rel=0.3)


def test_latency_and_lever_arm_of_the_truth_are_estimated(tmp_path: Path) -> None:
    """The simulator's exact truth, re-stamped 120 ms late and tracked at a marker 25 mm ahead of
    and 10 mm left of the axle centre: both are found, and the marker's turns on the spot no
    longer reach the residual."""
    from odo_tools.gap import instrument
    from odo_tools.gap.io import discover, read_robot
    from odo_tools.gap.model import prepare

    real = tmp_path / "real"
    odo_sim("none.json", real, runs=1)
    lat, ox, oy = 0.12, 25.0, 10.0
    for p in real.glob("*.truth.csv"):
        lines = p.read_text().splitlines()
        out = [lines[0]]
        for ln in lines[1:]:
            f = ln.split(",")
            t, x, y, th = (float(v) for v in f[:4])
            c, s = math.cos(math.radians(th)), math.sin(math.radians(th))
            f[0] = f"{t + lat:.3f}"
            f[1] = f"{x + c * ox - s * oy:.4f}"
            f[2] = f"{y + s * ox + c * oy:.4f}"
            out.append(",".join(f))
        p.write_text("\n".join(out) + "\n")
    robot = read_robot(SRC / "host_sim/robots/labmate.json")
    prs = [prepare(r, robot) for r in discover(real, robot)]
    inst, notes = instrument.estimate(prs, 1)
    assert not notes
    for L in inst.latency_s.values():
        assert L == pytest.approx(lat, abs=0.005)
    assert inst.lever_mm[0] == pytest.approx((ox, oy), abs=0.5)
    # no latency and no lever arm where there is none
    shutil.rmtree(real)
    odo_sim("none.json", real, runs=1)
    prs = [prepare(r, robot) for r in discover(real, robot)]
    inst, _ = instrument.estimate(prs, 1)
    assert all(L == 0.0 for L in inst.latency_s.values())
    assert inst.lever_mm[0] == (0.0, 0.0)


def _rewrite_truth(real: Path, heading_deg: float, ox: float = 0.0, oy: float = 0.0) -> None:
    """Marker ox, oy off the axle centre and its body's heading heading_deg off the truck's."""
    for p in real.glob("*.truth.csv"):
        lines = p.read_text().splitlines()
        out = [lines[0]]
        for ln in lines[1:]:
            f = ln.split(",")
            x, y, th = (float(v) for v in f[1:4])
            c, s = math.cos(math.radians(th)), math.sin(math.radians(th))
            f[1] = f"{x + c * ox - s * oy:.4f}"
            f[2] = f"{y + s * ox + c * oy:.4f}"
            f[3] = f"{th + heading_deg:.6f}"
            out.append(",".join(f))
        p.write_text("\n".join(out) + "\n")


def test_heading_offset_of_the_truth_is_estimated(tmp_path: Path) -> None:
    """A marker body whose heading is 0.3 deg off the truck's (the independent world draws up to
    +-0.3 deg): found from the chords of straight windows, taken off the measured heading, and
    the nominal model's windows lose the lateral misfit it made (every increment turned off the
    body axes); none where there is none. Without it, the fits took the offset for skid or
    scrub and made held-out runs worse."""
    from odo_tools.gap import instrument
    from odo_tools.gap.io import discover, read_robot
    from odo_tools.gap.model import prepare
    from odo_tools.gap.modes import TruthMode

    robot = read_robot(SRC / "host_sim/robots/labmate.json")
    real = tmp_path / "real"
    odo_sim("none.json", real, runs=2)
    prs = [prepare(r, robot) for r in discover(real, robot)]
    inst, _ = instrument.estimate(prs, 1)
    assert inst.heading_offset_rad[0] == 0.0
    # an Ed bends every straight the counts call straight while the robot speeds up along it:
    # the chord follows the heading's mean over distance, not over time (which read 3e-5 rad
    # here, 40 of its standard errors, and 0.05-0.13 deg on the simulator's clappers and sets,
    # where a fake rotary bias then joined the Ed)
    shutil.rmtree(real)
    odo_sim("effect-ed.json", real, runs=2)
    prs = [prepare(r, robot) for r in discover(real, robot)]
    inst, _ = instrument.estimate(prs, 1)
    assert inst.heading_offset_rad[0] == 0.0
    shutil.rmtree(real)
    odo_sim("none.json", real, runs=2)
    _rewrite_truth(real, 0.3, 20.0, -8.0)
    prs = [prepare(r, robot) for r in discover(real, robot)]
    inst, _ = instrument.estimate(prs, 1)
    assert math.degrees(inst.heading_offset_rad[0]) == pytest.approx(0.3, abs=0.01)
    assert inst.lever_mm[0] == pytest.approx((20.0, -8.0), abs=0.5)
    blind = inst.copy()
    blind.heading_offset_rad = [0.0]
    for pr in prs:
        lat = [
            np.sqrt(np.mean(TruthMode(pr, robot, x).residuals({})[:, 1] ** 2))
            for x in (inst, blind)
        ]
        assert lat[0] < 0.2 * lat[1]


@pytest.mark.parametrize(
    ("r0", "r1", "dbic", "expect"),
    [
        (1.3, 1.0, 3.0, "no significant gap"),  # within the background, no evidence
        (2.1, 1.0, 50.0, "ed"),  # small but clear on the held-out runs, closed
        (1.6, 1.0, 500.0, "no significant gap"),  # the fitting runs' Delta BIC alone: no gap
        (30.0, 1.2, 500.0, "ed"),  # large, closed to the background
        (30.0, 4.0, 500.0, "ed"),  # large, 98 % of the excess removed
        (3.0, 2.4, 500.0, "unexplained"),  # clearly there, not closed
    ],
)
def test_verdict_reads_the_held_out_misfit_against_the_background(r0, r1, dbic, expect) -> None:
    """A small effect is named when it closes the gap to the background, however small the
    nominal misfit was (the relative rule vetoed it); a gap no hypothesis closes is unexplained."""
    from odo_tools.gap.heldout import HeldOut
    from odo_tools.gap.verdict import decide

    h = HeldOut([], [], [], [], [], ratio_before=r0, ratio_after=r1)
    assert decide(h, dbic, "ed")[0] == expect


@pytest.mark.parametrize(
    ("r0", "r1", "dbic", "weak", "dof", "track", "expect"),
    [
        (1.97, 0.93, 1670.0, True, None, None, "ed"),  # dev 2801 case 22: both sides agree
        (1.97, 0.93, 1670.0, False, None, None, "no significant gap"),  # returns, linkage
        (1.97, 0.93, 60.0, True, None, None, "no significant gap"),  # the fitting runs barely
        (1.8, 1.45, 500.0, True, None, None, "no significant gap"),  # removes 52 %: not closed
        (1.45, 1.0, 500.0, True, None, None, "no significant gap"),  # below 1.5 x: background
        (1.9, 1.0, 500.0, True, 3.0, None, "no significant gap"),  # a few runs' spread: F's
        # the fitting runs' tracks agree instead of their Delta BIC (dev 2821 case 55)
        (1.86, 0.94, 68.0, True, None, 1.85, "ed"),
        (1.86, 0.94, 68.0, True, None, 1.2, "no significant gap"),  # the tracks see no gap
        # both sides see the gap and nothing closes it (dev 2821 case 14, a gear backlash)
        (1.87, 1.93, -2.0, True, None, 2.04, "unexplained"),
        (1.78, 6.29, 17.0, True, None, 0.81, "no significant gap"),  # dev 2831 case 20: none
        (1.87, 1.93, -2.0, False, None, 2.04, "no significant gap"),  # returns, linkage
        (1.45, 1.45, -2.0, True, None, 2.04, "no significant gap"),  # held out: background
    ],
)
def test_a_gap_below_twice_the_background_is_named_where_both_sides_agree(
    r0, r1, dbic, weak, dof, track, expect
) -> None:
    """Truth mode judges a gap of 1.5-2 x the background by what the fitting runs say: named
    when they want the candidate by Delta BIC >= 100 or their own nominal tracks sit at >= 1.5 x,
    and it removes >= 75 % of the held-out excess; "unexplained" when the tracks see the gap and
    the candidate does not close it; else no significant gap."""
    from odo_tools.gap.heldout import HeldOut, RunGap
    from odo_tools.gap.verdict import decide

    runs = [RunGap("a", 0, 0, 0, 3), RunGap("b", 0, 0, 0, 3)]
    h = HeldOut([], runs, runs, [], [], ratio_before=r0, ratio_after=r1)
    if dof is not None:
        h.extra["noise_dof"] = dof
    verdict, reason = decide(h, dbic, "ed", weak_gap=weak, fit_track=track)
    assert verdict == expect, reason


@pytest.mark.parametrize(
    ("r0", "r1", "dof", "expect"),
    [
        (4.0, 1.0, 3.0, "no significant gap"),  # 6 values against a 3-dof spread: F's 99 % is 28
        (4.0, 1.0, 300.0, "ed"),  # the same misfit against a well-measured background
        (40.0, 3.0, 3.0, "ed"),  # far beyond, and closed
        (4.0, 1.0, 0.0, "no significant gap"),  # no spread measured at all: no test
    ],
)
def test_a_background_from_few_runs_raises_the_gap_threshold(r0, r1, dof, expect) -> None:
    """Returns without a stated accuracy: the background is the spread of 2-3 runs per path, so
    a no-effect robot's held-out R^2 follows F(n, dof), far beyond 4 at the 99 % point; the
    returns mode's 4 of 6 false alarms on the independent world (seed 2611) sat there."""
    from odo_tools.gap.heldout import HeldOut, RunGap
    from odo_tools.gap.verdict import decide

    runs = [RunGap("a", 0, 0, 0, 3), RunGap("b", 0, 0, 0, 3)]
    h = HeldOut([], runs, runs, [], [], ratio_before=r0, ratio_after=r1)
    h.extra["noise_dof"] = dof
    assert decide(h, 500.0, "ed")[0] == expect


def test_returns_spread_pools_paths_and_counts_its_degrees_of_freedom() -> None:
    """The spread about each path's mean, x and y pooled, with 1.5 m dof (m = runs - paths);
    a path driven once adds nothing. Recovered on Gaussian returns of known sigma."""
    from types import SimpleNamespace

    from odo_tools.gap.fit import returns_spread

    rng = np.random.default_rng(3)
    sig = np.array([2.0, 2.0, 0.003])
    items = []
    for k in range(200):  # 200 paths of 3 runs, each path with its own systematic error
        mean = rng.normal(0, 50, 3)
        for _ in range(3):
            r = (mean + rng.normal(0, 1, 3) * sig)[None, :]
            items.append(
                SimpleNamespace(pr=SimpleNamespace(path=f"p{k}"), residuals=lambda P, r=r: r)
            )
    items.append(
        SimpleNamespace(pr=SimpleNamespace(path="once"), residuals=lambda P: np.full((1, 3), 99.0))
    )
    s, dof = returns_spread(items)
    assert dof == 1.5 * 400
    assert s == pytest.approx(sig, rel=0.08)


def test_start_heading_spreads_an_open_paths_return_by_its_reach() -> None:
    """A start placed off by a heading d ~ N(0, s) turns the whole run about its start point:
    returns of a path ending at (9 m, -6 m), simulated with 20 000 placements, spread by what
    ReturnsMode.own_var says, per axis; a closed path's return (at its start) not at all."""
    from types import SimpleNamespace

    from odo_tools.gap.modes import ReturnsMode

    rng = np.random.default_rng(5)
    s = 0.002
    sigma = np.array([1.0, 1.0, s])
    for end in ((9000.0, -6000.0), (0.0, 0.0)):
        ret = np.array([end[0], end[1], 0.3])
        mode = ReturnsMode(SimpleNamespace(run=SimpleNamespace(ret=ret)), None)
        d = rng.normal(0.0, s, 20000)
        x = np.cos(d) * end[0] - np.sin(d) * end[1]
        y = np.sin(d) * end[0] + np.cos(d) * end[1]
        v = mode.own_var(sigma)[0]
        assert v[2] == 0.0
        assert math.sqrt(v[0]) == pytest.approx(np.std(x), rel=0.03, abs=1e-9)
        assert math.sqrt(v[1]) == pytest.approx(np.std(y), rel=0.03, abs=1e-9)


def test_a_long_open_run_without_effect_is_no_gap_in_returns_mode(tmp_path: Path) -> None:
    """Independent world, seed 2691 case 43: a LabMate with no effect whose one 'drive' run ends
    11 m from its start 24 mm off the nominal model, 0.13 deg of start heading over that reach,
    while its squares' returns spread by 1 mm. Judged against the squares' spread alone it was
    "unexplained"; with the start heading's reach it is no gap."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(2691, 43, real, "labmate", {})
    from odo_tools.gap.report import _remainder

    rep = diagnose(real, real / "robot.json", mode="returns").to_dict()
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]
    # the report says where the allowance came from: the drive's reach, not the squares' spread
    assert "over the reach" in _remainder(rep) and "run-drive-01" in _remainder(rep)


def test_walk_of_single_run_paths_is_measured_against_the_held_out_runs(tmp_path: Path) -> None:
    """Fitting runs that each drove a path of their own cannot tell a walk from what repeats:
    the whole residual left under the candidate was taken for the floor's walk, and the allowance
    vetoed the effect (the independent world's skid law, which the catalog's only approximates,
    seed 9 case 5: a 34 mm allowance on a floor that walks 100 times less). The held-out runs of
    the same paths give what does not repeat: here a heading misfit of 0.5 deg with a 3 s period,
    the same on every run of a path, is a walk only without them."""
    from odo_tools.gap.background import measure
    from odo_tools.gap.fit import estimate_sigma
    from odo_tools.gap.io import discover, read_robot
    from odo_tools.gap.model import prepare
    from odo_tools.gap.modes import TruthMode
    from odo_tools.gap.paths import assign_paths

    robot = read_robot(SRC / "host_sim/robots/labmate.json")
    real = tmp_path / "real"
    odo_sim("none.json", real, runs=2)
    for p in real.glob("*.truth.csv"):
        lines = p.read_text().splitlines()
        out = [lines[0]]
        for ln in lines[1:]:
            f = ln.split(",")
            f[3] = f"{float(f[3]) + 0.5 * math.sin(2 * math.pi * float(f[0]) / 3.0):.6f}"
            out.append(",".join(f))
        p.write_text("\n".join(out) + "\n")
    prs = [prepare(r, robot) for r in discover(real, robot)]
    assign_paths(prs)
    items = [TruthMode(pr, robot) for pr in prs]
    fit, held = [], []
    for it in items:
        (held if any(f.pr.path == it.pr.path for f in fit) else fit).append(it)
    assert len(fit) == 2 and len(held) == 2
    sigma = estimate_sigma(fit, "truth")
    alone = measure(fit, sigma, "truth", {})
    pooled = measure(fit, sigma, "truth", {}, pool=held)
    assert alone.q_wheel[0] > 1e-4
    assert pooled.q_wheel[0] < 0.01 * alone.q_wheel[0], (alone.q_wheel, pooled.q_wheel)


@pytest.fixture(scope="module")
def noisy_eb(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """The independent world's seed 2681 case 26 (traced after that seed was measured): a
    LabMate with an Eb of 0.9953 whose motion capture carries 0.28 deg of heading noise per
    sample at 200 Hz."""
    real = tmp_path_factory.mktemp("noisy") / "real"
    c = indep_case(2681, 26, real, "labmate", {"eb": "load_patch"})
    return real, c["true"]["effects"]["eb"]["value0"]


def test_heavy_truth_noise_is_not_read_as_a_walk(noisy_eb, monkeypatch) -> None:
    """Under the true Eb the runs have next to no walk. Read from each window's two end
    samples, the truth's noise came out as 0.28 deg per 90 deg spot turn, an allowance of
    36 mm beside the 3 mm the Eb leaves on the held-out runs; from the windows' mean headings,
    less what the noise alone reads through the estimator, it is a fifth of that."""
    from odo_tools.gap import background as B
    from odo_tools.gap import diagnose as D

    real, eb = noisy_eb
    ds = D.load(real, real / "robot.json")
    sel = D.select_runs(ds)
    fit = [ds.items[i] for i in sel.fit]
    pool = [ds.items[i] for i in sel.held if i not in sel.fit]
    b = fit[0].pr.b[0]
    P = {"eb.value": eb}
    now = B.measure(fit, None, "truth", P, pool=pool)
    monkeypatch.setattr(B, "heading_means", lambda it, P, t: it.residuals(P)[:, 3 * t + 2])
    monkeypatch.setattr(B, "noise_walk", lambda *a: (0.0, 0.0))
    ends = B.measure(fit, None, "truth", P, pool=pool)
    assert B.spot_turn_deg(ends.q_turn[0], b) > 0.15
    assert B.spot_turn_deg(now.q_turn[0], b) < 0.2 * B.spot_turn_deg(ends.q_turn[0], b)
    assert B.heading_walk_deg_per_sqrt_m(now.q_wheel[0], b) < 0.05


def test_an_eb_under_heavy_truth_noise_is_named(noisy_eb) -> None:
    from odo_tools.gap import diagnose as D

    real, eb = noisy_eb
    v = D.diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] == "eb", v
    assert abs(v["params"]["eb.value"] - eb) < 0.2 * abs(eb - 1.0), (v["params"], eb)


def test_noise_alone_reads_as_a_walk_through_the_estimator(monkeypatch: pytest.MonkeyPatch) -> None:
    """What `noise_walk` takes off is there: white noise alone, through `unrepeated` and
    `walk_by_phase`, reads as a walk (its slopes are kept >= 0), and the larger the noise the
    larger the reading."""
    from odo_tools.gap.background import noise_walk

    class Item:
        def __init__(self, n: int, rng: np.random.Generator) -> None:
            self.i = np.arange(n)
            self.j = self.i + 40  # 40 truth samples per window
            E = rng.uniform(20.0, 80.0, (1, 2, n))
            self.wtravel = E
            self.wturn = np.where(np.arange(n) % 10 < 3, E.sum(axis=1)[0], 0.0)[None, :]
            self.pr = type("Pr", (), {"path": "p", "run": None})()

    rng = np.random.default_rng(2)
    items = [Item(400, rng) for _ in range(4)]
    from odo_tools.gap import paths

    monkeypatch.setattr(paths, "group_key", lambda pr: "p")  # one path, four runs
    small = noise_walk(items, 0, math.radians(0.05), 200.0, 1)
    large = noise_walk(items, 0, math.radians(0.5), 200.0, 1)
    assert sum(large) > 0
    assert sum(large) > 50 * sum(small)


def test_the_model_track_between_ticks_follows_an_acceleration() -> None:
    """The model is known at its count ticks; a truth sampled between them is compared with the
    track there. Through a turn's start at 4.7 rad/s^2 on 100 ms ticks a straight line between
    ticks misses by alpha T^2 / 8 (0.34 deg); the cubic through the ticks follows a constant
    acceleration exactly, and returns the ticks' own values at the ticks."""
    from odo_tools.gap.model import track_at

    alpha, T = 4.7, 0.1
    t = np.arange(0.0, 2.0 + 1e-9, T)
    th = 0.5 * alpha * t * t
    tq = np.arange(0.3, 1.7, 0.005)
    exact = 0.5 * alpha * tq * tq
    lin = np.max(np.abs(np.interp(tq, t, th) - exact))
    assert lin == pytest.approx(alpha * T * T / 8, rel=1e-6)
    assert np.max(np.abs(track_at(tq, t, th) - exact)) < 1e-9
    assert np.array_equal(track_at(t, t, th), th)
    assert track_at(-1.0, t, th) == th[0] and track_at(9.0, t, th) == th[-1]


def test_a_walk_along_the_track_alone_still_spreads_the_track(tmp_path: Path) -> None:
    """A floor that takes travel without turning the truck (longitudinal walk q_long, heading
    walk 0) moves it along its heading: its track allowance at a window start is q_long x the
    travel so far, in x and y together, none in heading. It was zero wherever the heading walk
    was (the independent world's trailer on grains: 1-1.5 mm lost along 15 m, judged against
    the truth's 0.3 mm alone, dev seed 2701 case 30 at 2.2 x the background)."""
    from odo_tools.gap.background import Background
    from odo_tools.gap.io import discover, read_robot
    from odo_tools.gap.model import prepare
    from odo_tools.gap.modes import TruthMode

    robot = read_robot(SRC / "host_sim/robots/labmate.json")
    real = tmp_path / "real"
    odo_sim("none.json", real, runs=1)
    pr = prepare(discover(real, robot)[0], robot)
    item = TruthMode(pr, robot)
    ql = 2e-4
    bg = Background("truth", q_wheel=[0.0], q_turn=[0.0], q_long=[ql])
    v = bg.track_var(item, 0) - bg.count_var(item, 0)  # the counts' own share aside
    travel = np.concatenate([[0.0], np.cumsum(np.abs(pr.ds[:, 0, :]).sum(axis=1))])
    want = ql * np.interp(item.tt[item.i], pr.t, travel)
    assert want[-1] > 1.0  # mm^2: the run drives metres
    assert np.all(np.abs(v[:, 2]) < 1e-15)
    np.testing.assert_allclose(v[:, 0] + v[:, 1], want, rtol=0.05, atol=ql * 50.0)


def test_the_track_allowance_kept_per_run_follows_the_walk_and_the_floor_bumps(
    tmp_path: Path,
) -> None:
    """Background.track_var is kept per run and truck (a track fit asks for it at every step,
    and no parameter it moves acts on it), but it is computed again when what it reads changes:
    the walk, or the floor bumps placed on the run (the nominal track crosses them). Each answer
    is a fresh Background's, and is read-only, since every caller shares it."""
    from odo_tools.gap.background import Background
    from odo_tools.gap.io import discover, read_robot
    from odo_tools.gap.model import prepare
    from odo_tools.gap.modes import TruthMode

    robot = read_robot(SRC / "host_sim/robots/labmate.json")
    real = tmp_path / "real"
    odo_sim("none.json", real, runs=1)
    pr = prepare(discover(real, robot)[0], robot)
    item = TruthMode(pr, robot)
    bg = Background("truth", q_wheel=[3e-3], q_turn=[1e-3])
    v = bg.track_var(item, 0)
    assert bg.track_var(item, 0) is v  # kept
    assert not v.flags.writeable
    assert np.array_equal(v, Background("truth", q_wheel=[3e-3], q_turn=[1e-3]).track_var(item, 0))
    bg.q_wheel = [6e-3]
    w = bg.track_var(item, 0)
    assert np.array_equal(w, Background("truth", q_wheel=[6e-3], q_turn=[1e-3]).track_var(item, 0))
    assert not np.array_equal(w, v)
    pr.bumps.append({"truck": 0, "wheel": 0, "s0": 0.3 * pr.S[-1, 0, 0], "h": 20.0})
    try:
        u = bg.track_var(item, 0)
        fresh = Background("truth", q_wheel=[6e-3], q_turn=[1e-3]).track_var(item, 0)
    finally:
        pr.bumps.clear()
    assert np.array_equal(u, fresh)
    assert not np.array_equal(u, w)  # the bump turned the track: the cache must not serve w
    assert bg.track_var(item, 0) is w


def _runs(lat: list[float], tick: float = 0.04):
    from types import SimpleNamespace

    return [
        SimpleNamespace(run=SimpleNamespace(name=f"r{k}", session="s"), dt=np.full(10, tick))
        for k in range(len(lat))
    ], {f"r{k}": v for k, v in enumerate(lat)}


def test_one_run_off_the_clock_does_not_take_the_session_clock_away() -> None:
    """Ten runs at 21-27 ms and an eight at 41 ms on 40 ms ticks (the independent world's set
    with an Es, seed 2681 case 1): the session runs on one clock; the eight takes it, the
    others keep their own. Before, the spread of all eleven zeroed every latency (all below
    1.5 ticks), and a 30 ms clock went unmodelled."""
    from odo_tools.gap.instrument import one_clock, session_latencies

    lat = [0.0233, 0.0268, 0.0245, 0.0224, 0.0256, 0.0247, 0.025, 0.0244, 0.0212, 0.022, 0.041]
    prs, found = _runs(lat)
    out = session_latencies(prs, found)
    assert one_clock(prs, out) == {"s": True}
    assert [out[f"r{k}"] for k in range(10)] == lat[:10]
    assert out["r10"] == pytest.approx(float(np.median(lat[:10])))


def test_a_session_whose_runs_disagree_keeps_only_long_latencies() -> None:
    """Four of ten runs off the median (slip read as latency varies with each path's
    accelerations): no one clock; the shifts shorter than 1.5 ticks go, a long one stays. They
    go to the clock the scan under slip chose, where it chose one (`unfixed`), else to none."""
    from odo_tools.gap.instrument import one_clock, session_latencies

    lat = [0.012, 0.012, 0.013, 0.011, 0.012, 0.012, 0.025, 0.026, 0.024, 0.070]
    prs, found = _runs(lat)
    assert one_clock(prs, found) == {"s": False}
    out = session_latencies(prs, found)
    assert [out[f"r{k}"] for k in range(9)] == [0.0] * 9
    assert out["r9"] == 0.070
    out = session_latencies(prs, found, 0.03)
    assert [out[f"r{k}"] for k in range(9)] == [0.03] * 9
    assert out["r9"] == 0.070


def _own_clock(prs, off_s: float) -> None:
    """Give the fake runs a truth sampled `off_s` after each count tick (0: at the ticks)."""
    from types import SimpleNamespace

    for pr in prs:
        pr.t = np.arange(10) * pr.dt[0]
        pr.run.truth = SimpleNamespace(t_s=pr.t[:-1] + off_s)


def test_a_truth_on_its_own_clock_keeps_the_runs_median_where_they_disagree() -> None:
    """The independent world's dev seed 4071 case 19, a LabMate with no effect whose motion
    capture ran 14 ms late on 25 ms ticks: its runs read 9.5-24 ms, no one clock. Set to none,
    slip took the lateness and the diagnosis called the robot "unexplained". A truth on its
    own clock takes the runs' median instead; one taken at the ticks keeps none, and a clock
    the scan under slip chose still wins."""
    from odo_tools.gap.instrument import one_clock, session_latencies

    lat = [0.0099, 0.0117, None, 0.0196, 0.0095, 0.0239, None]
    prs, found = _runs(lat, tick=0.025)
    assert one_clock(prs, {k: v for k, v in found.items() if v is not None}) == {"s": False}
    _own_clock(prs, 0.0)
    assert set(session_latencies(prs, found).values()) == {0.0}
    _own_clock(prs, 0.004)
    assert list(session_latencies(prs, found).values()) == pytest.approx([0.0117] * 7)
    assert set(session_latencies(prs, found, 0.015).values()) == {0.015}


def test_a_late_motion_capture_is_no_gap_on_a_robot_with_none(tmp_path: Path) -> None:
    """The same case diagnosed: each run keeps the median read, the scan under slip finds a
    clock of 15 ms (the truth's 14 ms), and the robot with no effect has no significant gap."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    c = indep_case(4071, 19, real, "labmate", {})
    assert c["fidelity"]["truth_latency_s"] == pytest.approx(0.014, abs=5e-4)
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]
    lat = rep["instrument"]["latency_s"]
    assert all(abs(v - 0.014) < 0.004 for v in lat.values()), lat


def test_a_weak_gap_both_sides_see_and_nothing_closes_is_unexplained(tmp_path: Path) -> None:
    """The independent world's dev seed 2821 case 14: a LabMate with gear backlash (out of the
    catalog). Its held-out runs sit at 1.5-2 x the background, its fitting runs' nominal tracks
    beyond 1.5 x as well, and no candidate closes the gap: "unexplained" (it was "no
    significant gap", read from the held-out runs alone)."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(2821, 14, real, "labmate", {"gear_backlash": "play"})
    v = diagnose(real, real / "robot.json", mode="truth")["verdict"]
    ev = v["evidence"]
    assert v["effect"] == "unexplained", v["reason"]
    assert 1.5 <= ev["heldout_ratio_before"] < 2.0, ev
    assert ev["fit_track_ratio_nominal"] >= 1.5, ev
    assert ev["heldout_ratio_after"] > 1.5, ev


def test_a_sets_weak_gap_is_not_judged_by_its_fitting_tracks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The independent world's seed 2971 case 58: a set (a robot towing an encoder trailer)
    with no effect, its held-out runs at 1.5-2 x the background. A set's trailer is dragged,
    and four such sets became false alarms under the fitting-track rule (verdict.py); it is
    asked only where every truck is driven. (Seed 2711 case 56, the case this test first used,
    sat at 1.44 x once the longitudinal walk joined the track allowance; dev seed 2751 case 57,
    the next, at 1.42 x once the counts' own resolution did, background.counting_error.) Its
    truth runs 12.3 ms late, which no run fixes alone; read from the runs together
    (instrument.run_latencies) it sits at 1.23 x, so the rule is asked with each run's own
    latency, as it was."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(2971, 58, real, "set", {})
    v = diagnose(real, real / "robot.json", mode="truth")["verdict"]
    assert v["evidence"]["heldout_ratio_before"] < 1.5, v["evidence"]
    assert v["effect"] == "no significant gap", v["reason"]
    each_run_its_own_latency(monkeypatch)
    v = diagnose(real, real / "robot.json", mode="truth")["verdict"]
    assert 1.5 <= v["evidence"]["heldout_ratio_before"] < 2.0, v["evidence"]
    assert v["evidence"]["fit_track_ratio_nominal"] is None
    assert v["effect"] == "no significant gap", v["reason"]


def _quiet_labmate(real: Path, seed: int = 4071, case: int = 59) -> dict:
    """A LabMate of the independent world with its effects removed, quieted: a perfect floor,
    perfect sensors. Dev seed 4071 case 59 has no effect and 5-line encoders (one count is 0.89
    mrad of heading); 4061/37 (7 lines, 5.4 mm a count) drew a pair of effects, taken away."""
    from odo_tools.validation import case_seed, indep
    from odo_tools.validation.indep import cases

    rng = np.random.default_rng(seed)
    c = [indep.draw_case(rng, i) for i in range(case + 1)][case]
    assert c["vehicle"] == "labmate", "the world moved: pick another"
    c = cases.quiet(c)
    c["true"]["effects"] = {}
    indep.simulate_case(c, real, case_seed(seed, case))
    return c


def test_counting_alone_is_no_gap_on_a_perfect_robot_with_coarse_encoders(tmp_path: Path) -> None:
    """Counting is the only error left on the quieted LabMate: the heading the model takes from
    two counters is off by the difference of the wheels' unread fractions, held along each
    straight. Without the counting term (background.counting_error) its held-out runs sat at
    3.4 x a 0.15 mm background, "unexplained"; the allowance now carries it."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    _quiet_labmate(real)
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["background"]["count_heading_mrad"] == pytest.approx([0.885], abs=0.005)
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]["reason"]
    assert rep["heldout"]["ratio_before"] < 1.5, rep["heldout"]["ratio_before"]
    assert rep["background"]["heldout_allowance_mm"] > 2 * rep["gap_before_mm"] / 3


def test_a_window_carries_its_counts_unread_fractions(tmp_path: Path) -> None:
    """On a perfect LabMate with coarse counts (4061/37 quieted: 5.4 mm a count) what a fitting
    window's body increment misses is counting alone, and TruthMode.own_var says how much: the
    moving windows' mean square residual per channel is within 0.5-2.5 x of it (the robot's own
    loop dithers its wheels about a count, which the draw does not know). Without it the fit
    took the truth's robust noise (0.02 mm) as the windows' spread, and slip, which moves
    exactly the windows where the fractions change, won by Delta BIC 87,000 on this robot."""
    from odo_tools.gap import diagnose as D

    real = tmp_path / "real"
    _quiet_labmate(real, 4061, 37)
    ds = D.load(real, real / "robot.json", "truth")
    moving = np.concatenate([~it.stationary() for it in ds.items])
    r = np.vstack([it.residuals({}) for it in ds.items])[moving]
    v = np.vstack([it.own_var(None) for it in ds.items])[moving]
    ratio = np.mean(r * r, axis=0) / np.mean(v, axis=0)
    assert np.all((ratio > 0.5) & (ratio < 2.5)), ratio
    rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]["reason"]
    assert rep["verdict"]["evidence"]["dbic_vs_nominal"] < 1000


def test_the_counting_allowance_grows_along_a_straight_and_with_the_count(tmp_path: Path) -> None:
    """On the quieted LabMate's squares the counting allowance is nil where the anchor holds the
    track (the first seconds), grows along the straights, and shrinks with the count: 100 x
    finer counters leave 100 x less (the same fractions drawn, the travel per count scaled)."""
    from odo_tools.gap import diagnose as D
    from odo_tools.gap.background import counting_error

    real = tmp_path / "real"
    _quiet_labmate(real)
    ds = D.load(real, real / "robot.json", "truth")
    it = next(x for x in ds.items if x.pr.run.name.startswith("run-cw"))
    v = counting_error(it, 0)
    sd = np.sqrt(v[:, 0] + v[:, 1])
    t = it.tt[it.i] - it.tt[0]
    assert sd[t < 1.0].max() < 0.1 * sd.max()
    assert 0.5 < sd.max() < 5.0, sd.max()  # mm: 0.4 count's heading over ~5 m of straight
    it.pr.count_mm = [it.pr.count_mm[0] / 100.0]
    fine = np.sqrt(counting_error(it, 0)[:, :2].sum(axis=1))
    assert fine.max() < 0.05 * sd.max(), (fine.max(), sd.max())
