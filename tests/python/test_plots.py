"""The PNGs a person reads (odo-plot-umbmark, odo-plot-demo, odo-plot-realdata; issue 17 item 7):
>= 120 dpi, legends >= 9 pt, units on every axis, and what is small at the path's scale shown at
its own scale: the UMBmark "after" cluster (000 Fig. 6.5) in a panel of its own, the real runs'
ends in an inset.

Inputs are made here from closed-form shapes (clusters at known centres, a square path), not by
the tools under test.
"""

import csv
import math
import re
from pathlib import Path

import numpy as np
import pytest
from odo_tools import plot_demo, realdata_plot, umbmark_plot
from odo_tools.plotstyle import DPI
from PIL import Image

UNIT = re.compile(r"[\[(](mm|m|s|deg)[\])]")
RNG = np.random.default_rng(17)


def legends(fig):
    out = list(fig.legends)
    for ax in fig.axes:
        if ax.get_legend() is not None:
            out.append(ax.get_legend())
    return out


def check_style(fig, png: Path) -> None:
    assert legends(fig), "a legend"
    for lg in legends(fig):
        for t in lg.get_texts():
            assert t.get_fontsize() >= 9, f"legend text {t.get_text()!r} at {t.get_fontsize()} pt"
    for ax in fig.axes:
        assert UNIT.search(ax.get_xlabel()), f"x axis without a unit: {ax.get_xlabel()!r}"
        assert UNIT.search(ax.get_ylabel()), f"y axis without a unit: {ax.get_ylabel()!r}"
    with Image.open(png) as im:
        dpi = im.info["dpi"][0]
        w, h = im.size
    assert DPI >= 120 and round(dpi) == DPI
    fw, fh = fig.get_size_inches()
    assert abs(w - fw * DPI) <= 2 and abs(h - fh * DPI) <= 2


def write_returns(path: Path, cw_cg, ccw_cg, spread: float, n: int = 5) -> dict:
    pts = {}
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(umbmark_plot.COLUMNS)
        for d, cg in (("cw", cw_cg), ("ccw", ccw_cg)):
            e = np.asarray(cg) + RNG.normal(0, spread, (n, 2))
            pts[d] = e
            for i, (ex, ey) in enumerate(e, 1):
                # x_abs - x_calc = ex: put the calculated pose at the origin
                w.writerow([i, d, f"{ex:.3f}", f"{ey:.3f}", "0.5", "0", "0", "0"])
    return pts


@pytest.fixture()
def returns(tmp_path):
    # 000 Table III sizes: uncalibrated clusters some 300 mm out, calibrated ones ~20 times closer
    before = write_returns(tmp_path / "before.csv", (228, 209), (-51, 52), 8.0)
    after = write_returns(tmp_path / "after.csv", (3, -2), (-12, 7), 4.0)
    return tmp_path, before, after


def test_umbmark_after_cluster_gets_its_own_scale(returns, tmp_path):
    d, _, after = returns
    png = tmp_path / "u.png"
    assert (
        umbmark_plot.main(
            ["--before", str(d / "before.csv"), "--after", str(d / "after.csv"), "--out", str(png)]
        )
        == 0
    )
    fig = umbmark_plot.figure(
        umbmark_plot.read_returns(d / "before.csv"), umbmark_plot.read_returns(d / "after.csv"), "t"
    )
    check_style(fig, png)
    assert len(fig.axes) == 3
    zoom = fig.axes[2]
    pts = np.vstack([after["cw"], after["ccw"]])
    (x0, x1), (y0, y1) = zoom.get_xlim(), zoom.get_ylim()
    assert (pts[:, 0] > x0).all() and (pts[:, 0] < x1).all()
    assert (pts[:, 1] > y0).all() and (pts[:, 1] < y1).all()
    assert x0 < 0 < x1 and y0 < 0 < y1, "the origin, the calibration's target, stays in view"
    span = max(np.ptp(np.append(pts[:, 0], 0)), np.ptp(np.append(pts[:, 1], 0)))
    assert span >= 0.6 * max(x1 - x0, y1 - y0), "the cluster fills the zoomed panel"
    # on one scale (middle panel) the same cluster is a speck: the reason for the zoom
    (bx0, bx1), _ = fig.axes[1].get_xlim(), fig.axes[1].get_ylim()
    assert span < 0.2 * (bx1 - bx0)


def test_umbmark_before_only_is_one_panel(returns, tmp_path):
    d, _, _ = returns
    png = tmp_path / "u1.png"
    assert umbmark_plot.main(["--before", str(d / "before.csv"), "--out", str(png)]) == 0
    fig = umbmark_plot.figure(umbmark_plot.read_returns(d / "before.csv"), None, "t")
    assert len(fig.axes) == 1
    check_style(fig, png)


