/// candump -l log lines: "(sec.usec) iface ID#HEX", the format can-utils' canplayer/candump,
/// python-can and cantools read as they are (DESIGN.md s. 4).
#ifndef ODO_CANDUMP_H
#define ODO_CANDUMP_H

#include <stdint.h>
#include <stdio.h>

#include "odo/odo_types.h"

/// Write one frame as a candump -l line: 3-hex standard or 8-hex extended ID, data in upper-case
/// hex, "R" for remote frames. Returns 0, or -1 if the stream reported an error.
int odo_candump_write(FILE *f, uint64_t t_us, const char *iface, const odo_can_frame_t *frame);

#endif
