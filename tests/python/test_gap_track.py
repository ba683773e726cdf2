"""odo-gap's truth mode fits the robot's geometry to the accumulated track where the 0.4 s windows
cannot see it (diagnose._track_refit, issue 13 item 2: verdicts on what the held-out runs show).

The case is the independent world's dev seed 8 case 12: a LabMate with an Ed of 0.37 % (fixed law)
whose motion capture is noisy per sample (0.8 mm, 0.13 deg at 180 Hz). Per window the Ed is buried
in that noise; along a square it leaves ~8 mm against a ~1 mm background."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from gap_support import each_run_its_own_latency, indep_case, indep_named
from odo_tools.gap import diagnose as D
from odo_tools.gap import hypotheses
from odo_tools.gap.fit import Problem
from odo_tools.validation import indep


@pytest.fixture(scope="module")
def case(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    rng = np.random.default_rng(8)
    c = [indep.draw_case(rng, k) for k in range(13)][12]
    assert c["vehicle"] == "labmate" and c["laws"] == {"ed": "fixed"}, (
        "the independent world's seed 8 case 12 changed; pick another small-Ed LabMate"
    )
    real = tmp_path_factory.mktemp("track") / "real"
    indep.simulate_case(c, real, 8 * 1_000_003 + 12)
    return real, c["true"]["effects"]["ed"]["value"]


def _ranked(real: Path):
    ds = D.load(real, real / "robot.json")
    sel = D.select_runs(ds)
    return ds, sel, D.rank(ds, sel)


def test_windows_alone_do_not_see_the_ed_the_track_shows(case) -> None:
    """The premise, measured: the windows' deviance at the true Ed is no better than nominal by
    BIC's one-parameter price, while the fitting runs' tracks sit far from the background."""
    real, ed = case
    ds, sel, rk = _ranked(real)
    prob: Problem = rk.prob
    gain = prob.deviance({})[0] - prob.deviance({"ed.value": ed})[0]
    assert gain < np.log(prob.deviance({})[2]), gain
    bg = prob.walk or D.Background("truth")
    tp = D.TrackProblem([ds.items[i] for i in sel.fit], prob.sigma, bg)
    assert tp.ratio({}) >= 3.0 * tp.ratio({"ed.value": ed}), (tp.ratio({}), ed)


def test_the_track_refit_names_the_ed_and_sizes_it(case) -> None:
    real, ed = case
    rep = D.diagnose(real, real / "robot.json").to_dict()
    v = rep["verdict"]
    assert v["effect"] == "ed", v
    assert abs(v["params"]["ed.value"] - ed) < 0.2 * abs(ed - 1.0), (v["params"], ed)
    assert v["evidence"]["heldout_ratio_after"] <= 1.5
    assert "the accumulated track" in rep["proposals"]


def test_without_the_track_refit_the_same_case_is_missed(case, monkeypatch) -> None:
    """The refit is what names it (this test fails if the windows start seeing the Ed alone,
    which would make the refit's reason moot, not wrong)."""
    real, _ = case
    monkeypatch.setattr(D, "TRACK_FAMILIES", ())
    v = D.diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] != "ed", v


def test_a_member_that_only_helps_the_runs_it_was_fitted_to_stays_out(tmp_path: Path) -> None:
    """Dev seed 8 case 6, as the blind check draws it: a LabMate whose scrub follows a torque law
    the catalog's does not have. On the fitting runs' tracks a tiny Ed beside the scrub halved
    what was left (R 2.13 -> 1.03) and the held-out runs came out worse (3.71 -> 4.36 x the
    background); left out of its fit, each path says so (diagnose._track_cv)."""
    real = tmp_path / "real"
    indep_case(8, 6, real, "labmate", {"scrub": "torque"})
    v = D.diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] == "scrub", v


