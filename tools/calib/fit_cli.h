/// `odo-calib fit` and the one output writer odo-calib's commands share.
#ifndef CALIB_FIT_CLI_H
#define CALIB_FIT_CLI_H

#include "odo/odo_params.h"
#include "odo_out.h"

/// odo-calib fit [options] (argv without "odo-calib fit"). Returns the exit status.
int calib_fit_main(int argc, char **argv);

/// Write a parameter block, JSON or the raw block by the name's extension (.bin), by
/// hostlib/odo_out.h's rule (a temp beside it, renamed into place; never one of `ins`, never a
/// special file). Returns 0, or -1 (message on stderr).
int calib_write_params(const char *path, const odo_params_t *p, const odo_out_inputs_t *ins);

#endif
