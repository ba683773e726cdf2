"""The report's PNGs: the hypothesis ranking on signed evidence, the gap along the held-out runs'
paths (nominal, with the verdict's effect, and the background band), residuals before/after."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from .bumps import clear_bumps
from .heldout import HELDOUT_BUMP_MIN_RUNS, apply
from .modes import TruthMode
from .where import classify

if TYPE_CHECKING:
    from .report import Context

DPI = 130
FONT = 9
PHASE_COLORS = {
    "straight": "C0",
    "turn": "C1",
    "arc": "C4",
    "acceleration": "C3",
    "stationary": "0.8",
}


def plot_report(rep: dict, ctx: Context, out: Path) -> None:
    plt.rcParams.update({"font.size": FONT, "legend.fontsize": FONT})
    plot_ranking(rep, out / "ranking.png")
    plot_gap_along_path(rep, ctx, out / "gap_along_path.png")
    plot_residuals(rep, ctx, out / "residuals.png")


def plot_ranking(rep: dict, path: Path) -> None:
    """Delta BIC against the nominal model, signed: a hypothesis worse than nominal shows as
    such (a symmetric-log axis, not a clamp)."""
    allr = [r for r in rep["ranking"] if r["effect"] != "nominal"]
    rk = allr[:12] + [r for r in allr[12:] if r["dbic_vs_nominal"] < 0][-4:]
    names = [r["effect"] for r in rk][::-1]
    vals = np.array([r["dbic_vs_nominal"] for r in rk][::-1])
    best = rep["verdict"]["best_hypothesis"]
    colors = [
        "C2" if n == best else ("C0" if v >= 0 else "C3") for n, v in zip(names, vals, strict=False)
    ]
    fig, ax = plt.subplots(figsize=(7.5, 0.35 * len(rk) + 1.6))
    ax.barh(names, vals, color=colors)
    ax.set_xscale("symlog", linthresh=10.0)
    thr = rep["thresholds"]["dbic_significant"]
    ax.axvline(thr, color="k", ls="--", lw=0.8, label=f"Delta BIC {thr:g} (significant)")
    ax.axvline(0.0, color="0.3", lw=0.8)
    ax.set_xlabel("Delta BIC vs the nominal model (fitting runs; > 0: more evidence, < 0: worse)")
    ax.set_title(f"Hypotheses, best first - verdict: {rep['verdict']['effect']}")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def plot_gap_along_path(rep: dict, ctx: Context, path: Path) -> None:
    """The held-out runs (at most four), each marked as such: position gap of truck A along the
    distance travelled, nominal vs with the verdict's effect, the background allowance as a
    band, the phases along the bottom and the located bumps."""
    items, prs = ctx.items, ctx.prs
    if rep["mode"] == "returns":
        plot_return_errors(rep, ctx, path)
        return
    held = list(ctx.held)[:4] or list(range(min(4, len(items))))
    fig, axs = plt.subplots(len(held), 1, figsize=(8.5, 2.5 * len(held) + 0.4), squeeze=False)
    name = ctx.fit.name if ctx.fit is not None else None
    for row, k in enumerate(held):
        it, pr, ax = items[k], prs[k], axs[row, 0]
        label = f"{pr.run.name} (held out)" if k in ctx.held else pr.run.name
        if isinstance(it, TruthMode):
            clear_bumps([pr])
            tt, e0 = it.error_track({})
            d = np.interp(tt, pr.t, pr.S[:, 0].mean(axis=1)) / 1000.0
            ax.plot(d, np.hypot(e0[:, 0], e0[:, 1]), "k-", lw=1.2, label="nominal model")
            if ctx.fit is not None:
                P = apply(ctx.fit, [pr], HELDOUT_BUMP_MIN_RUNS)
                _, e1 = it.error_track(P)
                clear_bumps([pr])
                ax.plot(d, np.hypot(e1[:, 0], e1[:, 1]), "C2-", lw=1.2, label=f"+ {name}")
            bmm = _background_track(rep, it, k, ctx)
            if bmm is not None:
                ax.fill_between(
                    bmm[0], 0, bmm[1], color="C1", alpha=0.15, label="background (2 sigma)"
                )
            lab = classify(pr)
            lt = lab[np.clip(np.searchsorted(pr.t[1:], tt), 0, lab.size - 1)]
            for s, c in PHASE_COLORS.items():
                m = lt == s
                if m.any():
                    ax.scatter(d[m], np.zeros(m.sum()), s=3, color=c, label=s)
            for b in _events(rep, pr.run.name):
                ax.axvline(b["at_wheel_travel_mm"] / 1000.0, color="C3", lw=0.7, ls=":")
            ax.set_ylabel("position gap (mm)")
        else:
            r0 = it.residuals({})
            P = apply(ctx.fit, [pr]) if ctx.fit is not None else {}
            r1 = it.residuals(P)
            clear_bumps([pr])
            ax.plot(np.abs(r0[:, 0]), "k.-", label="nominal model")
            ax.plot(np.abs(r1[:, 0]), "C2.-", label=f"+ {name}" if name else "nominal")
            ax.set_ylabel(it.channels()[0])
        ax.set_title(label)
        ax.legend(ncol=4, loc="upper left", framealpha=0.8)
    truth = isinstance(items[0], TruthMode)
    axs[-1, 0].set_xlabel("distance travelled (m)" if truth else "row")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def plot_return_errors(rep: dict, ctx: Context, path: Path) -> None:
    """Returns mode: each run's return position error (000 Eq. 3.1: true minus model) with the
    nominal model and with the verdict's effect; held-out runs filled, fitted runs hollow; the
    runs' own spread (the background) as a circle."""
    items, prs = ctx.items, ctx.prs
    P = apply(ctx.fit, prs) if ctx.fit is not None else {}
    r0 = np.vstack([it.residuals({}) for it in items])
    r1 = np.vstack([it.residuals(P) for it in items])
    clear_bumps(prs)
    held = set(ctx.held)
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    for k, pr in enumerate(prs):
        ho = k in held
        kw = {"s": 45 if ho else 30, "zorder": 3}
        ax.scatter(r0[k, 0], r0[k, 1], c="k" if ho else "none", edgecolors="k", marker="s", **kw)
        ax.scatter(r1[k, 0], r1[k, 1], c="C2" if ho else "none", edgecolors="C2", marker="o", **kw)
        ax.plot([r0[k, 0], r1[k, 0]], [r0[k, 1], r1[k, 1]], color="0.7", lw=0.6, zorder=1)
        if ho:
            ax.annotate(
                pr.run.name,
                (r0[k, 0], r0[k, 1]),
                fontsize=8,
                xytext=(4, 4),
                textcoords="offset points",
            )
    sp = rep["background"].get("return_spread", {})
    if sp:
        rad = float(np.hypot(sp.get("x_mm", 0.0), sp.get("y_mm", 0.0)))
        ax.add_patch(plt.Circle((0, 0), rad, color="C1", alpha=0.2, label="background (spread)"))
    ax.scatter([], [], c="k", marker="s", label="nominal model (filled: held out)")
    name = ctx.fit.name if ctx.fit is not None else "nominal"
    ax.scatter([], [], c="C2", marker="o", label=f"with {name} (filled: held out)")
    ax.axhline(0, color="0.5", lw=0.6)
    ax.axvline(0, color="0.5", lw=0.6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("return error x (mm, true minus model)")
    ax.set_ylabel("return error y (mm)")
    ax.set_title(f"Return errors per run - verdict: {rep['verdict']['effect']}")
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def _events(rep: dict, run: str) -> list:
    for w in rep["where"]:
        if w["run"] == run:
            return w.get("events", [])
    return []


def _background_track(rep: dict, it: TruthMode, k: int, ctx: Context):
    """(distance m, allowance mm) along a run: 2 x the background's RMS at each window start."""
    rk = ctx.ranking
    if rk is None:
        return None
    from .background import Background

    q = rep["background"].get("walk_q_wheel_mm2_per_mm")
    if q is None:
        return None
    b = rep["background"]
    bg = Background("truth", list(q), list(b.get("walk_q_turn_mm2_per_mm", q)))
    bg.q_long = list(b.get("walk_q_long_mm2_per_mm", []))
    tv = bg.track_var(it, 0)
    s = rep["noise_sigma"]["A.longitudinal_mm"] / np.sqrt(2.0)
    allow = 2.0 * np.sqrt(tv[:, 0] + tv[:, 1] + 2 * s * s)
    pr = it.pr
    d = np.interp(it.tt[it.i], pr.t, pr.S[:, 0].mean(axis=1)) / 1000.0
    return d, allow


def plot_residuals(rep: dict, ctx: Context, path: Path) -> None:
    items, prs = ctx.items, ctx.prs
    clear_bumps(prs)
    r0 = np.vstack([it.residuals({}) for it in items])
    P = apply(ctx.fit, prs) if ctx.fit is not None else {}
    r1 = np.vstack([it.residuals(P) for it in items])
    clear_bumps(prs)
    ch = items[0].channels()
    fig, axs = plt.subplots(1, len(ch), figsize=(2.9 * len(ch), 3.2), squeeze=False)
    for c in range(len(ch)):
        ax = axs[0, c]
        lim = np.percentile(np.abs(r0[:, c]), 99.5) or 1.0
        bins = np.linspace(-lim, lim, 41)
        ax.hist(r0[:, c], bins=bins, histtype="step", color="k", label="nominal")
        ax.hist(r1[:, c], bins=bins, histtype="step", color="C2", label="with the verdict")
        ax.set_title(ch[c])
    axs[0, 0].legend()
    fig.suptitle("residuals of every run, before / after the verdict's effect")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