def test_a_linkage_bias_below_half_an_encoder_step_is_no_member() -> None:
    """diagnose._below_resolution: a 0.07 deg rotary bias on an 11-bit encoder (0.18 deg steps)
    is what a truth's lever arm a few mm off fakes; 0.3 deg is a bias. The linear encoder alike."""
    from odo_tools.gap import hypotheses as H
    from odo_tools.gap.fit import Fit
    from odo_tools.gap.io import Robot

    set_ = Robot("r.json", "set", 0.04, [{}, {}], trailer={"rotary_bits": 11})
    clap = Robot(
        "r.json",
        "clapper",
        0.04,
        [{}, {}],
        linkage={"rotary_bits": 10, "linear_resolution_mm": 0.1},
    )

    def fit(fams: tuple[str, ...], params: dict, vehicle: str) -> Fit:
        hyp = H.Hypothesis(tuple(H.catalog_law(f, vehicle) for f in fams))
        return Fit("+".join(fams), params, {}, 0.0, 0.0, 100, len(params), [], hyp)

    small = fit(("count_loss", "rotary_bias"), {"rotary_bias.alpha_deg": -0.07}, "set")
    assert D._below_resolution(small, set_) == {"rotary_bias"}
    big = fit(("rotary_bias",), {"rotary_bias.alpha_deg": 0.3}, "set")
    assert not D._below_resolution(big, set_)
    both = {"rotary_bias.alpha_deg": 0.1, "rotary_bias.beta_deg": 0.4}  # 10 bit: 0.35 deg steps
    assert not D._below_resolution(fit(("rotary_bias",), both, "clapper"), clap)
    link = {"link_bias.const_mm": 0.02, "link_bias.ecc_mm": -0.01}
    assert D._below_resolution(fit(("link_bias",), link, "clapper"), clap) == {"link_bias"}
    link["link_bias.const_mm"] = 0.5
    assert not D._below_resolution(fit(("link_bias",), link, "clapper"), clap)
    # a link-length bias within the lever arms taken off the tracked points (independent seed
    # 2691 case 50: 1.25 mm beside a 2.1 mm lever arm estimated on a truck that has none)
    link = {"link_bias.const_mm": 1.25, "link_bias.ecc_mm": -0.48}
    assert D._below_resolution(fit(("link_bias",), link, "clapper"), clap, 2.06) == {"link_bias"}
    assert not D._below_resolution(fit(("link_bias",), link, "clapper"), clap, 1.0)


def test_geometry_that_leaves_the_fitting_tracks_far_off_is_no_explanation(tmp_path: Path) -> None:
    """The simulator's fresh seed 2672, case 53: a clapper whose wheel diameter breathes with a
    30 s period (out of the catalog). A scrub fitted to the tracks halved their excess but left
    them at 38 x the background (from 109), and the held-out runs named it (R 83.6 -> 37.3);
    geometry that does not explain the tracks it was fitted to (TRACK_EXPLAINED) stays out, and
    the verdict is 'unexplained'."""
    from odo_tools.validation.blind import draw_case, simulate_case

    rng = np.random.default_rng(2672)
    c = [draw_case(rng, k) for k in range(54)][53]
    assert c["vehicle"] == "clapper" and c["kind"] == "ooc", "the simulator's draw changed"
    real = tmp_path / "real"
    simulate_case(c, real, 2672 * 1000 + 53)
    assert D.diagnose(real, real / "robot.json").to_dict()["verdict"]["effect"] == "unexplained"


def test_a_trailer_truck_s_own_es_is_tried_when_the_misfit_leans_to_it(tmp_path: Path) -> None:
    """The independent world's seed 2681 case 57 (traced after that seed was measured): a
    clapper whose truck B alone has an Es of 1.0067. Truck B holds 62 % of the excess misfit,
    short of the 75 % that proposes every effect of one truck; the linked trucks share the
    rest. Es on both trucks left R 20.9 ('unexplained'); B's own Es removes most of it (R 25.5 ->
    4.4) and is sized within 15 % (1.0060; the remainder is not closed by any candidate)."""
    real = tmp_path / "real"
    c = indep_case(2681, 57, real, "clapper", {"es": "diameter"})
    assert c["scope"] == {"es": "B"}
    v = D.diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] == "es", v
    assert v["best_hypothesis"] == "es[B]", v
    es = c["true"]["effects"]["es"]["value"]
    assert abs(v["params"]["es.value.B"] - es) < 0.15 * abs(es - 1.0), (v["params"], es)


