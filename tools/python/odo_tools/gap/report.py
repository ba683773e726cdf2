"""The diagnosis report: typed parts, report.json (every number), report.md (plain words with
units, links to the plots, the next step), written by the project's output rule (outpath.py)."""

from __future__ import annotations

import json
import math
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import catalog
from .background import heading_walk_deg_per_sqrt_m, spot_turn_deg
from .fit import DBIC_PAIR, DBIC_SIGNIFICANT, Z_GAP
from .heldout import POOLED
from .stability import STABLE_Z
from .verdict import THRESHOLDS

if TYPE_CHECKING:  # only for type hints: diagnose imports this module
    from .diagnose import Dataset, Judgement, Ranking
    from .fit import Fit
    from .select import Selection

# plain words for each family (the verdict names physics, not codes)
WORDS = {
    "ed": "unequal wheel diameters (Ed)",
    "eb": "wheelbase error (Eb)",
    "es": "scale error: mean wheel diameter (Es)",
    "bumps": "discrete bumps on the floor",
    "roughness": "floor roughness",
    "slip": "longitudinal wheel slip under acceleration",
    "skid": "lateral skid in fast turns",
    "count_loss": "encoder count loss at high wheel speed",
    "rotary_bias": "linkage rotary encoder zero offset",
    "link_bias": "link-length encoder bias",
    "tire_compression": "load-dependent tyre radius",
    "scrub": "turn-radius-dependent wheelbase (tyre scrub)",
}
LAW_WORDS = {
    "catalog": "the catalog's law",
    "accel": "slip fraction a power of the wheel's acceleration above a threshold, "
    "one grip per tyre",
    "traction": "traction (torque) saturation: the floor speed changes by at most what the "
    "friction circle of a_max leaves beside the turn",
    "motor": "traction saturation inside the tick: the motor takes each tick's speed with a lag "
    "tau, and the floor follows it by at most a_max",
    "speed": "a fraction of the counts lost above a wheel speed",
    "growth": "one tyre's rolling radius grows with the square of its speed, beside a fixed Ed",
    "flagged": "the wheel decoders' own word: each wheel tick they flagged with a skipped "
    "quadrature state lost this many counts (one skipped state: 2)",
    "missed": "edges missed with a probability that rises with the edge rate and saturates, as "
    "often as the decoders' flags show at each rate; a flagged tick lost two counts per state "
    "it skipped (scale: where the probability saturates, x the flags' own reading)",
    "plateau": "a count-rate ceiling: the counts sit on a flat top while the hidden wheel speed "
    "rises beyond it and back",
    "cornering": "linear cornering stiffness: the tyres run at a slip angle proportional to the "
    "centripetal acceleration, from the gentlest arc up (no threshold)",
    "load": "a wheelbase that grows with the lateral load (speed squared over radius): "
    "Eb (1 + zeta |a_lat| / g)",
    "friction": "friction circle: the truck's centre changes its velocity by at most a_lim; "
    "beyond it (fast turns) the centre falls behind the wheels' path while the heading follows",
    "eccentric": "a joint encoder's offset that varies once per turn of its shaft (a disc "
    "mounted off centre): b0 + s sin(angle) + c (cos(angle) - 1)",
    "offset": "a link-length encoder whose ends sit off the pivots: b0 + s sin(angle) + "
    "c (cos(angle) - 1) at each joint, the offsets' projection on the link",
}
# effects a parameter block corrects (odo-calib): what a next step can fix on the robot
KINEMATIC = ("ed", "eb", "es", "scrub")
SPECIAL = ("no significant gap", "unexplained")


def _judged_on(hd: dict) -> str:
    """Where one linkage channel was judged on its own (heldout._judged_channel): which."""
    on = hd["judged_on"]
    return "" if on == POOLED else f" (`{on}` on its own before)"


def words(label: str) -> str:
    if label in SPECIAL or label == "nominal":
        return label
    return " + ".join(WORDS.get(f, f) for f in label.split("+"))


