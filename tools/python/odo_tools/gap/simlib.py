"""libodosim through ctypes (host_sim/include/odosim/odosim.h): the effects catalog for the
diagnosis, and odosim_run_ex for the blind check's "real" runs.

The ctypes structs below mirror the C ones; `check_layouts` compares their sizes with the
`sizeof` libodosim exports (odosim_sizeof), and `lib()` refuses a library they do not match, so a
field added on the C side fails loudly (tests/python/test_gap_hidden.py) instead of shifting every
later field."""

from __future__ import annotations

import ctypes as C
import json
import os
from functools import lru_cache
from pathlib import Path

import numpy as np

from .errors import GapInputError
from .repo import source_dir


class RowEx(C.Structure):
    _fields_ = [
        ("t_s", C.c_double),
        ("t_us", C.c_uint64),
        ("truth", (C.c_double * 3) * 2),
        ("link_true", C.c_double * 3),
        ("counts", (C.c_uint32 * 2) * 2),
        ("wheel_seq", C.c_uint8 * 2),
        ("wheel_status", C.c_uint8 * 2),
        ("wheel_present", C.c_uint8 * 2),
        ("rotary_present", C.c_uint8),
        ("linear_present", C.c_uint8),
        ("rotary_status", C.c_uint8),
        ("linear_status", C.c_uint8),
        ("rotary_seq", C.c_uint8),
        ("linear_seq", C.c_uint8),
        ("alpha_bam16", C.c_uint16),
        ("beta_bam16", C.c_uint16),
        ("length_um", C.c_uint32),
        ("n_events", C.c_uint32),
    ]


class Event(C.Structure):
    _fields_ = [(n, C.c_double) for n in ("t_s", "x_mm", "y_mm", "height_mm", "at_distance_mm")] + [
        ("truck", C.c_uint32),
        ("wheel", C.c_uint32),
    ]


class Result(C.Structure):
    _fields_ = [
        (n, C.c_double)
        for n in (
            "x_abs_mm",
            "y_abs_mm",
            "theta_abs_deg",
            "x_calc_mm",
            "y_calc_mm",
            "theta_calc_deg",
            "ex_mm",
            "ey_mm",
            "etheta_deg",
            "t_end_s",
        )
    ] + [("n_ticks", C.c_size_t)]


class Opts(C.Structure):
    _fields_ = [
        ("experiment", C.c_char_p),
        ("ccw", C.c_int),
        ("bumps", C.c_int),
        ("bump_height_mm", C.c_double),
        ("ipec", C.c_int),
        ("seed", C.c_uint64),
        ("run_index", C.c_uint),
        ("physics_dt_s", C.c_double),
        ("motor_tau_s", C.c_double),
        ("diam_var_amp", C.c_double),
        ("diam_var_period_s", C.c_double),
        ("diam_drift_per_s", C.c_double),
        ("backlash_rad", C.c_double),
    ]


def lib_path() -> Path:
    cands = []
    if os.environ.get("ODO_BUILD_DIR"):
        cands.append(Path(os.environ["ODO_BUILD_DIR"]) / "lib" / "libodosim.so")
    root = source_dir()
    cands += [root / "build" / d / "lib" / "libodosim.so" for d in ("host", "release", "h-gap")]
    cands += sorted((root / "build").glob("*/lib/libodosim.so"))
    for c in cands:
        if c.is_file():
            return c
    raise GapInputError(
        root / "build", "libodosim.so not found: build first (make build) or set ODO_BUILD_DIR"
    )


@lru_cache(maxsize=1)
def lib() -> C.CDLL:
    so = C.CDLL(str(lib_path()))
    so.odosim_setup_parse.restype = C.c_void_p
    so.odosim_setup_parse.argtypes = [C.c_char_p, C.c_char_p, C.c_char_p, C.c_size_t]
    so.odosim_setup_free.argtypes = [C.c_void_p]
    so.odosim_run_seed.restype = C.c_uint64
    so.odosim_run_seed.argtypes = [C.c_uint64, C.c_int, C.c_uint]
    so.odosim_run_ex.argtypes = [
        C.c_void_p,
        C.POINTER(Opts),
        C.POINTER(RowEx),
        C.c_size_t,
        C.POINTER(Event),
        C.c_size_t,
        C.POINTER(C.c_size_t),
        C.POINTER(Result),
        C.c_char_p,
        C.c_size_t,
    ]
    so.odosim_effects_json.restype = C.c_void_p
    so.odosim_free.argtypes = [C.c_void_p]
    so.odosim_sizeof.restype = C.c_size_t
    so.odosim_sizeof.argtypes = [C.c_char_p]
    dbl = C.POINTER(C.c_double)
    so.odosim_link_clamp.restype = C.c_long
    so.odosim_link_clamp.argtypes = [
        dbl,
        C.c_size_t,
        C.c_double,
        C.c_double,
        C.POINTER(C.c_ubyte),
        dbl,
    ]
    so.odosim_rate_limit.argtypes = [dbl, dbl, C.c_size_t, dbl]
    so.odosim_rate_limit_track.argtypes = [dbl, C.c_size_t, dbl, C.c_double, dbl]
    bad = check_layouts(so)
    if bad:
        raise GapInputError(lib_path(), "ctypes layouts do not match libodosim: " + "; ".join(bad))
    return so