def test_both_trucks_own_geometry_is_tried_whichever_the_windows_lean_to(tmp_path: Path) -> None:
    """The independent world's seed 2841 case 58 (traced after that seed was measured): a
    clapper whose truck B alone has an Ed of 0.99879. B's tracks were 27-113 mm off and A's
    within 2 mm, but the windows' excess leaned to truck A, whose own variants were the only
    ones tried: nothing closed the gap ('unexplained', 11.6 x the background held out). With
    both trucks' own geometry, B's Ed closes it and is sized within 15 %."""
    real = tmp_path / "real"
    c = indep_case(2841, 58, real, "clapper", {"ed": "fixed"})
    assert c["scope"] == {"ed": "B"}
    rep = D.diagnose(real, real / "robot.json").to_dict()
    v = rep["verdict"]
    assert v["effect"] == "ed", v
    assert v["best_hypothesis"] == "ed[B]", v
    ed = c["true"]["effects"]["ed"]["value"]
    assert abs(v["params"]["ed.value.B"] - ed) < 0.15 * abs(ed - 1.0), (v["params"], ed)
    assert rep["heldout"]["ratio_after"] < 1.5


def test_a_member_that_bends_the_fitting_tracks_away_is_refused(tmp_path: Path) -> None:
    """The independent world's seed 2681 case 31 (traced after that seed was measured): a set
    whose trailer alone has an Es (tyre deflection, 1.0058), driven without turns on the spot.
    An Eb beside the trailer's Es won 21 BIC on the windows and took the fitting runs' tracks
    from 6 to 122 x the background (held-out 32 -> 127, 'unexplained'). A member that makes
    the fitting tracks worse by TRACK_GAIN is not one."""
    real = tmp_path / "real"
    indep_case(2681, 31, real, "set", {"es": "deflection"})
    ds, sel, rk = _ranked(real)
    single = next(f for f in rk.cands if f.name == "es[B]")
    pair = next(f for f in rk.cands if f.name == "eb+es[B]")
    # the windows preferred the pair while the trailer's marker was read under the first
    # preliminary fit; read under the nominal geometry (_lever_on_arcs) they prefer the single
    # by 1.9 BIC, and the member rule is asked directly
    r1 = D._track_ratio(single, rk.prob, ds, sel)
    r2 = D._track_ratio(pair, rk.prob, ds, sel)
    assert r2 > 5 * r1, (r1, r2)  # the pair bends the tracks it was fitted to
    assert not D._more(single, pair, rk.prob, ds, sel)
    v = D.diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] == "es" and v["best_hypothesis"] == "es[B]", v


def test_a_linkage_bias_is_not_traded_for_geometry_the_tracks_prefer(tmp_path: Path) -> None:
    """The independent world's seed 2681 case 33 (traced after that seed was measured): a set
    whose hitch encoder reads 1.28 deg off. The windows name the rotary bias by 20244 BIC; the
    track fit, which leaves the linkage readings out, replaced it with an Ed that moved nothing
    (held-out R 3.07 -> 3.06, 'unexplained'). A sensor's bias is not the track fit's to judge."""
    real = tmp_path / "real"
    c = indep_case(2681, 33, real, "set", {"rotary_bias": "constant"})
    v = D.diagnose(real, real / "robot.json").to_dict()["verdict"]
    assert v["effect"] == "rotary_bias", v
    a = c["params"]["rotary_bias.alpha_deg"]
    assert abs(v["params"]["rotary_bias.alpha_deg"] - a) < 0.05 * abs(a), (v["params"], a)


