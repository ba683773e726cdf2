"""A truth clock that drifts against the wheel counts (issue 13 item 2, out of the catalog): each
run's latency grows linearly from its start to its end, which one latency per run cannot
follow. The runs' latencies on their first and last thirds give the rate (instrument.clock_rate,
under the best candidate); runs that agree on it beyond instrument.CLOCK_RATE_Z standard errors
make the verdict "unexplained", with the rate in the reason and the report - over a candidate
the verdict's rule names only where the truth re-stamped by the rate confirms it
(diagnose._clock_confirmed)."""

from __future__ import annotations

from pathlib import Path

import pytest
from gap_support import BUILD, SRC, indep_case


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def test_a_drifting_truth_clock_is_unexplained_with_its_rate(tmp_path: Path) -> None:
    """Independent world, seed 2911 case 31: a LabMate with no effect whose motion capture
    drifts 847 ppm against its counts (43 ms over a 50 s run). The held-out runs sat below the
    gap threshold (1.58 x the background) and the verdict was "no significant gap", which hid
    a rig that cannot be trusted; the eight runs read 854 +- 14 ppm."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    c = indep_case(2911, 31, real, "labmate", {"clock_drift": "linear"})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    true = c["true"]["effects"]["clock_drift"]["ppm"]
    cr = rep["instrument"]["clock_rate"]
    assert abs(cr["ppm"] - true) < 0.15 * abs(true), (cr, true)
    assert rep["verdict"]["effect"] == "unexplained", rep["verdict"]
    v, steps = rep["verdict"], rep["next_step"]
    assert f"the truth's clock runs {cr['ppm']:+.0f} +- " in v["reason"], v
    assert steps[0].startswith("stamp the truth with the robot's clock"), steps


def test_a_clock_read_at_five_to_eight_standard_errors_is_unexplained(tmp_path: Path) -> None:
    """Dev seed 4520 case 54: a clapper with no effect whose motion capture drifts -321 ppm.
    Its held-out runs sit at 0.88 x the background, and nine of nine runs read -397 +- 73 ppm,
    5.4 standard errors; the verdict was "no significant gap" while the rate needed 8."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    c = indep_case(4520, 54, real, "clapper", {"clock_drift": "linear"})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    true = c["true"]["effects"]["clock_drift"]["ppm"]
    cr = rep["instrument"]["clock_rate"]
    assert 5.0 <= abs(cr["ppm"]) / cr["se_ppm"] < 8.0, cr
    assert cr["ppm"] * true > 0 and abs(cr["ppm"] - true) < 0.4 * abs(true), (cr, true)
    assert rep["verdict"]["effect"] == "unexplained", rep["verdict"]
    assert "the truth's clock runs" in rep["verdict"]["reason"], rep["verdict"]


def test_a_skid_is_named_beside_a_clock_that_restamping_does_not_confirm(tmp_path: Path) -> None:
    """Dev seed 4061 case 14: a LabMate whose floor gives 0.56 m/s^2 and whose truth keeps the
    robot's time. Under the friction skid named (96 % of the held-out misfit removed) the runs'
    thirds read +1879 ppm, seven of nine agreeing, and the verdict was "unexplained", the clock's.
    The truth re-stamped by that rate leaves the skid more of the held-out misfit, not less
    (diagnose._clock_confirmed): the skid stays named, the rate and the re-stamped misfit in
    the report."""
    from odo_tools.gap.diagnose import CLOCK_CONFIRM, diagnose
    from odo_tools.gap.report import markdown

    real = tmp_path / "real"
    c = indep_case(4061, 14, real, "labmate", {"skid": "friction"})
    assert "clock_drift" not in c["true"]["effects"]
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "skid", rep["verdict"]
    cr, h = rep["instrument"]["clock_rate"], rep["heldout"]
    assert abs(cr["ppm"]) >= 8 * cr["se_ppm"] and abs(cr["ppm"]) > 1000, cr  # read drifting
    assert cr["restamped_ratio_after"] ** 2 - 1 > CLOCK_CONFIRM * (h["ratio_after"] ** 2 - 1), cr
    assert "not the clock's, and the verdict stands" in markdown(rep)


