/// hal_log: a candump -l log as a frame source, line by line, with the line number of every
/// frame for error messages. Reads in fixed 1 MiB chunks (any file size, constant memory).
///
/// Two layers:
///  - hal_log_t (this header): open / next frame / close. No hal_* symbols, so a program can link
///    it beside another backend (odo-replay links it with hal_socketcan_core).
///  - hal_log_backend.h: the same reader behind hal/hal.h (link-time backend `hal_log`).
///
/// Threading: one thread per reader. Errors are returned with a message; nothing asserts on the
/// file's content.
#ifndef HAL_LOG_H
#define HAL_LOG_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "candump_parse.h"

#ifdef __cplusplus
extern "C" {
#endif

#define HAL_LOG_CHUNK   (1U << 20) ///< read size; also the longest line accepted
#define HAL_LOG_ERR_MAX 320U

typedef enum {
    HAL_LOG_FRAME = 0, ///< *out holds the next frame
    HAL_LOG_EOF,       ///< no more lines
    HAL_LOG_ERROR      ///< read error or malformed line: err holds "PATH:LINE: why"
} hal_log_status_t;

/// What the reader saw; counters only increase.
typedef struct {
    uint64_t lines;        ///< lines read, blank ones included
    uint64_t frames;       ///< frames returned
    uint64_t blank;        ///< blank lines skipped
    uint64_t fd_skipped;   ///< CAN FD lines ("##") skipped: another node's traffic
    uint64_t error_frames; ///< frames with ODO_CAN_FLAG_ERR
    uint64_t rtr_frames;   ///< frames with ODO_CAN_FLAG_RTR
    uint64_t ext_frames;   ///< frames with ODO_CAN_FLAG_EXT
} hal_log_stats_t;

typedef struct {
    FILE *f;
    bool own_f;        ///< close f in hal_log_close
    char *buf;         ///< HAL_LOG_CHUNK bytes
    size_t start, end; ///< unread bytes are buf[start, end)
    bool eof;
    uint64_t line_no; ///< 1-based number of the line last returned
    hal_log_stats_t stats;
    char path[256];
    char err[HAL_LOG_ERR_MAX];
} hal_log_t;

/// Open `path` ("-" is stdin). Returns 0, or -1 with l->err set (cannot open, out of memory).
int hal_log_open(hal_log_t *l, const char *path);

/// Next frame of the log (blank and CAN FD lines skipped and counted). Returns HAL_LOG_ERROR on the first malformed line
/// (err: "PATH:LINE: why"), on a read error, and on a line longer than HAL_LOG_CHUNK. O(line).
hal_log_status_t hal_log_next(hal_log_t *l, candump_line_t *out);

/// Release the buffer and the file. Safe on a reader that failed to open.
void hal_log_close(hal_log_t *l);

/// Format one frame as a candump -l line ("(sec.usec) iface ID#DATA\n", upper-case hex, 3- or
/// 8-digit ID, "R" for remote requests, error frames with the 0x20000000 bit) into buf. Returns the
/// length written (no NUL), at most CANDUMP_LINE_MAX. The same text as tools/lib candump.h writes.
#define CANDUMP_LINE_MAX 80U
size_t candump_format_line(char *buf, uint64_t t_us, const char *iface, const odo_can_frame_t *f);

#ifdef __cplusplus
}
#endif
#endif
