"""host_sim's hidden (out-of-catalog) effects through libodosim's odosim_run_ex (issue 7 item 3):
all off is bit-identical to odosim_run, and each hidden effect changes the truth."""

from __future__ import annotations

import ctypes as C
import json

from gap_support import SRC, env  # noqa: F401  (sets nothing; keeps the import path uniform)
from odo_tools.gap.simlib import Opts, Result, RowEx, lib

ROBOT = json.loads((SRC / "host_sim/robots/labmate.json").read_text())


def run(**hidden: float) -> tuple[Result, int]:
    so = lib()
    err = C.create_string_buffer(256)
    s = so.odosim_setup_parse(json.dumps(ROBOT).encode(), b'{"effects": {}}', err, 256)
    assert s, err.value
    o = Opts(b"umbmark", 0, 0, 10.0, 0, 7, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for k, v in hidden.items():
        setattr(o, k, v)
    res = Result()
    rows = (RowEx * 4000)()
    n = C.c_size_t(0)
    rc = so.odosim_run_ex(s, C.byref(o), rows, 4000, None, 0, C.byref(n), C.byref(res), err, 256)
    so.odosim_setup_free(s)
    return res, rc


def test_all_hidden_off_is_the_plain_run_and_each_effect_moves_the_truth() -> None:
    so = lib()
    err = C.create_string_buffer(256)
    s = so.odosim_setup_parse(json.dumps(ROBOT).encode(), b'{"effects": {}}', err, 256)
    so.odosim_run.argtypes = [C.c_void_p, C.c_char_p, C.c_int, C.c_int, C.c_int, C.c_uint64,
                              C.c_uint, C.c_void_p, C.c_size_t, C.POINTER(Result), C.c_char_p,
                              C.c_size_t]
    plain = Result()
    assert so.odosim_run(s, b"umbmark", 0, 0, 0, 7, 0, None, 0, C.byref(plain), err, 256) == 0
    so.odosim_setup_free(s)
    off, rc = run()
    assert rc == 0 and (off.x_abs_mm, off.y_abs_mm) == (plain.x_abs_mm, plain.y_abs_mm)
    for h in ({"backlash_rad": 0.05}, {"diam_var_amp": 0.02, "diam_var_period_s": 30.0}):
        r, rc = run(**h)
        assert rc == 0
        assert abs(r.x_abs_mm - off.x_abs_mm) + abs(r.y_abs_mm - off.y_abs_mm) > 0.5, h
    # the follower closes its loop on the counts, so a motor lag changes the run only slightly
    lag, rc = run(motor_tau_s=0.02)
    assert rc == 0 and lag.t_end_s >= off.t_end_s and (lag.y_abs_mm != off.y_abs_mm)
    _, rc = run(diam_var_amp=0.02)      # an amplitude without a period is refused
    assert rc != 0
