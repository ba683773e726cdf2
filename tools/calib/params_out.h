/// The one parameter-block writer odo-calib's commands share (`umbmark --out-params`, `fit`): in
/// the odo_calib library, not in odo-calib.c, so the commands depend on it and not on main's file.
#ifndef CALIB_PARAMS_OUT_H
#define CALIB_PARAMS_OUT_H

#include "odo/odo_params.h"
#include "odo_out.h"

/// Write a parameter block, JSON or the raw block by the name's extension (.bin), by
/// hostlib/odo_out.h's rule (a temp beside it, renamed into place; never one of `ins`, never a
/// special file). Returns 0, or -1 (message on stderr).
int calib_write_params(const char *path, const odo_params_t *p, const odo_out_inputs_t *ins);

#endif
