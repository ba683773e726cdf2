"""The report's PNGs: gap along the path, residuals before/after, hypothesis ranking."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from .modes import TruthMode


def plot_report(rep: dict, extra: dict, out: Path) -> None:
    items, prs, fit = extra["items"], extra["prs"], extra["fit"]
    from .diagnose import apply, classify
    from .fit import clear_bumps

    # 1. ranking
    rk = [r for r in rep["ranking"] if r["effect"] != "nominal"][:12]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.barh(
        [r["effect"] for r in rk][::-1],
        [max(r["dbic_vs_nominal"], 0.1) for r in rk][::-1],
        color=["C2" if r["effect"] == rep["verdict"]["best_candidate"] else "C0" for r in rk][::-1],
    )
    ax.set_xscale("log")
    ax.axvline(rep["thresholds"]["dbic_significant"], color="k", ls="--", lw=0.8)
    ax.set_xlabel("Delta BIC vs nominal model (higher = more evidence)")
    ax.set_title(f"Hypothesis ranking - verdict: {rep['verdict']['effect']}")
    fig.tight_layout()
    fig.savefig(out / "ranking.png", dpi=90)
    plt.close(fig)

    # 2. gap along the path (truth mode) or per run
    n = min(4, len(items))
    fig, axs = plt.subplots(n, 1, figsize=(8, 2.2 * n), squeeze=False)
    colors = {
        "straight": "C0",
        "turn": "C1",
        "arc": "C4",
        "acceleration": "C3",
        "stationary": "0.8",
    }
    P = apply(fit, prs) if rep["verdict"]["effect"] != "no significant gap" else {}
    for k in range(n):
        it, pr, ax = items[k], prs[k], axs[k, 0]
        if isinstance(it, TruthMode):
            clear_bumps([pr])
            tt, e0 = it.error_track({})
            P = apply(fit, [pr]) if rep["verdict"]["effect"] != "no significant gap" else {}
            _, e1 = it.error_track(P)
            clear_bumps([pr])
            d = np.interp(tt, pr.t, pr.S[:, 0].mean(axis=1)) / 1000.0
            lab = classify(pr, 0)
            lt = lab[np.clip(np.searchsorted(pr.t[1:], tt), 0, lab.size - 1)]
            g0 = np.hypot(e0[:, 0], e0[:, 1])
            ax.plot(d, g0, "k-", lw=1, label="nominal model")
            ax.plot(d, np.hypot(e1[:, 0], e1[:, 1]), "C2-", lw=1, label=f"+ {fit.name}")
            for s, c in colors.items():
                m = lt == s
                if m.any():
                    ax.scatter(d[m], np.zeros(m.sum()), s=2, color=c, label=s)
            for b in rep["where"][k].get("events", []):
                ax.axvline(b["at_wheel_travel_mm"] / 1000.0, color="C3", lw=0.6, ls=":")
            ax.set_ylabel("pos. gap (mm)")
        else:
            r0, r1 = it.residuals({}), it.residuals(P)
            ax.plot(np.abs(r0[:, 0]), "k.-", label="nominal")
            ax.plot(np.abs(r1[:, 0]), "C2.-", label=f"+ {fit.name}")
            ax.set_ylabel(it.channels()[0])
        ax.set_title(pr.run.name, fontsize=9)
        ax.legend(fontsize=6, ncol=4, loc="upper left")
    axs[-1, 0].set_xlabel("distance travelled (m)" if isinstance(items[0], TruthMode) else "window")
    fig.tight_layout()
    fig.savefig(out / "gap_along_path.png", dpi=90)
    plt.close(fig)

    # 3. residuals before/after (all runs pooled), per channel
    clear_bumps(prs)
    r0 = np.vstack([it.residuals({}) for it in items])
    P = apply(fit, prs) if rep["verdict"]["effect"] != "no significant gap" else {}
    r1 = np.vstack([it.residuals(P) for it in items])
    clear_bumps(prs)
    ch = items[0].channels()
    fig, axs = plt.subplots(1, len(ch), figsize=(2.6 * len(ch), 2.8), squeeze=False)
    for c in range(len(ch)):
        ax = axs[0, c]
        lim = np.percentile(np.abs(r0[:, c]), 99.5) or 1.0
        bins = np.linspace(-lim, lim, 41)
        ax.hist(r0[:, c], bins=bins, histtype="step", color="k", label="nominal")
        ax.hist(r1[:, c], bins=bins, histtype="step", color="C2", label="after")
        ax.set_title(ch[c], fontsize=8)
        ax.tick_params(labelsize=6)
    axs[0, 0].legend(fontsize=6)
    fig.suptitle("residuals before / after the verdict's effect", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "residuals.png", dpi=90)
    plt.close(fig)
