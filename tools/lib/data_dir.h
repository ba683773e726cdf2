/// Where a CLI finds the files the project ships with it: can/odometry.dbc,
/// host_sim/robots/<vehicle>.json, host_sim/scenarios/*.json. Paths are given relative to a data
/// root, which is, in order:
///   1. $ODO_SOURCE_DIR, when set and not empty;
///   2. the checkout a build-tree binary sits in: ROOT/build/<preset>/bin/<exe> -> ROOT,
///      recognised by ROOT/can/odometry.dbc;
///   3. the install prefix the binary runs from: PREFIX/bin/<exe> -> PREFIX/share/odometry, which
///      `cmake --install` and the .deb lay out like the repository (cmake/OdoInstall.cmake).
/// When neither 2 nor 3 holds the file, 3 is used, so an error names the installed path.
///
/// Host C99 + POSIX (readlink of /proc/self/exe, stat); reentrant; a few system calls.
#ifndef ODO_DATA_DIR_H
#define ODO_DATA_DIR_H

#include <stddef.h>

/// Write "<data root>/<rel>" into out (NUL-terminated). Returns 0, or -1 when it does not fit in
/// out_len bytes (out then holds "").
int odo_data_path(const char *rel, char *out, size_t out_len);

#endif
