/// `odo-calib acceptance`: the acceptance numbers, computed by simulation (host_sim's
/// software-in-the-loop runner, in process). See tools/calib/README.md.
#ifndef CALIB_ACCEPTANCE_H
#define CALIB_ACCEPTANCE_H

/// argv after "acceptance". Returns the process exit status.
int calib_acceptance_main(int argc, char **argv);

#endif
