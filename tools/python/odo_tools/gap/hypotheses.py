"""Hypotheses: which effects, under which laws, with which free parameters.

Every catalog effect the evidence mode can see (catalog.hypotheses) is a hypothesis under its
catalog law. Some physics come in more than one law in the real world (issue 13 item 3): slip
tied to the acceleration or to traction (torque) saturation, counts lost above a speed. Those
laws are hypotheses of the same family, proposed when the residual lives where that physics acts
(`propose`: slip in the accelerating phases, count loss at high wheel speed); the verdict names
the family (the physics) and reports the law that fitted. Pairs join two families.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from . import catalog
from .model import DRIVE_ONLY

# free parameters of each catalog effect under its catalog law (others stay at their defaults)
CATALOG_FREE = {
    "ed": ("value",),
    "eb": ("value",),
    "es": ("value",),
    "roughness": (),  # its height follows from the measured walk (fit.Problem.rough_from_walk)
    "slip": ("k_per_m_s2", "tau_s"),
    "skid": ("k_s",),
    "rotary_bias": ("alpha_deg", "beta_deg"),
    "link_bias": ("const_mm", "ecc_mm"),
    "scrub": ("k",),
}

# parameters that are not catalog parameters: model-side nuisances and the other laws' own
# (min, max, start)
EXTRA_BOUNDS = {
    "slip.tau_s": (0.0005, 0.02, 0.004),
    "slip@accel.k_per_m_s2": (0.0, 5.0, 0.05),
    "slip@accel.a0_m_s2": (0.0, 5.0, 0.2),
    "slip@accel.asym": (-0.9, 0.9, 0.0),
    "slip@accel.exponent": (0.5, 3.0, 1.0),
    "slip@traction.a_max_m_s2": (0.05, 20.0, 2.0),
    "slip@motor.a_max_m_s2": (0.05, 20.0, 1.0),
    "slip@motor.tau_s": (0.002, 0.2, 0.03),
    "count_loss@speed.k_per_m_s": (0.0, 20.0, 0.2),
    "count_loss@speed.v0_mm_s": (0.0, 5000.0, 300.0),
    "count_loss@plateau.excess_mm_s": (0.0, 5000.0, 400.0),
    "count_loss@plateau.a_m_s2": (0.05, 20.0, 1.0),
    "count_loss@flagged.counts": (0.0, 1000.0, 2.0),
    "count_loss@missed.scale": (0.05, 20.0, 1.0),
    "skid@cornering.deg_per_m_s2": (0.0, 30.0, 1.0),
    "skid@friction.a_lim_m_s2": (0.05, 20.0, 2.0),
    "eb@load.zeta": (0.0, 1.0, 0.05),
    "ed@growth.g_per_m2_s2": (-0.05, 0.05, 0.0),
    "rotary_bias@eccentric.alpha_sin_deg": (-10.0, 10.0, 0.0),
    "rotary_bias@eccentric.alpha_cos_deg": (-10.0, 10.0, 0.0),
    "rotary_bias@eccentric.beta_sin_deg": (-10.0, 10.0, 0.0),
    "rotary_bias@eccentric.beta_cos_deg": (-10.0, 10.0, 0.0),
    "link_bias@offset.alpha_s_mm": (-50.0, 50.0, 0.0),
    "link_bias@offset.alpha_c_mm": (-50.0, 50.0, 0.0),
    "link_bias@offset.beta_s_mm": (-50.0, 50.0, 0.0),
    "link_bias@offset.beta_c_mm": (-50.0, 50.0, 0.0),
}
START = {"slip.k_per_m_s2": 0.05, "skid.k_s": 0.05, "roughness.max_height_mm": 0.5}


@dataclass(frozen=True)
class Law:
    family: str  # the catalog effect whose physics it is ("slip")
    name: str  # "catalog", "acceleration", "traction", "above a speed"
    params: tuple[str, ...]  # fitted keys
    doc: str
    truck: str | None = None  # "A" or "B": on that truck only (model.truck_view)

    @property
    def key(self) -> str:
        """How the hypothesis is named in rankings: 'slip', 'slip@traction', 'ed[B]'."""
        k = self.family if self.name == "catalog" else f"{self.family}@{self.name}"
        return k if self.truck is None else f"{k}[{self.truck}]"

    def on(self, truck: str) -> Law:
        """The same law on one truck of a clapper or set."""
        return Law(
            self.family, self.name, tuple(f"{p}.{truck}" for p in self.params), self.doc, truck
        )


def catalog_law(effect: str, vehicle: str) -> Law:
    free = CATALOG_FREE.get(effect, ())
    if effect == "rotary_bias" and vehicle == "set":
        free = ("alpha_deg",)  # a set has one joint encoder
    doc = catalog.effects()[effect]["doc"]
    return Law(effect, "catalog", tuple(f"{effect}.{p}" for p in free), doc)


# the other laws of a family (model.py implements each)
OTHER_LAWS = {
    "ed": (
        Law(
            "ed",
            "growth",
            ("ed.value", "ed@growth.g_per_m2_s2"),
            "one tyre's rolling radius grows with the square of its speed (centrifugal growth): "
            "r (1 + |g| v^2), the left tyre's for g > 0, the right's for g < 0, beside a fixed Ed",
        ),
    ),
    "eb": (
        Law(
            "eb",
            "load",
            ("eb.value", "eb@load.zeta"),
            "a wheelbase that grows with the lateral load: Eb (1 + zeta |a_lat| / g), so a "
            "circle driven faster turns less",
        ),
    ),
    "slip": (
        Law(
            "slip",
            "accel",
            (
                "slip@accel.k_per_m_s2",
                "slip@accel.a0_m_s2",
                "slip@accel.asym",
                "slip@accel.exponent",
            ),
            "slip fraction k (1 -/+ asym) max(0, |a| - a0)^exponent on the acceleration the "
            "counts show (m/s^2), tick by tick, left/right",
        ),
        Law(
            "slip",
            "traction",
            ("slip@traction.a_max_m_s2",),
            "traction (torque) saturation: the floor speed follows the wheel at most by what "
            "the friction circle of a_max leaves beside the turn's lateral acceleration",
        ),
        Law(
            "slip",
            "motor",
            ("slip@motor.a_max_m_s2", "slip@motor.tau_s"),
            "traction saturation inside the tick: the motor reaches each tick's speed with a "
            "lag tau, and the floor follows it at most by the friction circle of a_max",
        ),
    ),
    "skid": (
        Law(
            "skid",
            "cornering",
            ("skid@cornering.deg_per_m_s2",),
            "linear cornering stiffness: a slip angle proportional to the centripetal "
            "acceleration, from the gentlest arc up (no threshold)",
        ),
        Law(
            "skid",
            "friction",
            ("skid@friction.a_lim_m_s2",),
            "friction circle: the truck's centre changes its velocity by at most a_lim in any "
            "direction; beyond it the centre falls behind the wheels' path, the heading follows",
        ),
    ),
    "count_loss": (
        Law(
            "count_loss",
            "speed",
            ("count_loss@speed.k_per_m_s", "count_loss@speed.v0_mm_s"),
            "a fraction k max(0, |v| - v0) of the travel never reaches the counter",
        ),
        Law(
            "count_loss",
            "plateau",
            ("count_loss@plateau.excess_mm_s", "count_loss@plateau.a_m_s2"),
            "a count-rate ceiling: the counts sit on a flat top while the hidden wheel speed "
            "goes on to the ceiling + excess at the rate the counts rose into it (at most a) "
            "and back at the rate they fall out of it",
        ),
        Law(
            "count_loss",
            "flagged",
            ("count_loss@flagged.counts",),
            "the decoder's own word: a wheel tick flagged with a skipped quadrature state "
            "(WHEEL_COUNTS Status) lost this many counts",
        ),
        Law(
            "count_loss",
            "missed",
            ("count_loss@missed.scale",),
            "edges missed with a probability that rises with the edge rate and saturates, read "
            "from how often the decoders flagged a tick at each rate (model.read_missed); a "
            "flagged tick lost the two counts of each state it skipped; scale sets where the "
            "probability saturates (scale x the flags' p_max), the low-rate tail kept",
        ),
    ),
    "rotary_bias": (
        Law(
            "rotary_bias",
            "eccentric",
            tuple(
                f"rotary_bias{p}"
                for j in ("alpha", "beta")
                for p in (f".{j}_deg", f"@eccentric.{j}_sin_deg", f"@eccentric.{j}_cos_deg")
            ),
            "a joint encoder's offset that varies once per turn of its shaft (a disc mounted off "
            "centre): b0 + s sin(angle) + c (cos(angle) - 1) on each joint angle",
        ),
    ),
    "link_bias": (
        Law(
            "link_bias",
            "offset",
            (
                "link_bias.const_mm",
                *(f"link_bias@offset.{j}_{f}_mm" for j in ("alpha", "beta") for f in "sc"),
            ),
            "a linear encoder whose ends sit off the pivots: b0 + s sin(angle) + c (cos(angle) "
            "- 1) at each joint, the offsets' projection on the link",
        ),
    ),
}

# the catalog count_loss acts through the decoder's clock (an HCTL filter), which the counts do
# not show: its hypothesis is the generic law above
CATALOG_LAW_REPLACED = {"count_loss": "speed"}


@dataclass(frozen=True)
class Hypothesis:
    laws: tuple[Law, ...]

    @property
    def name(self) -> str:
        """'ed', 'slip@traction', 'eb+scrub': families with their law where not the catalog's,
        bumps last."""
        keys = sorted((law.key for law in self.laws), key=lambda k: (k == "bumps", k))
        return "+".join(keys)

    @property
    def families(self) -> tuple[str, ...]:
        return tuple(sorted({law.family for law in self.laws}))

    @property
    def label(self) -> str:
        """What the verdict names: the physics, whatever the law ('slip', 'ed+slip')."""
        return "+".join(self.families)

    @property
    def params(self) -> list[str]:
        return [p for law in self.laws for p in law.params]

    @property
    def has_bumps(self) -> bool:
        return any(law.family == "bumps" for law in self.laws)

    def __add__(self, other: Hypothesis) -> Hypothesis:
        return Hypothesis(self.laws + other.laws)


def singles(mode: str, vehicle: str) -> list[Hypothesis]:
    """One hypothesis per catalog effect the mode sees, under its catalog law (count loss under
    the law the counts can show)."""
    out = []
    for e in catalog.hypotheses(mode, vehicle):
        if e in CATALOG_LAW_REPLACED:
            name = CATALOG_LAW_REPLACED[e]
            law = next(x for x in OTHER_LAWS[e] if x.name == name)
            out.append(Hypothesis((law,)))
        else:
            out.append(Hypothesis((catalog_law(e, vehicle),)))
    return out


def other_laws(family: str, mode: str, vehicle: str) -> list[Hypothesis]:
    """The other laws of a family, when the family is a hypothesis of this mode."""
    if family not in catalog.hypotheses(mode, vehicle):
        return []
    skip = CATALOG_LAW_REPLACED.get(family)
    laws = [law for law in OTHER_LAWS.get(family, ()) if law.name != skip]
    if family == "rotary_bias" and vehicle == "set":  # one joint encoder (catalog_law)
        laws = [replace(x, params=tuple(p for p in x.params if "beta" not in p)) for x in laws]
    return [Hypothesis((law,)) for law in laws]


def on_truck(h: Hypothesis, truck: str, driven: Sequence[bool] = (True, True)) -> Hypothesis | None:
    """A single hypothesis of a truck-scoped effect restricted to one truck (None otherwise, and
    for a drive effect on a truck that rolls passively, where it is the nominal model:
    model.DRIVE_ONLY; `driven` per truck, model.Prepared.driven)."""
    if len(h.laws) != 1 or h.has_bumps:
        return None
    law = h.laws[0]
    if law.truck is not None or catalog.effects()[law.family]["scope"] != "truck":
        return None
    if (
        not driven["AB".index(truck)]
        and law.params
        and all(p.startswith(DRIVE_ONLY) for p in law.params)
    ):
        return None
    if law.family == "roughness":  # one floor under both trucks
        return None
    return Hypothesis((law.on(truck),))


TRUCK_SHARE = 0.75  # a truck holding this share of the excess misfit proposes its own variants


def bounds(key: str) -> tuple[float, float, float]:
    """(min, max, start) of a fitted parameter: the catalog's range, or EXTRA_BOUNDS (a truck's
    own copy, 'ed.value.B', has the bounds of 'ed.value')."""
    if key.endswith((".A", ".B")):
        key = key[:-2]
    if key in EXTRA_BOUNDS:
        return EXTRA_BOUNDS[key]
    lo, hi, d = catalog.bounds(key)
    return lo, hi, START.get(key, d)


# where the residual lives -> which families to test with their other laws (where.phase_excess)
PROPOSE = {
    "slip": ("acceleration",),
    "count_loss": ("fast",),
    "skid": ("arc",),
}
# other laws always tried, whatever the phases propose ("family": all of its laws, or "family@law"):
# a load-dependent Eb shows in no one phase (every arc, more so the faster), and one cheap fit
# beside the catalog's Eb costs less than missing it; a cornering skid's outward step is made on the
# arc but read on the straight after it, where no phase proposes it (independent world, seed 2761
# case 1: 86 % of the excess on the straights, and a scrub that took the held-out runs from 14.6 to
# 402 x the background led the ranking). The friction circle's skid is read there too: a LabMate's
# two fast circles of three skidded 232 and 342 mm, 92 % of it on the straights after them, so
# nothing proposed the law and the cornering law left 64 x (independent seed 2951 case 30; the
# friction circle, tried, 1.16 x). It was left out once because it joined a LabMate's slip as a
# "skid" (2761 case 22); unproposed it joins no pair now, and that case and the 240 truth cases of
# dev seeds 2821-2851 keep their verdicts (one clapper's clock drift more "unexplained"). A joint
# encoder's offset that varies with the angle (a disc off centre) shows in no phase either; as a
# constant it left a set's held-out runs at 2.8 x the background (2741 case 40: 1.1 x once per
# turn), and it costs no dead reckoning. A tyre that grows with speed acts wherever the robot drives
# fast, turning or not, and the phases' "fast" share proposes count loss; as a fixed Ed it was "ed +
# scrub" twice (2791 cases 32 and 50). Unproposed it leads alone and joins no pair (`unproposed`). A
# floor that cannot follow the motor's torque (traction saturation) loses travel at every start and
# stop, and where it loses much the track is off everywhere after the first start: the phases then
# proposed nothing and the catalog's slip, fitted alone, left a LabMate's held-out runs worse than
# the nominal model (independent seeds 2791 case 51, 2801 case 58: "unexplained"). A link-length
# encoder whose ends sit off the pivots reads a bias that varies with each joint angle; the
# catalog's one term of the angle between them left a clapper's held-out runs at 7.1 x the
# background (independent seed 3241 case 40, fitted 1.16 x with the ends' law: const -0.727 mm
# for a true -0.728). Its whole family is here, so that it pairs: a sensor's bias adds to any
# motion effect (dev 4071 case 13, Ed beside it). The acceleration slip law, by a power of the
# acceleration: return errors have no phases to propose it (a LabMate's squares' returns at 10.8 x
# the spread of repeated runs, the catalog's and the traction laws closing none of it, the
# acceleration law 1.1 x; independent dev seed 4021 case 26), and a LabMate's spot turns, which
# the phases count as turns, not as accelerations, carry most of its slip (dev 4501 case 44:
# "unexplained"; under the law linear in the acceleration "eb + slip", the Eb taking up the
# heading step each turn leaves where it slows down at another rate than it sped up:
# model.slip_accel)
ALWAYS = (
    "eb",
    "slip@accel",
    "skid@cornering",
    "skid@friction",
    "rotary_bias@eccentric",
    "link_bias",
    "ed@growth",
    "slip@traction",
    "slip@motor",
)


def unproposed(h: Hypothesis, proposals: dict) -> bool:
    """A law ALWAYS tries although the phases did not propose its family: it may lead the
    ranking alone, but joins no pair or triple. Beside an Ed on a set's truck the cornering skid
    took 0.27 deg per m/s^2 of the windows' residue ("ed+skid", independent seed 2721 case 13)."""
    return any(
        law.family not in proposals and law.name != "catalog" and law.family not in ALWAYS
        for law in h.laws
    )