def test_a_second_parameter_must_halve_what_a_simpler_law_leaves(tmp_path: Path) -> None:
    """Independent world, dev seed 2731 case 21: a LabMate whose wheelbase follows the inverse
    turn radius (k = 0.0212). Fitted to the tracks, the catalog scrub leaves 1.86 x the
    background and the load law's two parameters 1.72 x; taken for that, the load law sent the
    held-out oval (driven the other way) to 184 x ("unexplained"). A second parameter must
    halve the excess like a further member (diagnose._track_simplest)."""
    real = tmp_path / "real"
    indep_case(2731, 21, real, "labmate", {"scrub": "inv_radius"})
    rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "scrub", rep["verdict"]
    assert rep["verdict"]["params"]["scrub.k"] == pytest.approx(0.0212, rel=0.1)
    assert "scrub fitted to the tracks" in rep["proposals"]["the accumulated track"]


@pytest.mark.parametrize(
    ("ratios", "chosen"),
    [
        ((1.86, 1.72), "scrub"),  # 2731 case 21: 2.46 -> 1.96 of excess, not halved
        ((1.86, 1.20), "eb@load"),  # halved: the second parameter earns its place
        ((0.90, 0.50), "scrub"),  # nothing above the background to halve
    ],
)
def test_track_simplest(ratios: tuple, chosen: str) -> None:
    from odo_tools.gap import hypotheses as H

    hyps = [H.Hypothesis((H.catalog_law("scrub", "labmate"),))]
    hyps += [h for h in H.other_laws("eb", "truth", "labmate") if h.name == "eb@load"]
    fits = [type("F", (), {"hyp": h, "name": h.name})() for h in hyps]
    best, r = D._track_simplest(fits, list(ratios))
    assert best.name == chosen and r == ratios[[f.name for f in fits].index(chosen)]


@pytest.mark.parametrize(
    ("ratios", "chosen"),
    [
        ((0.976, 0.974), "eb"),  # 2841 case 53: within 1 %, the tracks cannot tell them
        ((1.20, 1.10), "scrub"),  # 8 % apart: the tracks can
    ],
)
def test_a_tie_on_the_tracks_goes_to_the_catalog_order(ratios: tuple, chosen: str) -> None:
    from odo_tools.gap import hypotheses as H

    hyps = [H.Hypothesis((H.catalog_law(f, "clapper"),)) for f in ("eb", "scrub")]
    fits = [type("F", (), {"hyp": h, "name": h.name})() for h in hyps]
    best, _ = D._track_simplest(fits, list(ratios))
    assert best.name == chosen


def test_one_trucks_geometry_is_fitted_to_the_tracks_on_that_truck(tmp_path: Path) -> None:
    """Independent world, dev seed 2841 case 23: a clapper whose truck B alone has a left tyre
    that grows with the square of its speed (Ed 1.00079 and 0.009 per (m/s)^2). The windows see
    nothing of it (Delta BIC 6); the tracks of B drift 2-4 deg along a 17 m run. Fitted to the
    tracks on both trucks at once, no geometry came near (an Ed's growth law left 6.6 x, since
    truck A has none), and the verdict was "unexplained" at 39 x the background. The track fit
    now tries the own geometry of the truck whose tracks sit furthest off (here B)."""
    c, rep = indep_named(2841, 23, tmp_path, "clapper", {"ed": "speed"}, "ed", "growth")
    v = rep["verdict"]
    assert set(v["params"]) == {"ed.value.B", "ed@growth.g_per_m2_s2.B"}, v["params"]
    e = c["true"]["effects"]["ed"]
    assert e["truck"] == "B" and e["g_right"] == 0.0
    assert v["params"]["ed@growth.g_per_m2_s2.B"] == pytest.approx(e["g_left"], rel=0.2)
    assert v["evidence"]["heldout_ratio_after"] <= 2.0, v["evidence"]
    assert "[B] fitted to the tracks" in rep["proposals"]["the accumulated track"]


