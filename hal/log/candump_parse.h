/// candump -l line parser: the grammar can-utils' candump writes and canplayer reads, classic CAN
/// only. Pure (no I/O, no allocation, no globals), reentrant, O(line length).
///
/// Grammar (one frame per line; the line may end in "\n" or "\r\n"):
///
///   line      = "(" seconds "." fraction ")" " " iface " " frame [ " R" | " T" ]
///   seconds   = 1..19 decimal digits           fraction = 1..9 decimal digits (scaled to us,
///                                                          digits past the 6th are truncated)
///   iface     = 1..15 printable ASCII characters (0x21..0x7E), none of them '(' or ')'
///   frame     = sff "#" data | eff "#" data | id "#R" [dlc]
///   sff       = 3 hex digits, value <= 0x7FF             -> standard frame
///   eff       = 8 hex digits, value <= 0x1FFFFFFF        -> extended frame (ODO_CAN_FLAG_EXT)
///             | 8 hex digits with bit 0x20000000 set     -> error frame (ODO_CAN_FLAG_ERR); the
///                                                           low 29 bits are the error class
///   data      = 0..8 bytes, two hex digits each (either case), optionally separated by "."
///   dlc       = one decimal digit 0..8 (RTR frames only; data bytes stay zero)
///
/// CAN FD lines ("##" flags digit, 0..64 data bytes, optional " R"/" T") are another node's traffic
/// on a mixed bus: CANDUMP_FD, so readers count and skip them (t_us and iface are filled).
///
/// Rejected with a message that says why: a malformed CAN FD line, CAN XL, more than 8 data bytes, an odd
/// hex digit, an identifier of another width, a standard identifier above 0x7FF, identifier bits
/// 30..31 set, a malformed timestamp, anything after the frame but " R"/" T". Blank lines are
/// reported as CANDUMP_BLANK, so a reader can skip them.
#ifndef ODO_CANDUMP_PARSE_H
#define ODO_CANDUMP_PARSE_H

#include <stddef.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Longest interface name (IFNAMSIZ - 1).
#define CANDUMP_IFACE_MAX 15U

typedef enum {
    CANDUMP_OK = 0, ///< *frame, *t_us, iface written
    CANDUMP_BLANK,  ///< empty or whitespace-only line; outputs untouched
    CANDUMP_ERR,    ///< malformed; *why names the problem (static string); outputs unspecified
    CANDUMP_FD      ///< a well-formed CAN FD line: not a classic frame; t_us and iface written
} candump_result_t;

/// One parsed line, as the log wrote it.
typedef struct {
    uint64_t t_us;                     ///< timestamp, microseconds
    odo_can_frame_t frame;             ///< id without flag bits; flags ODO_CAN_FLAG_*
    char iface[CANDUMP_IFACE_MAX + 1]; ///< NUL-terminated
    char direction;                    ///< 'R', 'T', or 0 when the line has none
} candump_line_t;

/// Parse `len` bytes of one line (without or with its trailing newline). Returns CANDUMP_OK,
/// CANDUMP_BLANK, or CANDUMP_ERR with *why set to a short explanation naming the offending
/// part. Never reads beyond line[len - 1]; `line` need not be NUL-terminated.
candump_result_t candump_parse_line(const char *line, size_t len, candump_line_t *out, const char **why);

#ifdef __cplusplus
}
#endif
#endif
