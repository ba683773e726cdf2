"""Traction slip inside the control tick (issue 13 item 3): a speed-commanded motor takes each
tick's new speed in a burst at the tick's start (first-order lag tau), so its wheel can spin on
every step even where the tick's mean acceleration is below the floor's grip. A limiter on the
tick means (`slip@traction`) sees none of it; the independent world's motors lag 10-60 ms
behind 10-100 ms ticks, and a set's traction slip there was "unexplained" at 13 x the
background."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from gap_support import BUILD, SRC, indep_case


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def _ramp(T: float, dv: float, n: int = 40, hold: int = 20):
    """Both wheels speeding up by dv mm/s per tick for n ticks, then holding: (pr, ds)."""
    v = np.concatenate([dv * np.arange(1, n + 1), np.full(hold, dv * n)])
    return SimpleNamespace(dt=np.full(v.size, T)), np.stack([v * T, v * T], axis=1)


@pytest.mark.parametrize("tau", [0.005, 0.02, 0.06])
def test_motor_profile_keeps_each_ticks_counted_mean(tau: float) -> None:
    """The speed inside each tick is an exponential from where the last tick ended towards a
    target whose exact mean over the tick is what the counts say: computed here tick by tick,
    against the closed-form filter the model uses."""
    from odo_tools.gap.model import motor_profile, motor_substeps

    rng = np.random.default_rng(1)
    m = np.cumsum(rng.normal(0, 30, 200))
    T = 0.04
    prof = motor_profile(m, T, tau)
    S = motor_substeps(T)
    assert prof.shape == (m.size, S)
    E = math.exp(-T / tau)
    g = tau / T * (1 - E)
    w_end = np.empty_like(m)
    w0 = 0.0
    for i, mi in enumerate(m):
        c = (mi - w0 * g) / (1 - g)
        assert c + (w0 - c) * g == pytest.approx(mi, abs=1e-6)  # the tick's exact mean
        w0 = c + (w0 - c) * E
        w_end[i] = w0
    ts = np.arange(1, S + 1) / S * T
    w_start = np.concatenate([[0.0], w_end[:-1]])
    c = (m - w_start * g) / (1 - g)
    want = c[:, None] + (w_start - c)[:, None] * np.exp(-ts / tau)[None, :]
    assert np.allclose(prof, want, atol=1e-6)


def test_bursts_spin_where_the_tick_mean_grips() -> None:
    """A ramp of 0.5 m/s^2 on 100 ms ticks under a 0.8 m/s^2 floor: the tick means never ask
    more than the floor gives, so slip_traction loses nothing; a 5 ms motor takes each 50 mm/s
    step in a burst of 10 m/s^2 and spins on every step, the floor catching up at 0.8 m/s^2
    after t = dv / a: the wheel runs dv (t - tau) ahead of a floor that covers a t^2 / 2 of
    the step, 1.31 mm per step (the model's 10 ms sub-steps resolve the 5 ms burst
    to within a few per cent). Once the speed holds, the floor has caught up."""
    from odo_tools.gap.model import slip_motor, slip_traction

    T, dv, a = 0.1, 50.0, 0.8
    pr, ds = _ramp(T, dv)
    b = 400.0
    assert np.allclose(slip_traction(pr, ds, a, b), ds)
    got = slip_motor(pr, ds, a, 0.005, b)
    tau, t = 0.005, dv / (a * 1e3)
    want = dv * (t - tau) - a * 1e3 * t * t / 2
    # the steps away from the ramp's start (the motor from rest) and end (where the speeds the
    # law reads weigh in the hold)
    lost = (ds - got)[2:39]
    assert lost == pytest.approx(np.full_like(lost, want), rel=0.06)
    assert np.allclose(got[-5:], ds[-5:])
    # a floor that grips the bursts too loses nothing
    assert np.allclose(slip_motor(pr, ds, 50.0, 0.005, b), ds, atol=1e-9)


def test_traction_slip_inside_the_tick_is_named(tmp_path: Path) -> None:
    """Independent world, seed 2731 case 24: a set (100 ms tick, 18 ms motor) whose drive truck
    spins under a 0.94 m/s^2 traction limit. A limiter on the tick means left its held-out runs
    at 13 x the background ("unexplained"); inside the tick the slip is named, and it closes
    the held-out gap."""
    rep = _slip_inside_the_tick(tmp_path, 2731, 24, "set")
    assert rep["heldout"]["ratio_after"] < 0.5 * rep["heldout"]["ratio_before"]


def _slip_inside_the_tick(tmp_path: Path, seed: int, k: int, vehicle: str) -> dict:
    """The report of the independent world's traction-slip case k of `seed`, diagnosed with
    truth, after checking that it names slip by the law inside the tick."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(seed, k, real, vehicle, {"slip": "traction"})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    v = rep["verdict"]
    assert v["effect"] == "slip", v
    assert v["laws"]["slip"]["law"] == "motor", v["laws"]
    return rep