def square_pose(path: Path, side_mm: float, drift_deg: float) -> tuple[float, float]:
    """A square whose true heading drifts by drift_deg per corner; returns the true end offset."""
    rows, x, y, th = [], 0.0, 0.0, 0.0
    tx, ty, tth = 0.0, 0.0, 0.0
    t = 0.0
    for _leg in range(4):
        for _ in range(100):
            x += side_mm / 100 * math.cos(th)
            y += side_mm / 100 * math.sin(th)
            tx += side_mm / 100 * math.cos(tth)
            ty += side_mm / 100 * math.sin(tth)
            t += 0.04
            rows.append((t, x, y, math.degrees(th), tx, ty, math.degrees(tth)))
        th += math.pi / 2
        tth += math.pi / 2 + math.radians(drift_deg)
    with path.open("w") as f:
        f.write("t_s,x_mm,y_mm,theta_deg,true_x_mm,true_y_mm,true_theta_deg\n")
        for r in rows:
            f.write(",".join(f"{v:.4f}" for v in r) + "\n")
    return tx - x, ty - y


def test_demo_square(tmp_path):
    e_cw = square_pose(tmp_path / "cw.csv", 4000, 1.0)
    square_pose(tmp_path / "ccw.csv", 4000, -0.2)
    png = tmp_path / "square.png"
    assert (
        plot_demo.main(
            [
                "--run",
                f"cw={tmp_path / 'cw.csv'}",
                "--run",
                f"ccw={tmp_path / 'ccw.csv'}",
                "--out",
                str(png),
            ]
        )
        == 0
    )
    fig = plot_demo.figure({"cw": tmp_path / "cw.csv", "ccw": tmp_path / "ccw.csv"})
    check_style(fig, png)
    err = fig.axes[1]
    (x0, x1), (y0, y1) = err.get_xlim(), err.get_ylim()
    assert x0 < e_cw[0] < x1 and y0 < e_cw[1] < y1


def test_realdata_end_is_zoomed(tmp_path):
    t = np.arange(0, 60, 0.05)
    # truth: a 700 mm square-ish loop from a start pose away from the origin; the firmware's
    # tracks (in their own frame, from the origin) end 30 mm and 3 mm off
    ang = 2 * np.pi * t / t[-1]
    tx, ty = 350 * np.sin(ang), 350 * (1 - np.cos(ang))
    th = np.degrees(np.unwrap(np.arctan2(np.gradient(ty), np.gradient(tx))))
    with (tmp_path / "run.truth.csv").open("w") as f:
        f.write("t_s,a_x_mm,a_y_mm,a_theta_deg\n")
        for r in zip(t, tx + 100, ty - 50, th, strict=True):
            f.write(",".join(f"{v:.4f}" for v in r) + "\n")
    for name, off in (("before", 30.0), ("after", 3.0)):
        k = np.linspace(0, 1, t.size)
        c, s = math.cos(-math.radians(th[0])), math.sin(-math.radians(th[0]))
        x, y = c * tx - s * ty + off * k, s * tx + c * ty
        d = tmp_path / name
        d.mkdir()
        with (d / "poses.csv").open("w") as f:
            f.write("tick,t_s,x_a_mm,y_a_mm,theta_a_deg\n")
            for i in range(t.size):
                f.write(f"{i},{t[i]:.3f},{x[i]:.4f},{y[i]:.4f},0\n")
    spec = (
        f"loop={tmp_path / 'run.truth.csv'},{tmp_path / 'before/poses.csv'},"
        f"{tmp_path / 'after/poses.csv'}"
    )
    png = tmp_path / "heldout.png"
    assert realdata_plot.main(["--run", spec, "--out", str(png)]) == 0
    fig = realdata_plot.figure(
        [
            (
                "loop",
                tmp_path / "run.truth.csv",
                tmp_path / "before/poses.csv",
                tmp_path / "after/poses.csv",
            )
        ]
    )
    check_style(fig, png)
    insets = [c for c in fig.axes[0].child_axes]
    assert len(insets) == 1
    (x0, x1), (y0, y1) = insets[0].get_xlim(), insets[0].get_ylim()
    xe, ye = tx[-1] + 100, ty[-1] - 50
    assert x0 < xe < x1 and y0 < ye < y1
    assert x1 - x0 < 0.15 * 700, "the inset is at the ends' scale, not the path's"
    assert x1 - x0 > 2 * 30 * 0.9, "both ends (30 mm apart) fit"