# laws that act only on ticks the wheel decoders flagged (model.count_loss_flagged): nothing to
# fit where they flagged none
NEEDS_FLAGS = ("count_loss@flagged", "count_loss@missed")


def tried_laws(proposals: dict, mode: str, vehicle: str, flagged: bool = False) -> list[Hypothesis]:
    """The other laws a ranking fits beside the catalog's: ALWAYS's, and every law of each
    family the phases propose (`propose`); NEEDS_FLAGS's only where the decoders `flagged`."""
    out = []
    for fam in dict.fromkeys([*(a.split("@")[0] for a in ALWAYS), *proposals]):
        laws = other_laws(fam, mode, vehicle)
        if fam not in proposals and fam not in ALWAYS:
            laws = [h for h in laws if h.name in ALWAYS]
        out += [h for h in laws if flagged or h.name not in NEEDS_FLAGS]
    return out


PROPOSE_SHARE = 0.25  # a phase holding this share of the excess misfit proposes its families
PROPOSE_DENSITY = 2.0  # ... or this many times its share of the run


def propose(phase_excess: dict[str, tuple[float, float]]) -> dict[str, str]:
    """Families whose physics acts where the residual lives, with the evidence in words.
    `phase_excess`: phase -> (share of the nominal excess misfit, share of the windows)."""
    out = {}
    for fam, phases in PROPOSE.items():
        for ph in phases:
            share, frac = phase_excess.get(ph, (0.0, 0.0))
            if share >= PROPOSE_SHARE or (
                frac > 0 and share >= PROPOSE_DENSITY * frac and share > 0.05
            ):
                out[fam] = (
                    f"{share:.0%} of the excess misfit lies in the {ph} phases "
                    f"({frac:.0%} of the run)"
                )
    return out
