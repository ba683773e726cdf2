/// `odo-calib fit`.
#ifndef CALIB_FIT_CLI_H
#define CALIB_FIT_CLI_H

#include "odo/odo_params.h"
#include "odo_out.h"

/// odo-calib fit [options] (argv without "odo-calib fit"). Returns the exit status.
int calib_fit_main(int argc, char **argv);

#endif