def unit(key: str) -> str:
    if key.endswith((".A", ".B")):
        key = key[:-2]
    fam, p = key.split(".", 1)
    fam = fam.split("@")[0]
    try:
        u = catalog.param(f"{fam}.{p}")["unit"]
    except (KeyError, StopIteration):
        u = {
            "tau_s": "s",
            "k_per_m_s2": "1/(m/s^2)",
            "a0_m_s2": "m/s^2",
            "a_max_m_s2": "m/s^2",
            "k_per_m_s": "1/(m/s)",
            "g_per_m2_s2": "1/(m/s)^2",
            "v0_mm_s": "mm/s",
            "deg_per_m_s2": "deg/(m/s^2)",
            "excess_mm_s": "mm/s",
            "a_m_s2": "m/s^2",
            "a_lim_m_s2": "m/s^2",
            "zeta": "1",
            "exponent": "1",
            "counts": "counts per flagged tick",
        }.get(p, "")
        if p.endswith("_deg"):  # the once-per-turn terms of a joint encoder's offset
            u = "deg"
        elif p.endswith("_mm"):  # a link encoder's ends off the pivots
            u = "mm"
    return "" if u in ("1", "-") else u


@dataclass
class Context:
    """What the plots need beyond the JSON: the per-run evidence and the verdict's fit."""

    items: list
    prs: list
    fit: Fit | None
    held: list[int]
    ranking: Ranking | None = None