def test_restamping_a_drifting_truth_by_its_rate_stops_the_drift(tmp_path: Path) -> None:
    """instrument.restamped scales each run's truth time by 1 - ppm x 1e-6 from the run's
    start (the next step the report gives): seed 2911 case 31's truth, re-stamped by the rate
    its runs read, reads within a tenth of it, and the truth's first sample keeps its time."""
    from odo_tools.gap import diagnose as D
    from odo_tools.gap import instrument

    real = tmp_path / "real"
    indep_case(2911, 31, real, "labmate", {"clock_drift": "linear"})
    ds = D.load(real, real / "robot.json", "truth")
    cr = instrument.clock_rate(ds.prs, ds.instrument)
    assert cr is not None and cr.drifting(), cr
    prs = instrument.restamped(ds.prs, cr.ppm)
    for a, b in zip(ds.prs, prs, strict=True):
        assert b.run.truth.t_s[0] == a.run.truth.t_s[0]
        span = a.run.truth.t_s[-1] - a.run.truth.t_s[0]
        got = b.run.truth.t_s[-1] - b.run.truth.t_s[0]
        assert got == pytest.approx(span * (1 - cr.ppm * 1e-6), abs=1e-6)  # epoch seconds
    again = instrument.clock_rate(prs, ds.instrument)
    assert abs(again.ppm) < 0.1 * abs(cr.ppm), again


def test_an_es_reads_as_a_clock_on_the_nominal_model_only(tmp_path: Path) -> None:
    """Independent world, dev seed 2811 case 25: a set's trailer with a mean-diameter error and a
    truth clock that holds still. On the nominal model the runs' thirds read -420 ppm, seven of
    seven agreeing; under the best candidate (Es) the rate is gone and the verdict stays es."""
    from odo_tools.gap import diagnose as D
    from odo_tools.gap import instrument

    real = tmp_path / "real"
    indep_case(2811, 25, real, "set", {"es": "deflection"})
    ds = D.load(real, real / "robot.json", "truth")
    nominal = instrument.clock_rate(ds.prs, ds.instrument)
    assert nominal is not None and nominal.drifting(), nominal
    rep = D.diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "es", rep["verdict"]
    cr = rep["instrument"]["clock_rate"]
    assert abs(cr["ppm"]) < 0.25 * abs(nominal.ppm), (cr, nominal)


def test_a_clock_needs_many_runs_that_agree_on_a_real_rate() -> None:
    """Each rule of ClockRate.drifting bites on its own: the rate, its standard error, the share
    of the runs whose thirds both fixed a latency, and their number."""
    from odo_tools.gap.instrument import ClockRate

    assert ClockRate(600.0, 30.0, 9, 10, 50.0).drifting()
    assert not ClockRate(150.0, 5.0, 9, 10, 50.0).drifting()  # too slow to matter
    assert not ClockRate(-600.0, 150.0, 9, 10, 50.0).drifting()  # the runs scatter
    assert ClockRate(-397.0, 73.0, 9, 9, 50.0).drifting()  # dev 4520 case 54: 5.4 se
    assert not ClockRate(-445.0, 117.0, 9, 9, 50.0).drifting()  # 3.8 se (dev 4502 case 6)
    assert not ClockRate(600.0, 30.0, 6, 10, 50.0).drifting()  # too few of the runs
    assert not ClockRate(600.0, 30.0, 3, 3, 50.0).drifting()  # too few runs


def test_a_short_latency_no_run_fixes_alone_is_fixed_by_the_session(tmp_path: Path) -> None:
    """Dev seed 4121 case 34: a LabMate counting 2.8 mm edges on 50 ms ticks whose motion
    capture runs 7 ms late. Each run's own shift gains less than instrument.LATENCY_DCHI2 over
    none (its misfit is the counts' coarseness), so every run took none and each turn on the
    spot left a heading step as strong as the floor's cables; the eight runs' misfits summed
    fix the clock for all of them."""
    from odo_tools.gap.diagnose import load
    from odo_tools.gap.instrument import latency

    real = tmp_path / "real"
    c = indep_case(4121, 34, real, "labmate", {"bumps": "ramps"})
    ds = load(real, real / "robot.json", "truth")
    assert all(latency(pr) is None for pr in ds.prs)
    true = c["fidelity"]["truth_latency_s"]
    got = set(ds.instrument.latency_s.values())
    assert len(got) == 1 and abs(got.pop() - true) < 0.0015, (ds.instrument.latency_s, true)
