/// odo_cli: the command-line vocabulary the C CLIs share (issue 17), one place.
///
/// Every CLI parses with getopt_long (so `--opt=value` and `--opt value` both work) and knows:
///   --help            usage on stdout, exit 0
///   --version         "PROG VERSION" on stdout (CMake's project version), exit 0
///   --out PATH        where results go (a file or a folder, per tool), by hostlib/odo_out.h's rule
///   --force           write into a non-empty folder the tool did not write (removing nothing)
///   --robot R.json    robot description (host_sim/robots/)
///   --params P        a parameter block, JSON or raw .bin
///   --json            machine-readable output on stdout
///   --quiet           no progress on stderr
///   --ipec MODE       off | on | paper | estimator (on = paper)
///   --seed S          non-negative integer
/// Exit status everywhere: 0 ok, 1 rejected input or I/O error, 2 usage error.
#ifndef ODO_CLI_H
#define ODO_CLI_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/// The project version ("0.1.0"), from CMakeLists.txt's project(VERSION).
const char *odo_cli_version(void);

/// Print "PROG VERSION\n" on stdout.
void odo_cli_print_version(const char *prog);

/// --ipec MODE: 0 off, 1 paper (also "on"), 2 estimator. -1 with a message on stderr naming
/// PROG and the bad value otherwise.
int odo_cli_ipec(const char *prog, const char *value);

/// --seed S: a non-negative decimal integer that fits 64 bits. false with a message otherwise.
bool odo_cli_seed(const char *prog, const char *value, uint64_t *seed);

/// A decimal integer in [lo, hi] for option NAME. false with a message otherwise.
bool odo_cli_long(const char *prog, const char *name, const char *value, long lo, long hi, long *out);

/// For the CLIs whose options take lists (odo-calib fit --runs A B ...) and so parse by hand: split
/// every "--name=value" argument into "--name" "value", as getopt_long reads it. Replaces *argv
/// with a new array (allocated once for the process' life); false only when out of memory.
bool odo_cli_split_equals(int *argc, char ***argv);

/// getopt_long's "unknown option / missing value" has been printed; add the pointer to --help.
void odo_cli_usage_hint(const char *prog);

#ifdef __cplusplus
}
#endif
#endif /* ODO_CLI_H */