@dataclass
class Report:
    tool: str
    real: list[str]
    robot: str
    mode: str
    vehicle: str
    runs: list[str]
    fit_runs: list[str]
    heldout_runs: list[str]
    selection: str
    in_sample: bool
    return_accuracy: list[float] | None
    instrument: dict
    noise_sigma: dict
    thresholds: dict
    nominal_fit_z: float | None
    background: dict
    verdict: dict
    runner_up: dict | None
    ranking: list[dict]
    proposals: dict
    phases: dict
    heldout: dict
    stability: dict
    where: list[dict]
    unidentifiable: list[dict]
    next_step: list[str]
    evidence_measure: str = "BIC = -2 ln L (Gaussian, per-channel sigma from the data) + k ln n"
    gap_definition: str = ""
    gap_metric_mm: str = ""
    elapsed_s: float = 0.0
    context: Context | None = field(default=None, repr=False)

    # flat figures kept for scripts (the blind check reads them)
    @property
    def shrink(self) -> float:
        return self.heldout["shrink"]

    def __getitem__(self, key: str):
        """report["verdict"] as in report.json (scripts and tests read it like the file)."""
        return self.to_dict()[key]

    def to_dict(self) -> dict:
        d = asdict(self) if self.context is None else asdict(_without_context(self))
        d.pop("context", None)
        h = self.heldout
        d.update(
            gap_before=h["gap_before"],
            gap_after_heldout=h["gap_after"],
            shrink=h["shrink"],
            shrink_ci=h["shrink_ci"],
            gap_before_mm=h["mm_before"],
            gap_after_heldout_mm=h["mm_after"],
            gap_before_runs_mm=[g["mm"] for g in h["before"]],
            gap_after_runs_mm=[g["mm"] for g in h["after"]],
            shrink_mm=h["mm_before"] / max(h["mm_after"], 1e-9),
            elapsed_s=self.elapsed_s,
        )
        return d

    @classmethod
    def build(
        cls,
        ds: Dataset,
        sel: Selection,
        rk: Ranking,
        jd: Judgement,
        where: list[dict],
        group_fits: list,
        findings: list,
    ) -> Report:
        chans = ds.items[0].channels()
        best = rk.best
        held = jd.held
        inst = {}
        if ds.instrument is not None:
            inst = {
                "lever_arm_mm": [list(x) for x in ds.instrument.lever_mm[: ds.robot.n_trucks]],
                "lever_arm_se_mm": [
                    list(x) for x in ds.instrument.lever_se_mm[: ds.robot.n_trucks]
                ],
                "latency_s": dict(ds.instrument.latency_s),
                "heading_offset_deg": [
                    math.degrees(x) for x in ds.instrument.heading_offset_rad[: ds.robot.n_trucks]
                ],
                "notes": list(ds.notes),
                "clock_rate": asdict(ds.clock) if ds.clock is not None else None,
            }
        bg = jd.background
        bgd: dict[str, Any] = {"mode": ds.mode}
        if bg.q_wheel:
            bgd["walk_q_wheel_mm2_per_mm"] = bg.q_wheel
            bgd["walk_q_wheel_68ci"] = [list(x) for x in bg.q_wheel_ci]
            bgd["walk_q_turn_mm2_per_mm"] = bg.q_turn
            bgd["walk_q_turn_68ci"] = [list(x) for x in bg.q_turn_ci]
            bgd["walk_q_long_mm2_per_mm"] = bg.q_long
            bgd["walk_q_with_repeatable_part"] = [list(x) for x in bg.q_all]
            bgd["heading_walk_deg_per_m"] = [
                heading_walk_deg_per_sqrt_m(q, ds.prs[0].b[t]) for t, q in enumerate(bg.q_wheel)
            ]
            bgd["heading_per_spot_turn_deg"] = [
                spot_turn_deg(q, ds.prs[0].b[t]) for t, q in enumerate(bg.q_turn)
            ]
        if bg.spread is not None:
            bgd["return_spread"] = dict(zip(chans, map(float, bg.spread), strict=False))
        if ds.mode == "truth":
            bgd["count_heading_mrad"] = [
                1e3 * c / b for c, b in zip(ds.prs[0].count_mm, ds.prs[0].b, strict=False)
            ]
        bgd["heldout_allowance_mm"] = held.bg_mm
        bgd["heldout_allowance_deg"] = held.bg_deg
        named = jd.verdict not in SPECIAL
        laws = {}
        if best.hyp is not None:
            for law in best.hyp.laws:
                laws[law.family] = {
                    "law": law.name,
                    "in_words": LAW_WORDS.get(law.name, law.doc),
                    "params": {k: best.params.get(k) for k in law.params},
                }
        verdict = {
            "effect": jd.verdict,
            "in_words": words(jd.verdict),
            "best_candidate": best.label,
            "best_hypothesis": best.name,
            "laws": laws,
            "params": _clean(best.params),
            "stderr": _clean(best.stderr),
            "units": {k: unit(k) for k in best.params},
            "reason": jd.reason,
            "evidence": {
                "bic": best.bic,
                "dbic_vs_nominal": jd.dbic,
                "k": best.k,
                "n": best.n,
                "overdispersion": rk.c_hat,
                "heldout_ratio_before": held.ratio_before,
                "heldout_ratio_after": held.ratio_after,
                # truth, a weak held-out gap: the fitting runs' tracks, nominal (verdict.py)
                "fit_track_ratio_nominal": held.extra.get("fit_track_ratio_nominal"),
            },
            "bumps": best.bumps,
        }
        runner = next((f for f in rk.cands if f.name != best.name), None)
        hd = {
            "runs": held.runs,
            "before": [asdict(g) for g in held.before],
            "after": [asdict(g) for g in held.after],
            "background_mm": held.background_mm,
            "background_deg": held.background_deg,
            "mm_before": held.mm_before,
            "mm_after": held.mm_after,
            "return_mm_before": held.end_mm_before,
            "return_mm_after": held.end_mm_after,
            "deg_before": held.deg_before,
            "deg_after": held.deg_after,
            "ratio_before": held.ratio_before,
            "ratio_after": held.ratio_after,
            # a linkage channel judged on its own (heldout._judged_channel), or the pool
            "judged_on": held.extra.get("judged_on", POOLED),
            "gap_before": held.gap_before,
            "gap_after": held.gap_after,
            "shrink": held.shrink,
            "shrink_ci": list(held.shrink_ci),
            "after_model": best.name if named else "nominal",
        }
        stab = {
            "groups": [asdict(g) for g in group_fits],
            "findings": [asdict(f) for f in findings],
        }
        unident = [
            {"what": k, "why": v}
            for k, v in catalog.not_identifiable(ds.mode, ds.robot.vehicle).items()
        ]
        unident += [{"what": WORDS.get(k, k), "why": v} for k, v in rk.unseen.items()]
        for k, se in best.stderr.items():
            v = best.params.get(k, 0.0)
            ref = abs(v - 1.0) if k.endswith(".value") else abs(v)
            if se and math.isfinite(se) and ref > 0 and se > 0.5 * ref:
                unident.append(
                    {"what": k, "why": f"fitted {v:.4g} +- {se:.2g}: not fixed by these runs"}
                )
        if ds.mode == "returns" and ds.return_accuracy is None:
            unident.append(
                {
                    "what": "roughness vs eb",
                    "why": "without the return measurement's accuracy (--return-accuracy) the "
                    "returns' spread is the noise, and roughness's mean shortens every turn "
                    "like an Eb",
                }
            )
        if ds.mode == "returns":
            unident.append(
                {
                    "what": "ed vs slip vs encoder bias",
                    "why": "return errors of one path excite them alike unless the paths differ",
                }
            )
        rep = cls(
            tool="odo-gap diagnose",
            real=[str(p) for p in ds.real],
            robot=ds.robot_path,
            mode=ds.mode,
            vehicle=ds.robot.vehicle,
            runs=[r.name for r in ds.runs],
            fit_runs=[ds.runs[i].name for i in sel.fit],
            heldout_runs=[ds.runs[i].name for i in sel.held],
            selection=sel.how,
            in_sample=sel.in_sample,
            return_accuracy=list(ds.return_accuracy) if ds.return_accuracy else None,
            instrument=inst,
            noise_sigma=dict(zip(chans, map(float, rk.prob.sigma), strict=False)),
            thresholds={
                "dbic_significant": DBIC_SIGNIFICANT,
                "dbic_pair": DBIC_PAIR,
                "z_gap": Z_GAP,
                **THRESHOLDS,
            },
            nominal_fit_z=rk.gof,
            background=bgd,
            verdict=verdict,
            runner_up=None
            if runner is None
            else {
                "effect": runner.name,
                "in_words": words(runner.label),
                "params": _clean(runner.params),
                "bic": runner.bic,
                "margin_dbic": runner.bic - best.bic,
            },
            ranking=[
                {
                    "effect": f.name,
                    "in_words": words(f.label),
                    "bic": f.bic,
                    "dbic_vs_nominal": rk.null.bic - f.bic,
                    "k": f.k,
                    "params": _clean(f.params),
                }
                for f in [*rk.cands, rk.null]
            ],
            proposals=dict(rk.proposals),
            phases={k: list(v) for k, v in rk.phases.items()},
            heldout=hd,
            stability=stab,
            where=where,
            unidentifiable=unident,
            next_step=next_step(ds, sel, jd.verdict, best, findings),
            gap_definition="misfit ratio R = sqrt(mean z^2) over the held-out runs' standardised "
            "residuals z = error / sqrt(truth noise + background variance) (truth: each truck's "
            "accumulated x, y, heading error once per window, and the linkage readings; returns, "
            "linkage: the mode's residuals): 1 = nothing but background. Systematic gap "
            "G = sqrt(max(R^2 - 1, 2 sqrt(2/n))); shrink = G before / G after",
            gap_metric_mm={
                "truth": "RMS position error of truck A along the run (mm)",
                "returns": "return position error (mm)",
                "linkage": "RMS linkage prediction error over 1 s horizons (mm)",
            }[ds.mode],
        )
        return rep


