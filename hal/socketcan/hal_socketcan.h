/// hal_socketcan: Linux SocketCAN (CAN_RAW) frame I/O for odo-replay's live mode and the
/// `hal_socketcan` hal.h backend (hal_socketcan_backend.h).
///
/// - One CAN_RAW socket bound to one interface, non-blocking, with kernel receive timestamps
///   (SO_TIMESTAMP, CLOCK_REALTIME microseconds) and the socket's drop counter (SO_RXQ_OVFL).
/// - Acceptance filters: only standard data frames with the listed identifiers reach the reader
///   (the kernel drops the rest, like a controller's hardware filters); error frames of every
///   class are always subscribed and returned with ODO_CAN_FLAG_ERR (bus-off counted apart).
/// - Interface down: a read or write fails with ENETDOWN; the call returns HAL_SC_DOWN and counts
///   it. hal_socketcan_check_up() polls the interface flags and re-opens the socket if the
///   interface was deleted and re-created; frames flow again once it is up.
/// - ENOBUFS/EAGAIN on send (queue full): wait up to HAL_SC_SEND_WAIT_MS for room, retry once,
///   then give up and count the frame as dropped; the caller's tick goes on.
///
/// No hal_* symbols here, so odo-replay can link it beside the log reader. One thread per socket.
/// libsocketcan is not needed: vcan has no controller state to query, and the interface flags
/// come from SIOCGIFFLAGS.
#ifndef HAL_SOCKETCAN_H
#define HAL_SOCKETCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define HAL_SC_MAX_FILTERS  16U
#define HAL_SC_SEND_WAIT_MS 2

/// Counters only increase.
typedef struct {
    uint64_t rx_frames;    ///< frames returned by hal_socketcan_recv (error frames included)
    uint64_t error_frames; ///< error frames (any class)
    uint64_t bus_off;      ///< error frames with the bus-off class (CAN_ERR_BUSOFF)
    uint64_t rx_dropped;   ///< frames the kernel dropped because our queue was full (SO_RXQ_OVFL)
    uint64_t tx_frames;    ///< frames sent
    uint64_t tx_retries;   ///< sends that hit ENOBUFS/EAGAIN and were retried
    uint64_t tx_dropped;   ///< sends given up (queue still full, interface down, other errors)
    uint64_t down_events;  ///< reads/writes that found the interface down
    uint64_t reopens;      ///< sockets re-opened after the interface came back with a new index
} hal_sc_stats_t;

typedef struct {
    int fd;
    int ifindex;
    bool up; ///< last known interface state
    char ifname[16];
    uint32_t ids[HAL_SC_MAX_FILTERS];
    size_t n_ids;
    uint32_t kernel_drops; ///< last SO_RXQ_OVFL value seen
    hal_sc_stats_t stats;
    char err[256];
} hal_socketcan_t;

typedef enum {
    HAL_SC_FRAME = 0, ///< *frame and *t_us written
    HAL_SC_NONE,      ///< nothing waiting
    HAL_SC_DOWN,      ///< the interface is down (counted); try hal_socketcan_check_up later
    HAL_SC_ERROR      ///< other socket error; err says which
} hal_sc_status_t;

/// Open a CAN_RAW socket on `ifname` that receives only standard data frames with the `n_ids`
/// identifiers in `ids` (n_ids 0: every data frame) plus all error frames. Returns 0, or -1 with
/// s->err set: no CAN in this kernel (socket(AF_CAN) fails with EAFNOSUPPORT: load can, can_raw),
/// no such interface, not a CAN interface, interface down, n_ids > HAL_SC_MAX_FILTERS.
int hal_socketcan_open(hal_socketcan_t *s, const char *ifname, const uint32_t *ids, size_t n_ids);

/// Wait until a frame is readable or timeout_ms passes (< 0: forever). Returns 1 readable, 0
/// timeout or signal, -1 on a poll error (err set). POLLERR (interface down) returns 1: the next
/// hal_socketcan_recv reports it.
int hal_socketcan_wait(hal_socketcan_t *s, int timeout_ms);

/// Take one received frame without blocking. *t_us is the kernel's receive time (CLOCK_REALTIME).
hal_sc_status_t hal_socketcan_recv(hal_socketcan_t *s, odo_can_frame_t *frame, uint64_t *t_us);

/// Send one classic frame. Returns false iff it was not sent (counted in stats.tx_dropped; see
/// the ENOBUFS rule above). Blocks at most HAL_SC_SEND_WAIT_MS.
bool hal_socketcan_send(hal_socketcan_t *s, const odo_can_frame_t *frame);

/// Re-read the interface state; re-open the socket if the interface was re-created. Returns true
/// iff it is up (and the socket usable).
bool hal_socketcan_check_up(hal_socketcan_t *s);

/// Close the socket. Safe on a handle that failed to open.
void hal_socketcan_close(hal_socketcan_t *s);

/// Now on the clock of the receive timestamps (CLOCK_REALTIME), microseconds.
uint64_t hal_socketcan_now_us(void);

#ifdef __cplusplus
}
#endif
#endif