def test_a_member_the_tracks_do_not_need_leaves_the_pair(tmp_path, monkeypatch) -> None:
    """Independent world, dev seed 2761 case 28: a set whose trailer's wheels differ (Ed
    0.99846 on truck B) and whose truth runs 6.7 ms late on 10 ms ticks, which no run's track
    fixes. With no clock, the windows ranked a motor-law slip first and took "ed + slip" from
    it (Delta qBIC -0.1, accepted on the tracks: 13.1 -> 4.9 x the background). Without the
    slip the tracks stay where they were, so it leaves (diagnose._prune_members) and the
    verdict is the trailer's Ed. Since the clock is scanned where no run fixed one (10 ms
    found), the trailer's Ed leads alone and nothing needs to leave; and since the runs' misfits
    are summed where none fixes a latency alone (instrument.run_latencies), they read 6.5 ms
    before any ranking. The pruning is asked here with each run's own latency and the clock
    left unscanned, as it was, and the track fit off."""
    real = tmp_path / "real"
    c = indep_case(2761, 28, real, "set", {"ed": "fixed"})

    def diagnosed() -> dict:
        rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
        assert rep["verdict"]["effect"] == "ed", rep["verdict"]
        assert rep["verdict"]["params"]["ed.value.B"] == pytest.approx(0.99846, abs=3e-4)
        return rep

    rep = diagnosed()
    got = set(rep["instrument"]["latency_s"].values())
    true = c["fidelity"]["truth_latency_s"]
    assert len(got) == 1 and abs(got.pop() - true) < 0.0015, (got, true)
    assert "the accumulated track" not in rep["proposals"]
    each_run_its_own_latency(monkeypatch)
    rep = diagnosed()
    assert set(rep["instrument"]["latency_s"].values()) == {0.01}
    ask = D._slip_not_latency

    def no_scan(ds, sel, ranked, best, cand=None, others=()) -> bool:
        late = [i for i in sel.fit if ds.instrument.latency_s.get(ds.prs[i].run.name)]
        return bool(late) and ask(ds, sel, ranked, best, cand, others)

    monkeypatch.setattr(D, "_slip_not_latency", no_scan)
    # the track fit of each truck's own geometry names the trailer's Ed before the pruning is
    # asked (ed[B] leaves the fitting tracks at 2.43 x); with it off, the pruning is asked
    rep = diagnosed()
    assert set(rep["instrument"]["latency_s"].values()) == {0.0}
    assert "ed[B] fitted to the tracks" in rep["proposals"]["the accumulated track"]
    monkeypatch.setattr(D, "_track_refit", lambda *a, **k: False)
    rep = diagnosed()
    assert "the rest is not needed there" in rep["proposals"]["the accumulated track"]


def test_an_es_the_tracks_choose_is_the_floor_when_the_walk_accounts_for_it(
    tmp_path: Path, monkeypatch
) -> None:
    """Dev seed 2851 case 54: a LabMate on a rough surface (the independent world's own
    roughness law). The windows named roughness + slip, the track refit replaced it with an Es,
    and the floor's rule (diagnose._floor_or_scale: an Es whose shortening the measured walk
    accounts for is the floor) was not asked again: "es". Its runs are kept whole, as they were
    then: with its only oval cut in two (test_gap_halves.py) the windows' best is roughness
    alone and the track refit is not needed. Nor is it where the allowance carries what the
    counts' own resolution leaves (background.counting_error: 4.9 mrad a count here), so the
    scenario is traced without that share, then judged with it."""
    from odo_tools.gap import background

    real = tmp_path / "real"
    indep_case(2851, 54, real, "labmate", {"roughness": "surface"})
    monkeypatch.setattr(D, "lone_kinds", lambda prs: [])
    with monkeypatch.context() as m:
        m.setattr(background, "counting_error", lambda it, t: np.zeros((it.i.size, 3)))
        rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "roughness", rep["verdict"]
    assert "es fitted to the tracks" in rep["proposals"]["the accumulated track"]
    rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "roughness", rep["verdict"]


