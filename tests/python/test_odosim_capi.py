"""libodosim, the simulator's C API for tools (host_sim issue item 6), called through ctypes as
the diagnosis tool will: a library run equals the CLI run of the same seed, per-tick rows land in
memory, candidate effects can be set without files, and errors come back as messages."""

from __future__ import annotations

import csv
import ctypes as C
import json
import math
import os
import subprocess
from pathlib import Path

import pytest

SRC = Path(os.environ["ODO_SOURCE_DIR"])
BUILD = Path(os.environ["ODO_BUILD_DIR"])


class Row(C.Structure):
    _fields_ = [("t_s", C.c_double), ("truth", (C.c_double * 3) * 2), ("est", (C.c_double * 3) * 2),
                ("link", C.c_double * 3), ("counts", (C.c_uint32 * 2) * 2), ("faults", C.c_uint32),
                ("bump_events", C.c_uint32)]


class Result(C.Structure):
    _fields_ = [(n, C.c_double) for n in ("x_abs_mm", "y_abs_mm", "theta_abs_deg", "x_calc_mm",
                                          "y_calc_mm", "theta_calc_deg", "ex_mm", "ey_mm",
                                          "etheta_deg", "t_end_s")] + [("n_ticks", C.c_size_t)]


@pytest.fixture(scope="module")
def lib() -> C.CDLL:
    so = C.CDLL(str(BUILD / "lib" / "libodosim.so"))
    so.odosim_setup_load.restype = C.c_void_p
    so.odosim_setup_load.argtypes = [C.c_char_p, C.c_char_p, C.c_char_p, C.c_size_t]
    so.odosim_setup_set.argtypes = [C.c_void_p, C.c_char_p, C.c_char_p, C.c_uint, C.c_double,
                                    C.c_char_p, C.c_size_t]
    so.odosim_setup_free.argtypes = [C.c_void_p]
    so.odosim_run_seed.restype = C.c_uint64
    so.odosim_run_seed.argtypes = [C.c_uint64, C.c_int, C.c_uint]
    so.odosim_run.argtypes = [C.c_void_p, C.c_char_p, C.c_int, C.c_int, C.c_int, C.c_uint64,
                              C.c_uint, C.POINTER(Row), C.c_size_t, C.POINTER(Result), C.c_char_p,
                              C.c_size_t]
    so.odosim_effects_json.restype = C.c_void_p
    so.odosim_free.argtypes = [C.c_void_p]
    return so


def setup(lib: C.CDLL, scenario: str) -> int:
    err = C.create_string_buffer(512)
    s = lib.odosim_setup_load(str(SRC / "host_sim/robots/labmate.json").encode(),
                              str(SRC / "host_sim/scenarios" / scenario).encode(), err, 512)
    assert s, err.value.decode()
    return s


def test_library_run_equals_the_cli_run_of_the_same_seed(lib: C.CDLL, tmp_path: Path) -> None:
    assert lib.odosim_api_version() == 1
    s = setup(lib, "set-sim.json")
    rows = (Row * 4000)()
    res = Result()
    err = C.create_string_buffer(512)
    seed = lib.odosim_run_seed(7, 0, 0)
    assert lib.odosim_run(s, b"umbmark", 0, -1, 0, seed, 0, rows, 4000, C.byref(res), err, 512) == 0
    subprocess.run([str(BUILD / "bin/odo-sim"), "--quiet", "--experiment", "umbmark", "--vehicle",
                    "labmate", "--scenario", str(SRC / "host_sim/scenarios/set-sim.json"),
                    "--runs", "1", "--seed", "7", "--out", str(tmp_path / "o")], check=True)
    first = next(csv.DictReader((tmp_path / "o" / "returns.csv").open()))
    for key in ("x_abs_mm", "y_abs_mm", "x_calc_mm", "y_calc_mm"):
        assert float(first[key]) == pytest.approx(getattr(res, key), abs=1e-3), key
    n = res.n_ticks
    assert 2000 < n <= 4000
    # per-tick rows: the firmware's estimate starts at the truth and ends where the result says
    assert rows[0].est[0][0] == 0.0 and rows[n - 1].est[0][0] == pytest.approx(res.x_calc_mm)
    assert rows[n - 1].truth[0][0] == pytest.approx(res.x_abs_mm)
    assert all(math.isfinite(rows[i].truth[0][2]) for i in range(n))
    lib.odosim_setup_free(s)


def test_candidate_effects_are_set_in_memory_and_errors_are_reported(lib: C.CDLL) -> None:
    s = setup(lib, "none.json")
    err = C.create_string_buffer(512)
    base, bent = Result(), Result()
    assert lib.odosim_run(s, b"umbmark", 1, -1, 0, 1, 0, None, 0, C.byref(base), err, 512) == 0
    assert lib.odosim_setup_set(s, b"ed", b"value", 1, 1.002, err, 512) == 0
    assert lib.odosim_run(s, b"umbmark", 1, -1, 0, 1, 0, None, 0, C.byref(bent), err, 512) == 0
    assert abs(bent.ex_mm - base.ex_mm) + abs(bent.ey_mm - base.ey_mm) > 20.0
    assert lib.odosim_setup_set(s, b"warp_drive", None, 1, 1.0, err, 512) != 0
    assert b"warp_drive" in err.value
    assert lib.odosim_setup_set(s, b"ed", b"value", 1, 9.0, err, 512) != 0
    assert lib.odosim_run(s, b"figure-8", 0, -1, 0, 1, 0, None, 0, C.byref(base), err, 512) != 0
    assert b"figure-8" in err.value
    assert lib.odosim_run(s, b"umbmark", 0, -1, 3, 1, 0, None, 0, C.byref(base), err, 512) != 0
    assert b"ipec" in err.value
    lib.odosim_setup_free(s)


def test_effects_catalog_is_published_as_json(lib: C.CDLL) -> None:
    p = lib.odosim_effects_json()
    assert p
    doc = json.loads(C.string_at(p).decode())
    lib.odosim_free(p)
    text = json.dumps(doc)
    for name in ("ed", "eb", "es", "bumps", "roughness", "slip", "skid", "count_loss",
                 "rotary_bias", "link_bias", "tire_compression"):
        assert f'"{name}"' in text, name


def test_the_robot_calibration_scrub_reaches_the_firmware(lib: C.CDLL, tmp_path: Path) -> None:
    """A robot description's "scrub" (k of the firmware's tyre-scrub term) is what the firmware in
    the loop believes: on the rectangle, whose corners the follower drives as arcs, the firmware's
    heading and so the driven path change; k = 0 is the file without the key, bit for bit."""
    robot = json.loads((SRC / "host_sim/robots/labmate.json").read_text())
    results = {}
    for k in (None, 0.0, 0.2):
        r = json.loads(json.dumps(robot))
        if k is not None:
            r["trucks"]["A"]["calibration"] = {"scrub": k}
        path = tmp_path / f"robot-{k}.json"
        path.write_text(json.dumps(r))
        err = C.create_string_buffer(512)
        s = lib.odosim_setup_load(str(path).encode(),
                                  str(SRC / "host_sim/scenarios/none.json").encode(), err, 512)
        assert s, err.value.decode()
        res = Result()
        assert lib.odosim_run(s, b"rect-7x4", 0, -1, 0, 1, 0, None, 0, C.byref(res), err, 512) == 0
        lib.odosim_setup_free(s)
        results[k] = (res.x_abs_mm, res.y_abs_mm, res.theta_calc_deg)
    assert results[None] == results[0.0]
    assert math.dist(results[0.2][:2], results[0.0][:2]) > 100.0
