/// `odo-ipec goals`: IPEC's acceptance figures as JSON (tools/ipec/README.md).
#ifndef IPEC_GOALS_H
#define IPEC_GOALS_H

/// Parse the command's arguments (after "goals"), run every case, print JSON. Exit status.
int ipec_cmd_goals(int argc, char **argv);

#endif
