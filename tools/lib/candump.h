/// candump -l log lines: "(sec.usec) iface ID#HEX", the format can-utils' canplayer/candump,
/// python-can and cantools read as they are (DESIGN.md s. 4).
#ifndef ODO_CANDUMP_H
#define ODO_CANDUMP_H

#include <stdint.h>
#include <stdio.h>

#include "odo/odo_types.h"

/// Largest log start odo_log_start_parse accepts: 2^33 s after the epoch (year 2242).
#define ODO_LOG_START_MAX_S 8589934592ULL

/// A log's start time, as a CLI takes it (`--log-start`): "now", the wall clock rounded down to
/// a whole second, or a whole number of seconds since the Unix epoch, 0..ODO_LOG_START_MAX_S
/// ("0" for reproducible test vectors). A writer stamps each frame start + the run's own time, so
/// the sub-second digits of a log are the run's clock; the truth CSV beside a log is on the same
/// clock, and readers pair the two by time, never by assuming a log starts at 0.
/// Returns 0 with *start_us set, or -1 (*start_us untouched) for anything else.
int odo_log_start_parse(const char *text, uint64_t *start_us);

/// The start a recording tool uses when not told: $SOURCE_DATE_EPOCH when it is set (the
/// reproducible-builds convention; tests set it to 0), else "now". Returns 0, or -1 when
/// SOURCE_DATE_EPOCH is set but not whole seconds 0..ODO_LOG_START_MAX_S.
int odo_log_start_default(uint64_t *start_us);

/// Write one frame as a candump -l line: 3-hex standard or 8-hex extended ID, data in upper-case
/// hex, "R" for remote frames. Returns 0, or -1 if the stream reported an error.
int odo_candump_write(FILE *f, uint64_t t_us, const char *iface, const odo_can_frame_t *frame);

#endif
