"""Shared helpers of the odo-gap / odo-import tests (not a test module)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

SRC = Path(os.environ.get("ODO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
BUILD = Path(os.environ.get("ODO_BUILD_DIR", SRC / "build" / "host"))
PY = sys.executable


def env() -> dict:
    e = dict(os.environ)
    e["ODO_SOURCE_DIR"] = str(SRC)
    e["ODO_BUILD_DIR"] = str(BUILD)
    e["PYTHONPATH"] = str(SRC / "tools" / "python") + os.pathsep + e.get("PYTHONPATH", "")
    return e


def odo_gap(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [PY, "-m", "odo_tools.gap.cli", *args], env=env(), capture_output=True, text=True,
        timeout=600)


def odo_import(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([PY, "-m", "odo_tools.importer", *args], env=env(), capture_output=True,
                          text=True, timeout=600)


def odo_sim(scenario: str, out: Path, runs: int = 1, experiment: str = "umbmark") -> None:
    subprocess.run([str(BUILD / "bin" / "odo-sim"), "--quiet", "--experiment", experiment,
                    "--vehicle", "labmate", "--scenario",
                    str(SRC / "host_sim/scenarios" / scenario),
                    "--runs", str(runs), "--out", str(out)], check=True, timeout=300)


def optiodom_dir() -> Path | None:
    """../shared/data/optiodom beside the repository (a worktree sits one level deeper)."""
    for base in (SRC.parent, SRC.parent.parent):
        d = base / "shared" / "data" / "optiodom"
        if d.is_dir():
            return d
    return None


def indep_case(seed: int, k: int, out: Path, vehicle: str, laws: dict) -> dict:
    """The independent world's case k of `seed`, simulated into `out` exactly as `odo-gap blind`
    draws and simulates it; the drawn vehicle and effect laws are checked first, so a change of
    the world that moves the case fails here, by name, rather than in what a test asserts."""
    import numpy as np
    from odo_tools.validation import case_seed, indep

    rng = np.random.default_rng(seed)
    c = [indep.draw_case(rng, i) for i in range(k + 1)][k]
    assert c["vehicle"] == vehicle and c["laws"] == laws, (
        f"the independent world's seed {seed} case {k} changed ({c['vehicle']}, {c['laws']}): "
        "pick another case like it"
    )
    indep.simulate_case(c, out, case_seed(seed, k))
    return c


def each_run_its_own_latency(monkeypatch) -> None:
    """The truth's latency as it was read before the session's runs were summed
    (instrument.run_latencies): each run's own shift, none where a run fixes none."""
    from odo_tools.gap import instrument

    def own(prs, P=None, lever=(0.0, 0.0), heading_offset=0.0) -> dict:
        return {
            pr.run.name: instrument.latency(pr, 0, P, lever=lever, heading_offset=heading_offset)
            for pr in prs
        }

    monkeypatch.setattr(instrument, "run_latencies", own)


def indep_named(seed: int, k: int, tmp: Path, vehicle: str, laws: dict, effect: str,
                law: str, mode: str = "truth") -> tuple[dict, dict]:
    """indep_case k of `seed` diagnosed in `mode`: (the case, the report), after checking that
    the verdict names `effect` and that its law is `law`."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp / "real"
    c = indep_case(seed, k, real, vehicle, laws)
    rep = diagnose(real, real / "robot.json", mode=mode).to_dict()
    v = rep["verdict"]
    assert v["effect"] == effect, v
    assert v["laws"][effect]["law"] == law, v["laws"]
    return c, rep


def sim_case(seed: int, k: int, out: Path, vehicle: str, effects: list) -> dict:
    """The simulator world's case k of `seed`, simulated into `out` as `odo-gap blind --world
    sim` draws and simulates it; the drawn vehicle and effects are checked first (indep_case)."""
    import numpy as np
    from odo_tools.validation import blind, case_seed

    rng = np.random.default_rng(seed)
    c = [blind.draw_case(rng, i) for i in range(k + 1)][k]
    assert c["vehicle"] == vehicle and list(c["effects"]) == effects, (
        f"the simulator world's seed {seed} case {k} changed ({c['vehicle']}, {c['effects']}): "
        "pick another case like it"
    )
    blind.simulate_case(c, out, case_seed(seed, k))
    return c