def _without_context(rep: Report) -> Report:
    from dataclasses import replace

    return replace(rep, context=None)


def _clean(d: dict) -> dict:
    return {k: float(v) for k, v in d.items()}


def next_step(ds: Dataset, sel: Selection, verdict: str, best: Fit, findings: list) -> list[str]:
    """What a user does next, as commands where the project has them."""
    real = " ".join(str(p) for p in ds.real)
    fams = verdict.split("+") if verdict not in SPECIAL else []
    kin = [f for f in fams if f in KINEMATIC]
    scrub_found = any("scrub.k" in getattr(f, "implies", {}) for f in findings)
    out = []
    if kin or scrub_found:
        effects = sorted(set(kin) | ({"scrub"} if scrub_found else set()))
        vals = ", ".join(
            f"{k} {best.params[k]:.5g}" for k in best.params if k.split(".")[0] in effects
        )
        out.append(
            f"correct {words('+'.join(effects))} in the parameter block ({vals}): "
            f"odo-calib fit --runs {real} --robot {ds.robot_path} --free "
            f"{','.join(effects)} --out-params calibrated.json, then odo-calib write --image "
            "build/cm4/bin/odo_image.elf --params calibrated.json --out fw.elf"
        )
    other = [f for f in fams if f not in KINEMATIC]
    for f in other:
        out.append(
            {
                "bumps": "the bumps are located in report.json (verdict.bumps: x, y, wheel); a "
                "robot with linkage encoders corrects them on line (IPEC, --ipec estimator)",
                "roughness": "a rough floor is a noise, not a bias: no calibration removes it; "
                "judge runs against the background allowance this report gives",
                "slip": "lower the acceleration limits of the path controller (slip lives in "
                "the accelerating phases) or raise traction",
                "skid": "lower the speed in turns (the centripetal acceleration drives it)",
                "count_loss": "check the decoder's count rate against the top wheel speed "
                "(counts are lost above the fitted speed)",
                "rotary_bias": "odo-ipec selfcal-link estimates the encoder offsets into a "
                "params JSON for odo-calib write",
                "link_bias": "odo-ipec selfcal-link estimates the link-length bias into a params "
                "JSON for odo-calib write",
            }.get(f, f"model {f}")
        )
    if verdict == "unexplained" and ds.clock is not None and ds.clock.drifting():
        out.append(
            "stamp the truth with the robot's clock (or scale its time by "
            f"{1.0 - ds.clock.ppm * 1e-6:.6f} from each run's start) and diagnose again: a "
            "truth that drifts against the counts is compared with the wrong wheel counts"
        )
    elif verdict == "unexplained":
        out.append(
            "no catalog effect closes the gap: look at gap_along_path.png and the 'where' table "
            "for the phase that carries it, and record runs that isolate it"
        )
    if verdict == "no significant gap":
        out.append("nothing to correct beyond the background this report measures")
    return out


