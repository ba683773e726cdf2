"""Linkage mode's noise (issue 13 item 2): the wheel counters' quantisation joins the linkage
encoders' (modes.LinkageMode.quantisation_var), so a clapper with coarse wheel counts and no
effect is not a gap."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from gap_support import indep_case


def _straight_windows(it) -> np.ndarray:
    """Windows in which both trucks drive straight in line (linkage read at zero at both ends,
    each truck's wheels equal within two counts, every wheel past 20 counts)."""
    pr = it.pr
    cs = np.concatenate([np.zeros((1, *pr.ds.shape[1:])), np.cumsum(pr.ds, axis=0)])
    tr = cs[it.j] - cs[it.i]
    step = pr.count_mm[0]
    inline = np.ones(it.i.size, dtype=bool)
    for ang in (it.a, it.b):
        inline &= (np.abs(ang[it.i]) < 0.005) & (np.abs(ang[it.j]) < 0.005)
    equal = np.abs(tr[:, :, 0] - tr[:, :, 1]).max(axis=1) < 2 * step
    moving = np.abs(tr).min(axis=(1, 2)) > 20 * step
    return inline & equal & moving


def test_a_clapper_with_coarse_counts_and_no_effect_is_no_gap(tmp_path: Path) -> None:
    """Dev seed 2606 case 11 of the independent world: a clapper on 0.154 mm counts and a 0.02 mm
    linear encoder, no effect. Driving straight in line, the predicted l is truck A's travel less
    truck B's, each the mean of two wheels read at both ends of the window: (4 x 2 readings of
    step^2 / 12) / 4 = step^2 / 6, which the profile cannot absorb (its l cell is 0.02 mm).
    The drawn quantisation must say so; taken as exact, the linkage mode called this robot
    "unexplained" at 2.8 x."""
    from odo_tools.gap.diagnose import diagnose, load

    real = tmp_path / "real"
    indep_case(2606, 11, real, "clapper", {})
    ds = load(real, real / "robot.json", "linkage")
    step = ds.prs[0].count_mm[0]
    assert ds.robot.linkage["linear_resolution_mm"] < 0.2 * step  # the case is what it says
    sd = np.concatenate(
        [np.sqrt(it.quantisation_var()[_straight_windows(it), 2]) for it in ds.items]
    )
    assert sd.size >= 4
    assert float(np.median(sd)) == pytest.approx(step / math.sqrt(6.0), rel=0.25)
    rep = diagnose(real, real / "robot.json", 0.5, 1, "linkage").to_dict()
    assert rep["verdict"]["effect"] == "no significant gap", rep["verdict"]