def test_a_rough_surface_that_shortens_more_than_grains_is_still_the_floor(tmp_path: Path) -> None:
    """Dev seed 4131 case 57: a LabMate on a continuous rough surface, which shortens travel
    more for the walk it makes than the catalog's grains do. Its Es (1.0057) was 2.3 x what
    grains walking as much as the measured floor would give, outside the floor's factor of 2:
    "es". Within diagnose.FLOOR_RATIO it is the floor, and an Es whose shortening the floor's
    walk does not account for stays an Es (its ratio on the same walk, beyond the factor)."""
    from odo_tools.gap.model import rough_moments

    real = tmp_path / "real"
    indep_case(4131, 57, real, "labmate", {"roughness": "surface"})
    ds = D.load(real, real / "robot.json", "truth")
    sel = D.select_runs(ds)
    rk = D.rank(ds, sel)
    assert rk.best.hyp is not None and "roughness" in rk.best.hyp.families, rk.best.name
    es = rk.best.params["es.value"]
    m1, _ = rough_moments(rk.prob.items[0].pr.R[0], rk.prob.rough_from_walk())
    ratio = (1.0 - 1.0 / es) / (m1 / 20.0)
    assert 2.0 < ratio <= D.FLOOR_RATIO  # named Es with a factor of 2
    scale = 1.0 / (1.0 - D.FLOOR_RATIO * 1.2 * m1 / 20.0)
    big = D.Fit(rk.best.name, {**rk.best.params, "es.value": scale}, {}, 0.0, 0.0, 1, 1, [],
                hypotheses.Hypothesis((hypotheses.catalog_law("es", "labmate"),)))  # fmt: skip
    assert D._floor_or_scale(big, rk.prob, "labmate").hyp.families == ("es",)


def test_a_linkage_bias_beside_the_tracks_geometry_must_earn_its_place(tmp_path: Path) -> None:
    """Independent world, seed 3071 case 49 (traced after that seed was measured): a set whose
    truck A has a tyre that grows with speed. The windows' best was a rotary bias of 0.05 deg;
    the tracks (12 x the background nominally) name Ed's growth law on truck A, and the bias
    stays beside it only where it still earns its place on the windows (diagnose._more): here it
    does not, and the verdict is the Ed alone (it was "unexplained", then "ed+rotary_bias")."""
    real = tmp_path / "real"
    c = indep_case(3071, 49, real, "set", {"ed": "speed"})
    rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    v = rep["verdict"]
    assert v["effect"] == "ed" and v["best_hypothesis"] == "ed@growth[A]", v
    assert c["true"]["effects"]["ed"]["truck"] == "A"
    assert v["evidence"]["heldout_ratio_after"] < 1.5, v["evidence"]
    assert "fitted to the tracks" in rep["proposals"]["the accumulated track"]


def test_geometry_the_tracks_want_joins_a_best_that_has_none(tmp_path: Path) -> None:
    """Independent world, seed 3071 case 40 (traced after that seed was measured): a set with
    count loss at a rate ceiling and an Ed of 1.00127 on truck A. The windows name the count
    loss, which leaves the fitting runs' tracks at 4.4 x the background; truck A's Ed fitted to
    the tracks beside it, the count loss as the windows fitted it, halves their excess misfit
    there and on the paths it was not fitted to (diagnose._geometry_beside)."""
    real = tmp_path / "real"
    c = indep_case(3071, 40, real, "set", {"count_loss": "rate_limit", "ed": "fixed"})
    rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    v = rep["verdict"]
    assert v["effect"] == "count_loss+ed", v
    assert v["params"]["ed.value.A"] == pytest.approx(c["true"]["effects"]["ed"]["value"], abs=3e-4)
    h = rep["heldout"]
    assert h["ratio_after"] < 0.25 * h["ratio_before"], h  # count loss alone: 88.9 -> 38.6 x
    said = rep["proposals"]["the accumulated track"]
    assert "count_loss@plateau[A]+ed[A] fitted to the tracks" in said, said