def fmt(v: float, se: float | None = None) -> str:
    s = f"{v:.5g}"
    if se is not None and math.isfinite(se):
        s += f" +- {se:.2g}"
    return s


def markdown(rep: dict) -> str:
    v = rep["verdict"]
    hd = rep["heldout"]
    bg = rep["background"]
    L = [
        f"# odo-gap diagnosis: {', '.join(rep['real'])}",
        "",
        f"Evidence: **{rep['mode']}** ({rep['vehicle']}), {len(rep['runs'])} runs: fitted on "
        f"{len(rep['fit_runs'])}, judged on {len(rep['heldout_runs'])} held out "
        f"({rep['selection']}).",
        "",
        f"## Verdict: **{v['effect']}**",
        "",
    ]
    if v["effect"] not in SPECIAL:
        L.append(f"In words: **{v['in_words']}**.")
    L.append(v["reason"] + ".")
    if v["effect"] != v["best_candidate"]:
        L.append(f"Best candidate: {v['best_candidate']} ({words(v['best_candidate'])}).")
    L += ["", "| parameter | fitted | +- | unit |", "|---|---|---|---|"]
    for k, x in v["params"].items():
        se = v["stderr"].get(k, float("nan"))
        L.append(f"| {k} | {x:.6g} | {se:.2g} | {v['units'].get(k, '')} |")
    for fam, law in v["laws"].items():
        if law["law"] != "catalog":
            L.append("")
            L.append(f"Fitted law for {WORDS.get(fam, fam)}: {law['in_words']}.")
    if rep["runner_up"]:
        r = rep["runner_up"]
        L.append("")
        L.append(f"Runner-up: {r['effect']} ({r['in_words']}), BIC {r['margin_dbic']:.1f} behind.")
    L += [
        "",
        "## Held-out runs: how far it shrinks, and what is left",
        "",
        f"Judged on {', '.join(hd['runs'])}"
        + (" (in-sample: no run could be held out)" if rep["in_sample"] else "")
        + ".",
        "",
        "| | nominal model | with the verdict's effect | background alone |",
        "|---|---|---|---|",
        f"| {rep['gap_metric_mm']} | {hd['mm_before']:.2f} mm | {hd['mm_after']:.2f} mm | "
        f"{bg['heldout_allowance_mm']:.2f} mm |",
        f"| heading error | {hd['deg_before']:.3f} deg | {hd['deg_after']:.3f} deg | "
        f"{bg['heldout_allowance_deg']:.3f} deg |",
        *(
            [
                f"| return error (position at the end of the run) | {hd['return_mm_before']:.2f}"
                f" mm | {hd['return_mm_after']:.2f} mm | |"
            ]
            if rep["mode"] == "truth"
            else []
        ),
        f"| misfit in units of the background{_judged_on(hd)} | {hd['ratio_before']:.2f} | "
        f"{hd['ratio_after']:.2f} | 1 |",
        "",
        f"Shrink of the systematic gap (above the background): x{hd['shrink']:.1f} (95 % CI "
        f"{hd['shrink_ci'][0]:.1f} - {hd['shrink_ci'][1]:.1f}); of the error in mm: "
        f"x{hd['mm_before'] / max(hd['mm_after'], 1e-9):.1f}.",
        "",
        "| run | nominal (mm) | after (mm) | background (mm) | return error (mm) |",
        "|---|---|---|---|---|",
    ]
    for b, a, m in zip(hd["before"], hd["after"], hd["background_mm"], strict=False):
        L.append(
            f"| {b['run']} | {b['mm']:.2f} | {a['mm']:.2f} | {m:.2f} | {b['end_mm']:.2f} -> "
            f"{a['end_mm']:.2f} |"
        )
    L += ["", "What the remainder looks like: " + _remainder(rep) + ".", ""]
    L += ["![gap along the path](gap_along_path.png)", ""]
    fs = rep["stability"]["findings"]
    L += ["## Parameters across groups", ""]
    if fs:
        for f in fs[:6]:
            L.append(f"- {f['text']}.")
    else:
        L.append(
            "No parameter differs between shapes, sessions, directions or groups beyond "
            f"{STABLE_Z:g} standard errors."
        )
    if rep["stability"]["groups"]:
        L += ["", "| kind | group | runs | " + " | ".join(_stab_keys(rep)) + " |"]
        L.append("|---|---|---|" + "---|" * len(_stab_keys(rep)))
        for g in rep["stability"]["groups"]:
            vals = " | ".join(
                fmt(g["params"][k], g["stderr"].get(k)) if k in g["params"] else ""
                for k in _stab_keys(rep)
            )
            L.append(f"| {g['kind']} | {g['group']} | {len(g['runs'])} | {vals} |")
    L += ["", "## Next step", ""]
    L += [f"- {s}" for s in rep["next_step"]]
    L += [
        "",
        "## Ranking (fitting runs)",
        "",
        "![ranking](ranking.png)",
        "",
        "| hypothesis | in words | Delta BIC vs nominal | k |",
        "|---|---|---|---|",
    ]
    for r in rep["ranking"][:12]:
        L.append(f"| {r['effect']} | {r['in_words']} | {r['dbic_vs_nominal']:.1f} | {r['k']} |")
    if rep["proposals"]:
        L += ["", "Proposed by where the residual lives (other laws tested):"]
        L += [f"- {WORDS.get(k, k)}: {why}" for k, why in rep["proposals"].items()]
    L += ["", "## Where", "", "![residuals](residuals.png)", ""]
    for w in rep["where"]:
        ch = max(w["channels"], key=w["channels"].get)
        s = f"- {w['run']}: mostly in {ch} ({w['channels'][ch]:.0%})"
        if "segments" in w:
            sg = max(w["segments"], key=w["segments"].get)
            s += f", during {sg} ({w['segments'][sg]:.0%}); end error {w['gap_end_mm']:.1f} mm"
        if w.get("events"):
            s += f"; {len(w['events'])} bump(s): " + ", ".join(
                f"{x['wheel']} at {x['at_wheel_travel_mm']:.0f} mm "
                f"({x['x_mm']:.0f}, {x['y_mm']:.0f})"
                for x in w["events"][:5]
            )
        L.append(s)
    inst = rep["instrument"]
    if inst:
        L += ["", "## Truth instrument (nuisances, fitted before any effect)", ""]
        for t, (o, se) in enumerate(
            zip(inst["lever_arm_mm"], inst["lever_arm_se_mm"], strict=False)
        ):
            L.append(
                f"- truck {'AB'[t]}: tracked point {o[0]:.1f} mm forward, {o[1]:.1f} mm left of "
                f"the axle centre (+- {se[0]:.1f}, {se[1]:.1f})"
            )
        lat = list(inst["latency_s"].values())
        if lat:
            L.append(
                f"- truth latency against the wheel counts: {min(lat) * 1e3:.0f} to "
                f"{max(lat) * 1e3:.0f} ms per run (report.json instrument.latency_s)"
            )
        cr = inst.get("clock_rate")
        if cr:
            L.append(
                f"- truth clock against the wheel counts: {cr['ppm']:+.0f} +- {cr['se_ppm']:.0f} "
                f"ppm within a run ({cr['runs']} of {cr['of']} runs: latency on their first and "
                "last thirds)"
            )
            if cr.get("restamped_ratio_after") is not None:
                L.append(
                    f"  - re-stamped by that rate, the truth leaves the named candidate at "
                    f"{cr['restamped_ratio_after']:.2f} x the background on the held-out runs "
                    f"(against {hd['ratio_after']:.2f} x as stamped): "
                    + (
                        "the clock's misfit"
                        if v["effect"] == "unexplained"
                        else "not the clock's, and the verdict stands"
                    )
                )
        L += [f"- {n}" for n in inst["notes"]]
    L += ["", "## Not identifiable from these data", ""]
    L += [f"- {u['what']}: {u['why']}" for u in rep["unidentifiable"]]
    L += [
        "",
        f"Noise per window: {', '.join(f'{k} {x:.3g}' for k, x in rep['noise_sigma'].items())}. "
        f"Evidence: {rep['evidence_measure']}. Elapsed {rep['elapsed_s']:.1f} s.",
    ]
    return "\n".join(L) + "\n"


