/// hal_socketcan as a hal/hal.h backend (library `hal_socketcan`): hal_can_recv/hal_can_send on a
/// CAN_RAW socket, hal_time_us on the receive-timestamp clock (CLOCK_REALTIME: it follows wall
/// clock steps, which a Linux box running NTP slews). The counters arrive as CAN frames, so
/// hal_wheel_read and hal_link_read return false; the caller assembles tick inputs from frames.
#ifndef HAL_SOCKETCAN_BACKEND_H
#define HAL_SOCKETCAN_BACKEND_H

#include "hal.h"
#include "hal_socketcan.h"

struct hal_ctx {
    hal_socketcan_t sc;
};

#endif