def _fit(*names: str, dev: float):
    """A LabMate's truth-mode Fit of the catalog singles `names` joined, with deviance `dev`
    (the windows' BIC, for _drop_members), on 5000 values."""
    from odo_tools.gap import hypotheses
    from odo_tools.gap.fit import Fit

    hs = {h.name: h for h in hypotheses.singles("truth", "labmate")}
    h = hs[names[0]]
    for n in names[1:]:
        h = h + hs[n]
    return Fit(h.name, {}, {}, dev, dev, 5000, len(h.params), hyp=h)


def test_of_members_the_tracks_can_spare_the_windows_keep_the_strongest() -> None:
    """Independent world, seed 3191 case 21 (traced after its blind): the windows' best was
    "scrub + slip" on a LabMate whose tyres slip under acceleration. Either member could leave
    the fitting runs' tracks (scrub alone 1.69, slip alone 1.76 x the background, the pair 1.68);
    the one whose removal left the tracks lowest went, the slip, though the windows put the
    slip alone 322 ahead of the scrub in BIC, and the scrub at its bound bent the held-out
    circle to 431 mm. The windows now keep the member they value most; a member the tracks
    need still stays."""
    pair = _fit("scrub", "slip", dev=1580.0)
    alone = {"scrub": (1.686, _fit("scrub", dev=1965.0)), "slip": (1.764, _fit("slip", dev=1635.0))}

    def refit(h, cur):
        return alone[h.name]

    got, r = D._drop_members(pair, 1.68, refit)
    assert (got.name, r) == ("slip", 1.764)
    alone["slip"] = (2.6, alone["slip"][1])  # without the scrub the tracks' excess triples
    got, r = D._drop_members(pair, 1.68, refit)
    assert (got.name, r) == ("scrub", 1.686)
    alone["scrub"] = (2.6, alone["scrub"][1])  # both needed: the pair stays
    assert D._drop_members(pair, 1.68, refit)[0] is pair


def test_a_spare_member_whose_removal_mends_the_tracks_leaves_whatever_the_windows_say() -> None:
    """Independent world, dev seed 4071 case 19, a LabMate with no effect: the windows' best
    was "skid + slip" at 8.2 x the background on the fitting tracks; the skid alone leaves
    1.34 x, the catalog's slip alone 7.6 x, though the windows put the slip 378 ahead. Both
    are spare, but not alike to the tracks (the slip's excess is 70 times the skid's): the
    slip leaves. By the windows alone it stayed, and the truth's clock, scanned at 15 ms
    (the world's 14 ms), went to 8-15 ms run by run."""
    alone = {"skid": (1.34, _fit("skid", dev=6350.0)), "slip": (7.6, _fit("slip", dev=5970.0))}
    pair = _fit("skid", "slip", dev=5870.0)
    got, r = D._drop_members(pair, 8.2, lambda h, cur: alone[h.name])
    assert (got.name, r) == ("skid", 1.34)


def test_a_scrub_no_held_out_run_shows_is_judged_path_by_path(tmp_path: Path) -> None:
    """Independent world, dev seed 4220 case 37: a LabMate's torque scrub changes no spot turn;
    its circle and free drive were fitted, two squares and a shuttle judged, and the held-out
    runs sat at 0.68 x the background while the fitting runs' tracks sat at 14.6 x ("no
    significant gap"). Each fitting path left out of the scrub's fit shows it
    (diagnose._paths_left_out), and the verdict names it with the held-out figure unchanged."""
    c, rep = indep_named(4220, 37, tmp_path, "labmate", {"scrub": "torque"}, "scrub", "catalog")
    hd = rep["heldout"]
    assert hd["ratio_before"] < D.R_GAP, hd  # the held-out runs still show no gap
    said = rep["verdict"]["reason"]
    assert "path by path" in said, said
    k = rep["verdict"]["params"]["scrub.k"]
    assert 0.0 < k < 2.0 * c["true"]["effects"]["scrub"]["s_sat"], (k, c["true"]["effects"])