# the C type each ctypes struct mirrors
LAYOUTS = {
    "odosim_tick_row_ex_t": RowEx,
    "odosim_event_t": Event,
    "odosim_result_t": Result,
    "odosim_run_opts_t": Opts,
}


def check_layouts(so: C.CDLL) -> list[str]:
    """Structs whose ctypes size differs from libodosim's sizeof (empty when all match)."""
    bad = []
    for name, cls in LAYOUTS.items():
        n = int(so.odosim_sizeof(name.encode()))
        if n != C.sizeof(cls):
            bad.append(f"{name}: C {n} bytes, ctypes {C.sizeof(cls)}")
    return bad


def link_clamp(rel: np.ndarray, lo: float, hi: float, gate: np.ndarray | None) -> np.ndarray:
    """(n, 2) cumulative move of truck A by the clapper's stop (world.c sim_link_clamp_track) over
    rel, the (n, 2) link vector A - B as the wheels alone move it; gate (n,) bool or None."""
    rel = np.ascontiguousarray(rel, dtype=np.float64)
    push = np.empty_like(rel)
    g = None
    if gate is not None:
        g = np.ascontiguousarray(gate[: rel.shape[0]], dtype=np.uint8)
        if g.size < rel.shape[0]:
            raise ValueError("link_clamp: the gate is shorter than the track")
    dbl = C.POINTER(C.c_double)
    n = lib().odosim_link_clamp(
        rel.ctypes.data_as(dbl),
        rel.shape[0],
        float(lo),
        float(hi),
        None if g is None else g.ctypes.data_as(C.POINTER(C.c_ubyte)),
        push.ctypes.data_as(dbl),
    )
    if n < 0:
        raise ValueError(f"link_clamp: bad range [{lo}, {hi}]")
    return push


def rate_limit(v: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """u_i = u_(i-1) + clip(v_i - u_(i-1), -lim_i, lim_i) from u = 0 (host_sim/src/ratelimit.c),
    for 1-D v and lim of one length."""
    v = np.ascontiguousarray(v, dtype=np.float64)
    lim = np.ascontiguousarray(lim, dtype=np.float64)
    if v.ndim != 1 or lim.shape != v.shape:
        raise ValueError(f"rate_limit: shapes {v.shape} and {lim.shape}")
    out = np.empty_like(v)
    dbl = C.POINTER(C.c_double)
    lib().odosim_rate_limit(
        v.ctypes.data_as(dbl), lim.ctypes.data_as(dbl), v.size, out.ctypes.data_as(dbl)
    )
    return out


def rate_limit_track(pose: np.ndarray, dt: np.ndarray, acc: float) -> np.ndarray:
    """host_sim/src/ratelimit.c sim_rate_limit_track: (n, 3) the track pose (x, y, theta rows)
    followed by a velocity that changes by at most acc dt_i per step (dt: the n - 1 steps)."""
    pose = np.ascontiguousarray(pose, dtype=np.float64)
    dt = np.ascontiguousarray(dt, dtype=np.float64)
    if pose.ndim != 2 or pose.shape[1] != 3 or dt.shape != (max(pose.shape[0] - 1, 0),):
        raise ValueError(f"rate_limit_track: shapes {pose.shape} and {dt.shape}")
    out = np.empty_like(pose)
    dbl = C.POINTER(C.c_double)
    lib().odosim_rate_limit_track(
        pose.ctypes.data_as(dbl), pose.shape[0], dt.ctypes.data_as(dbl), float(acc),
        out.ctypes.data_as(dbl),
    )  # fmt: skip
    return out


@lru_cache(maxsize=1)
def catalog() -> dict[str, dict]:
    """THE effects catalog (host_sim/src/effects.c), by effect name."""
    so = lib()
    p = so.odosim_effects_json()
    try:
        doc = json.loads(C.string_at(p).decode())
    finally:
        so.odosim_free(p)
    return {e["name"]: e for e in doc["effects"]}
