"""Frames the bus lost (a missing-frame input class): a tick whose truck B counts or linkage
frame is missing takes its value interpolated between its neighbours, the short way round a
counter's wrap and an encoder angle's 360 deg, instead of holding the previous one (which put a
whole tick of truck B's travel into one window and took it back from the next)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from gap_support import BUILD, SRC


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


N = 12
T0, TICK = 1000.0, 0.04


def _log(path: Path, lost: dict[str, int]) -> dict[str, np.ndarray]:
    """A clapper's frames every 40 ms: truck A 100 counts per tick, truck B's counters 37 per
    tick from just below the 24-bit wrap, alpha turning 0.3 deg per tick through 0, beta
    constant, l growing 0.5 mm per tick; the frame of each kind in `lost` is missing at that
    tick. Returns what every tick truly read."""
    from odo_tools.gap.io import encode_payload, frame_id, write_candump

    k = np.arange(N)
    t = T0 + TICK * k
    true = {
        "a": 100 * k,
        "b": (2**24 - 200 + 37 * k) % 2**24,
        "alpha": np.mod(-1.5 + 0.3 * k, 360.0),
        "l": 1000.0 + 0.5 * k,
    }
    frames = []
    for name, vals in (
        ("WHEEL_COUNTS_A", {"LeftCount": true["a"], "RightCount": true["a"]}),
        ("WHEEL_COUNTS_B", {"LeftCount": true["b"], "RightCount": true["b"]}),
        ("LINK_ROTARY", {"Alpha": true["alpha"], "Beta": np.full(N, 2.0)}),
        ("LINK_LINEAR", {"Length": true["l"]}),
    ):
        fid = frame_id(name)
        pay = encode_payload(fid, {**vals, "Seq": k % 256})
        keep = k != lost.get(name, -1)
        frames.append((t[keep] + 1e-4, fid, pay[keep]))
    write_candump(path, frames)
    return true


def test_a_lost_frame_is_interpolated_across_a_wrap(tmp_path: Path) -> None:
    from odo_tools.gap.io import read_log, read_robot

    robot = read_robot(SRC / "host_sim" / "robots" / "clapper.json")
    # B's counters wrap between ticks 5 and 6, alpha crosses 0 deg between ticks 4 and 5
    lost = {"WHEEL_COUNTS_B": 5, "LINK_ROTARY": 5, "LINK_LINEAR": 7}
    true = _log(tmp_path / "a.log", lost)
    log = read_log(tmp_path / "a.log", robot)
    assert log.counts[:, 1, 0].tolist() == true["b"].tolist()
    assert log.counts[:, 1, 1].tolist() == true["b"].tolist()
    dev = np.mod(log.alpha_deg - true["alpha"] + 180.0, 360.0) - 180.0
    assert np.abs(dev).max() < 0.01  # the DBC's 0.0055 deg step
    assert np.allclose(log.beta_deg, 2.0, atol=0.01)
    assert np.allclose(log.l_mm, true["l"], atol=1e-3)


@pytest.mark.parametrize("tick", [0, N - 1])
def test_a_frame_lost_at_either_end_holds_the_nearest(tmp_path: Path, tick: int) -> None:
    from odo_tools.gap.io import read_log, read_robot

    robot = read_robot(SRC / "host_sim" / "robots" / "clapper.json")
    true = _log(tmp_path / "a.log", {"LINK_LINEAR": tick})
    log = read_log(tmp_path / "a.log", robot)
    near = 1 if tick == 0 else N - 2
    assert log.l_mm[tick] == pytest.approx(true["l"][near], abs=1e-3)
    rest = np.arange(N) != tick
    assert np.allclose(log.l_mm[rest], true["l"][rest], atol=1e-3)