@pytest.mark.parametrize(
    ("fams", "paths", "r0", "r1", "named"),
    [
        (("scrub",), 5, 14.6, 1.27, True),  # dev 4220 case 37
        (("scrub",), 5, 14.6, 2.5, True),  # 2.5 x still removes 97 % of 14.6 x's excess
        (("scrub",), 5, 3.0, 2.5, False),  # a gap the paths left out keep
        (("scrub",), 5, 1.9, 1.0, False),  # the fitting tracks show no gap either
        (("scrub",), 1, 14.6, 1.0, False),  # one path: nothing left out
        (("slip",), 5, 14.6, 1.27, True),  # any law the tracks fit (seed 3341 case 3)
        (("slip",), 5, 3.0, 2.5, False),
        (("bumps",), 5, 14.6, 1.0, False),  # placed only where two fitting runs agree
        (("link_bias",), 5, 14.6, 1.0, False),  # a linkage bias: the tracks do not see it
    ],
)
def test_the_fitting_paths_judge_only_a_gap_they_show_and_close_left_out(
    monkeypatch: pytest.MonkeyPatch, fams: tuple, paths: int, r0: float, r1: float, named: bool
) -> None:
    """The rule of diagnose._paths_left_out on the fitting runs' nominal track ratio (r0) and the
    best's ratio on each path left out of its fit (r1, `_track_cv`)."""
    from types import SimpleNamespace

    hyp = hypotheses.Hypothesis(tuple(hypotheses.catalog_law(f, "labmate") for f in fams))
    best = SimpleNamespace(hyp=hyp, label="+".join(fams), model_params=dict)
    items = [SimpleNamespace(pr=SimpleNamespace(path=f"p{i % paths}")) for i in range(6)]
    tp = SimpleNamespace(items=items, ratio=lambda P: r0)
    monkeypatch.setattr(D, "_fitting_tracks", lambda *a: tp)
    monkeypatch.setattr(D, "group_key", lambda pr: pr.path)
    monkeypatch.setattr(D, "_track_cv", lambda *a, **k: r1 * r1)
    held = SimpleNamespace(ratio_before=0.7)
    got = D._paths_left_out(None, None, SimpleNamespace(best=best, prob=None), held)
    assert (got is not None) is named
    if named:
        assert got[0] == best.label and "path by path" in got[1]


def test_a_skid_no_held_out_run_shows_is_judged_path_by_path(tmp_path: Path) -> None:
    """Independent world, dev seed 4121 case 33: a LabMate's cornering skid; its held-out runs
    sit at 0.51 x the background, its fitting runs' tracks at 5.0 x. Judged path by path as a
    scrub is (any law the tracks can be fitted under, not geometry alone): "no significant gap"
    on the code before, the skid now, its stiffness within 10 % of the world's."""
    c, rep = indep_named(4121, 33, tmp_path, "labmate", {"skid": "cornering"}, "skid", "cornering")
    assert rep["heldout"]["ratio_before"] < D.R_GAP, rep["heldout"]
    assert "path by path" in rep["verdict"]["reason"], rep["verdict"]["reason"]
    want = math.degrees(1.0 / c["true"]["effects"]["skid"]["c_alpha_m_s2"])  # deg per m/s^2
    got = rep["verdict"]["params"]["skid@cornering.deg_per_m_s2"]
    assert got == pytest.approx(want, rel=0.1), (got, want)
