"""The independent world's own measure of how far a case's effect reaches the evidence
(validation/indep/imprint.py), and how the blind check scores with it: only where an effect acts
(the key's `visible`) and, as a second figure, only where its imprint stands out of the floor's
and the sensors' (`visible_only`)."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
from odo_tools.validation import indep
from odo_tools.validation.blind import score, scored_in
from odo_tools.validation.indep import cases, imprint
from odo_tools.validation.indep.simulate import run_world


def _case(seed: int = 3) -> dict:
    """A drawn no-effect LabMate with its floor and sensors as drawn, three runs of at most 12 s."""
    rng = np.random.default_rng(seed)
    while True:
        c = indep.draw_case(rng, 0)
        if c["vehicle"] == "labmate" and c["kind"] == "none":
            break
    c["plan"] = c["plan"][:3]
    for p in c["plan"]:
        segs = cases._fit([tuple(s) for s in p["segs"]], cases.limits(c, p), 12.0, 300.0)
        p["segs"] = [list(s) for s in segs]
    return c


def _with(c: dict, name: str, **e) -> dict:
    c = copy.deepcopy(c)
    c["true"]["effects"] = {name: {"truck": "A", **e}}
    return c


def _measure(c: dict, seed: int = 11) -> dict:
    return imprint.measure(c, run_world(c, seed), run_world(imprint.twin_case(c), seed))


def test_a_case_without_an_effect_is_not_measured(tmp_path: Path) -> None:
    c = _case()
    extra = indep.simulate_case(c, tmp_path / "real", 11)
    assert extra["imprint"] == {"truth": None, "returns": None, "linkage": None}
    # an effect on the linkage's sensors is not measured either: no twin is run
    assert imprint.twin_case(_with(c, "rotary_bias", law="constant", alpha_deg=1.0)) is None
    assert imprint.twin_case(_with(c, "gear_backlash", law="play", play_deg=3.0)) is not None


def test_the_imprint_grows_with_the_effect_and_a_faint_one_stays_unseen() -> None:
    """A diameter drift's imprint is linear in its size (the twin shares every random draw), a
    drift of 1 % of the radius stands far out of the floor and the sensors, one of 1e-5 does not."""
    c = _case()

    def drift(beta: float) -> dict:
        return _measure(
            _with(c, "diameter_drift", law="thermal", beta_left=beta, beta_right=0.0, tau_s=20.0)
        )

    big, small, faint = drift(1e-2), drift(1e-3), drift(1e-5)
    assert 8.0 < big["truth"]["imprint_mm"] / small["truth"]["imprint_mm"] < 12.0
    assert 8.0 < big["truth"]["imprint_deg"] / small["truth"]["imprint_deg"] < 12.0
    for m in ("truth", "returns"):
        assert big[m]["visible"] and big[m]["ratio"] >= 10 * imprint.VISIBLE_RATIO, big[m]
        assert not faint[m]["visible"] and faint[m]["ratio"] < 0.5, faint[m]
        assert big[m]["background_mm"] == faint[m]["background_mm"] > 0
    assert big["linkage"] is None


def test_a_truth_clock_drift_reaches_only_the_truth_and_within_its_bound() -> None:
    """The robot drives the same either way (a clock of the motion capture): its return errors
    carry no imprint. On the truth, every sample moves by at most the drift (its mean over the
    run taken off: a latency) times the motion's speed about it, a bound a heading interpolated
    across +-180 deg breaks (the runs turn through it three times each)."""
    c = _case()
    ppm = 1000.0
    cd = _with(c, "clock_drift", law="linear", ppm=ppm, offset_s=0.02)
    cd["true"]["effects"]["clock_drift"]["truck"] = "vehicle"
    sim = run_world(cd, 11)
    got = imprint.measure(cd, sim, run_world(imprint.twin_case(cd), 11))
    assert got["returns"]["imprint_mm"] == 0.0 and got["returns"]["imprint_deg"] == 0.0
    assert not got["returns"]["visible"]
    b_mm, b_deg = [], []
    for r in range(len(cd["plan"])):
        t, _, true = imprint.tracks(cd, sim, r, 0)
        assert np.sum(np.abs(np.diff(true[:, 2])) > math.pi) >= 2  # wraps through +-180 deg
        dl = np.abs(ppm * 1e-6 * (t - t.mean()))
        v = np.hypot(np.diff(true[:, 0]), np.diff(true[:, 1])) / np.diff(t)
        w = np.abs(np.diff(np.unwrap(true[:, 2]))) / np.diff(t)
        near = lambda x: np.maximum(np.r_[x[:1], x], np.r_[x, x[-1:]])  # noqa: E731
        b_mm.append(near(v) * dl)
        b_deg.append(np.degrees(near(w)) * dl)
    rms = lambda x: float(np.sqrt(np.mean(np.concatenate(x) ** 2)))  # noqa: E731
    assert 0.3 * rms(b_mm) < got["truth"]["imprint_mm"] <= 1.01 * rms(b_mm)
    assert 0.3 * rms(b_deg) < got["truth"]["imprint_deg"] <= 1.01 * rms(b_deg)


def _res(k: int, mode: str, verdict: str) -> dict:
    v = {"effect": verdict, "params": {}, "bumps": [], "evidence": {}}
    return {
        "real": f"/x/case-{k:03d}/real",
        "mode": mode,
        "report": {"verdict": v, "elapsed_s": 1.0, "shrink": 1.0, "runs": ["run-cw-01"]},
    }


def _key(k: int, vehicle: str, kind: str, effect: str, acts: str, seen: tuple) -> dict:
    """A hand-made key: `acts`, the modes (t, r, l) the world says the effect reaches; `seen`,
    the imprint's verdict in truth and returns mode (None: not measured)."""
    im = lambda v: None if v is None else {"visible": v, "ratio": 3.0 if v else 0.5}  # noqa: E731
    return {
        "case": k,
        "vehicle": vehicle,
        "kind": kind,
        "effects": [effect],
        "visible": {effect: {m: m[0] in acts for m in ("truth", "returns", "linkage")}},
        "imprint": {"truth": im(seen[0]), "returns": im(seen[1]), "linkage": None},
    }