def test_every_other_law_has_words_and_units_in_the_report() -> None:
    """A report names the law that fitted in words and gives each parameter's unit: every law
    of hypotheses.OTHER_LAWS has both (one list of laws, checked against the other)."""
    from odo_tools.gap import hypotheses, report

    for laws in hypotheses.OTHER_LAWS.values():
        for law in laws:
            assert law.name in report.LAW_WORDS, law.key
            for p in law.params:
                # asym, zeta, a scale, an exponent and the catalog's factors (eb.value) are
                # ratios: no unit
                assert report.unit(p) != "" or p.endswith(
                    (".asym", ".zeta", ".value", ".scale", ".exponent")
                ), p


def test_a_truth_late_behind_slipping_counts_finds_its_clock(tmp_path: Path) -> None:
    """Independent world, seed 2721 case 45: a set's traction slip (0.91 m/s^2) under a
    motion capture 33 ms late. Read before any effect, the latencies held the slip too, and
    without them (the only other choice then) the slip fitted to the wrong clock left the
    held-out runs at 13 x the background, "unexplained". One clock for every run tried under the
    slip candidate finds the rig's latency and the floor's grip; slip is named."""
    import statistics

    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    c = indep_case(2721, 45, real, "set", {"slip": "traction"})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    v = rep["verdict"]
    assert v["effect"] == "slip", v
    true = c["true"]["effects"]["slip"]["a_lim_m_s2"]
    assert v["params"]["slip@motor.a_max_m_s2"] == pytest.approx(true, rel=0.03)
    lat = statistics.median(rep["instrument"]["latency_s"].values())
    assert lat == pytest.approx(c["fidelity"]["truth_latency_s"], abs=0.008)
    assert rep["heldout"]["ratio_after"] < 0.5 * rep["heldout"]["ratio_before"]


def test_the_clock_is_screened_under_both_resolutions_of_a_grip_limit(tmp_path: Path) -> None:
    """Independent world, dev seed 4071 case 32: a LabMate's traction slip (0.83 m/s^2) on
    50 ms ticks under a motion capture 13 ms late. Under the tick-level limiter, the first slip
    law of the ranking, the clocks screen best at 20 ms, and the slip fitted there left the
    held-out runs at 13.6 x the background, "unexplained"; under the limiter inside the tick
    (the motor's lag) they screen best at 5 ms and 160 BIC lower. Screened under both, that
    law and clock are taken and the slip is named, closing the held-out gap."""
    rep = _slip_inside_the_tick(tmp_path, 4071, 32, "labmate")
    assert rep["heldout"]["ratio_after"] <= 1.5


@pytest.mark.parametrize(
    ("names", "twins"),
    [
        (["slip@traction", "slip@motor"], ["slip@motor"]),
        (["slip@motor[A]", "slip@traction[A]", "slip@accel"], ["slip@traction[A]"]),
        (["slip", "slip@accel"], []),  # laws proportional to acceleration take a latency
        (["slip@accel", "slip@motor"], []),
        (["slip@traction"], []),
    ],
)
def test_the_clock_is_screened_again_only_under_the_grip_limits_twin(
    names: list[str], twins: list[str]
) -> None:
    """diagnose.limiter_twins: beside the first slip law near the top, only the other
    resolution of one grip limit is screened. With the acceleration law beside catalog slip,
    the fresh seed 3161's case 36 (a floor roughness, truth 27.7 ms late) was screened at 20 ms
    under the acceleration law and named slip."""
    from odo_tools.gap import hypotheses
    from odo_tools.gap.diagnose import limiter_twins

    laws = [h.laws[0] for h in hypotheses.singles("truth", "set") if h.families == ("slip",)]
    laws += [h.laws[0] for h in hypotheses.other_laws("slip", "truth", "set")]
    laws += [law.on("A") for law in list(laws)]
    by_key = {law.key: law for law in laws}
    slips = [SimpleNamespace(name=n, hyp=hypotheses.Hypothesis((by_key[n],))) for n in names]
    assert [f.name for f in limiter_twins(slips)] == twins