def _stab_keys(rep: dict) -> list[str]:
    keys: list[str] = []
    for g in rep["stability"]["groups"]:
        for k in g["params"]:
            if k not in keys and not k.startswith("slip.tau"):
                keys.append(k)
    return keys[:5]


def _remainder(rep: dict) -> str:
    bg = rep["background"]
    hd = rep["heldout"]
    parts = []
    if "heading_walk_deg_per_m" in bg:
        w = bg["heading_walk_deg_per_m"][0]
        s = bg["heading_per_spot_turn_deg"][0]
        parts.append(
            f"a heading random walk of {w:.2f} deg per sqrt(m) of travel and {s:.2f} deg (one "
            "sigma) per 90 deg turn on the spot, different on every run (floor and wheels, "
            "measured under the candidate), and the truth's own noise"
        )
        if "count_heading_mrad" in bg:
            parts.append(
                f"and the counts' own resolution (one count is {bg['count_heading_mrad'][0]:.2g}"
                " mrad of heading, an error held along each straight: background.counting_error)"
            )
    if "return_spread" in bg:
        s = bg["return_spread"]
        parts.append(
            "the spread of repeated runs of one path: "
            + ", ".join(f"{k} {v:.3g}" for k, v in s.items())
        )
        # a run that ends away from its start also carries its start heading over that reach
        # (modes.ReturnsMode.own_var): say where that made the allowance
        spread = math.hypot(s.get("x_mm", 0.0), s.get("y_mm", 0.0))
        b, run = max(zip(hd["background_mm"], hd["runs"], strict=False), default=(0.0, ""))
        if b > 1.1 * spread:
            parts.append(
                f"and the start heading ({s.get('theta_rad', 0.0):.3g} rad) over the reach of "
                f"runs that end away from their start (up to {b:.1f} mm, {run})"
            )
    r1 = hd["ratio_after"]
    if r1 <= 1.5:
        parts.append(f"{r1:.2f} x the background: nothing systematic is left")
    else:
        parts.append(f"{r1:.2f} x the background: a systematic part is left")
    return "; ".join(parts)


