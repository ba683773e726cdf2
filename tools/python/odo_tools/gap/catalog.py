"""The effects catalog (host_sim/src/effects.c) as the diagnosis sees it, read through libodosim:
parameters with their ranges, the vehicles each effect exists on, and what each evidence mode sees
of it (`yes`: a hypothesis it identifies; `weak`: fitted but not named reliably; `no`: not a
hypothesis there, with the reason). Nothing here is a second copy of the catalog."""

from __future__ import annotations

from .simlib import catalog

MODES = ("truth", "returns", "linkage")


def effects() -> dict[str, dict]:
    """Every catalog effect by name, in catalog order."""
    return catalog()


def exists_on(effect: str, vehicle: str) -> bool:
    return vehicle in catalog()[effect]["vehicles"]


def seen(effect: str, mode: str) -> str:
    """'yes', 'weak' or 'no' (catalog `evidence`)."""
    return catalog()[effect]["evidence"][mode]["seen"]


def mode_applies(mode: str, vehicle: str) -> bool:
    """A labmate has no linkage: linkage mode needs a clapper or a set."""
    return mode != "linkage" or vehicle != "labmate"


def hypotheses(mode: str, vehicle: str) -> list[str]:
    """The catalog effects fitted as hypotheses in `mode` on `vehicle` (catalog order)."""
    if not mode_applies(mode, vehicle):
        return []
    return [e for e in catalog() if exists_on(e, vehicle) and seen(e, mode) != "no"]


def identifiable(mode: str, vehicle: str) -> list[str]:
    """The hypotheses the mode names reliably (`yes`): what the blind check scores it on."""
    return [e for e in hypotheses(mode, vehicle) if seen(e, mode) == "yes"]


def not_identifiable(mode: str, vehicle: str) -> dict[str, str]:
    """Effects of this vehicle the mode cannot name, with the catalog's reason (`no` and `weak`)."""
    out = {}
    for e, d in catalog().items():
        if exists_on(e, vehicle) and seen(e, mode) != "yes":
            out[e] = d["evidence"][mode]["why"] or ""
    return out


def param(key: str) -> dict:
    """The catalog entry of 'effect.param'."""
    e, p = key.split(".")
    return next(x for x in catalog()[e]["params"] if x["name"] == p)


def bounds(key: str) -> tuple[float, float, float]:
    """(min, max, default) of a catalog parameter 'effect.param'."""
    d = param(key)
    return float(d["min"]), float(d["max"]), float(d["default"])
