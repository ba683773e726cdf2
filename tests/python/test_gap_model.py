"""odo-gap's model side against the simulator's own laws (issue 7): the linkage encoders'
quantisation, the slip law under a lagging drive, and the false alarm they caused on the
two-truck vehicles (a no-effect clapper/set run must come out "no significant gap")."""

from __future__ import annotations

import math
import shutil
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


def _slip_reference(v_ticks: np.ndarray, tau: float, k: float, a0: float, cap: float) -> float:
    """host_sim/src/world.c step_driven + slip_factor transcribed as a plain loop: 1 ms steps,
    a first-order lag behind a command held for each 40 ms tick. Returns floor - surface travel."""
    dt, v, prev, lost = 0.001, 0.0, 0.0, 0.0
    for c in v_ticks:
        for _ in range(40):
            v += (c - v) * (1.0 - math.exp(-dt / tau))
            a = abs(v - prev) / dt * 1e-3
            s = min(k * (a - a0 if a > a0 else 0.0), cap)
            f = 1.0 - s if abs(v) >= abs(prev) else 1.0 / (1.0 - s)
            lost += v * dt * (f - 1.0)
            prev = v
    return lost


@pytest.mark.parametrize("tau", [0.002, 0.008])
def test_slip_loss_matches_the_simulators_law_seen_through_40ms_counts(tau: float) -> None:
    from odo_tools.gap.model import Prepared, slip_loss

    cmd = np.concatenate([np.linspace(0, 600, 16), np.full(20, 600.0), np.linspace(600, 0, 16)])
    # what 40 ms counts show: the mean speed over each tick of the lagging drive
    dt, v, means = 0.001, 0.0, []
    for c in cmd:
        acc = 0.0
        for _ in range(40):
            v += (c - v) * (1.0 - math.exp(-dt / tau))
            acc += v * dt
        means.append(acc)
    ds = np.array(means)[:, None, None] * np.ones((1, 1, 2))
    pr = Prepared(None, np.arange(len(means) + 1) * 0.04, ds, np.zeros((len(means) + 1, 1, 2)),
                  [340.0], [75.0], np.full(len(means), 0.04))
    P = {"slip.k_per_m_s2": 0.6, "slip.tau_s": tau}
    got = slip_loss(pr, P, 0, 0.6).sum(axis=0)[0]
    ref = _slip_reference(cmd, tau, 0.6, 0.5, 0.2)
    assert ref != 0.0
    assert got == pytest.approx(ref, rel=0.15)


@pytest.mark.parametrize("vehicle", ["clapper", "set"])
def test_a_no_effect_two_truck_vehicle_is_no_significant_gap(vehicle: str, tmp_path: Path) -> None:
    from odo_tools.gap import blind
    from odo_tools.gap.diagnose import diagnose

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
