/// `odo-calib fit` and the one output writer odo-calib's commands share.
#ifndef CALIB_FIT_CLI_H
#define CALIB_FIT_CLI_H

#include "odo/odo_params.h"

/// odo-calib fit [options] (argv without "odo-calib fit"). Returns the exit status.
int calib_fit_main(int argc, char **argv);

/// Write a parameter block, JSON or the raw 128-byte block by the name's extension (.bin), through
/// a temporary file beside it that is renamed into place. Returns 0, or -1 (message on stderr).
int calib_write_params(const char *path, const odo_params_t *p);

#endif