TOOL = "odo-gap"  # the report folder's manifest owner


@contextmanager
def _refusals_as_input_errors():
    """The output rule's refusals (OutputError) as odo-gap's one-line input errors."""
    from ..outpath import OutputError
    from .errors import GapInputError

    try:
        yield
    except OutputError as e:
        raise GapInputError(e.path, e.why) from None


def check_out(out: str | Path, force: bool = False, inputs: list | None = None) -> None:
    """GapInputError now where write_report(..., out, force, inputs) would refuse OUT."""
    from ..outpath import check_dir

    with _refusals_as_input_errors():
        check_dir(out, TOOL, force, inputs)


def write_report(
    rep: Report, out: str | Path, force: bool = False, inputs: list | None = None
) -> None:
    """Report into OUT by the project's output rule (odo_tools/outpath.py): built in a fresh temp
    folder beside OUT and moved into place, never a partial report; an existing OUT is written
    into only when it holds odo-gap's manifest (then exactly the files that manifest lists are
    replaced or removed, the user's other files stay) or with `force` (same-named files
    replaced, nothing removed); an OUT that is or lies in an input is refused."""
    from ..outpath import OutDir
    from .plots import plot_report

    with _refusals_as_input_errors(), OutDir(out, TOOL, force, inputs) as od:
        d = rep.to_dict()
        (od.tmp / "report.json").write_text(json.dumps(d, indent=2, default=_json_default) + "\n")
        (od.tmp / "report.md").write_text(markdown(d))
        if rep.context is not None:
            plot_report(d, rep.context, od.tmp)


def _json_default(o):
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)