def test_scores_count_a_case_only_where_its_effect_acts_and_split_the_unseen() -> None:
    ed_b = _key(0, "set", "single", "ed", "tl", (True, True))  # on the trailer
    ed_a = _key(1, "set", "single", "ed", "trl", (True, True))
    clock = _key(2, "labmate", "ooc", "clock_drift", "t", (True, False))
    faint = _key(3, "labmate", "ooc", "gear_backlash", "trl", (False, False))
    # an effect on the linkage's sensors: its imprint is not measured
    rotary = _key(4, "set", "single", "rotary_bias", "tl", (None, None))
    assert scored_in(rotary, "truth")
    assert scored_in(ed_a, "returns") and not scored_in(ed_b, "returns")
    assert scored_in(ed_b, "truth")
    res = [
        _res(0, "truth", "ed"),
        _res(0, "returns", "no significant gap"),
        _res(1, "truth", "ed"),
        _res(1, "returns", "ed"),
        _res(2, "truth", "unexplained"),
        _res(2, "returns", "unexplained"),
        _res(3, "truth", "no significant gap"),
        _res(3, "returns", "no significant gap"),
        _res(4, "truth", "rotary_bias"),
    ]
    s = score([ed_b, ed_a, clock, faint, rotary], res)
    # returns: the set's truck-B Ed is not scored there; the clock drift is not an out-of-catalog
    # case of that mode (judged "unexplained" there, it would count); the faint backlash is one,
    # and it was missed
    assert s["top1_return_errors_cases"] == 1 and s["top1_accuracy_return_errors"] == 1.0
    assert s["unexplained_rate_out_of_catalog_by_mode"]["returns"] == 0.0
    assert s["out_of_catalog_cases"] == 2 and s["unexplained_rate_out_of_catalog"] == 0.5
    vis = s["visible_only"]
    assert vis["truth"]["unexplained_rate_out_of_catalog"] == (1.0, 1)
    assert vis["truth"]["unseen_cases"] == 1 and vis["truth"]["unseen_judged_no_gap"] == 1
    assert vis["truth"]["top1_accuracy"] == (1.0, 3)  # the unmeasured one counts as before
    assert vis["returns"]["unseen_cases"] == 1 and vis["returns"]["top1_accuracy"] == (1.0, 1)
    assert "linkage" not in vis
    # a world that measures nothing (the simulator's) gets no second figure
    plain = [
        {k: v for k, v in c.items() if k not in ("imprint", "visible")}
        for c in (ed_b, ed_a, clock, faint, rotary)
    ]
    assert score(plain, res)["visible_only"] == {}
