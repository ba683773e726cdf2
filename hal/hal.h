/// The hardware abstraction layer: the only door between firmware/app and the world.
///
/// A backend is a separate library that defines `struct hal_ctx` and implements every function
/// below; which backend a program uses is chosen when it is linked: hal_test (scripted, unit
/// tests), hal_sim (the simulator's decoder emulators), hal_log (a candump log) and
/// hal_socketcan (Linux CAN_RAW); hal/README.md lists them. The Cortex-M4 image has no backend
/// yet (hal/cortexm/main.c runs a synthetic self-test). The firmware core never calls these; only
/// firmware/app/odo_loop.c does.
///
/// Threading: a context is used from one thread. Only hal_can_send may wait, and only as long as
/// its backend states (hal_socketcan: up to 2 ms for room in the queue, then the frame is
/// dropped); everything else returns at once. Errors are reported by return value and counted by
/// the backend; nothing here asserts on external input.
#ifndef HAL_H
#define HAL_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Backend-defined context (opaque to the firmware).
typedef struct hal_ctx hal_ctx_t;

/// Latest wheel-counter sample of a truck (ODO_TRUCK_A/B). Returns false iff the truck has no
/// counters in this backend; out->present tells whether a new sample arrived since the last call.
bool hal_wheel_read(hal_ctx_t *ctx, uint8_t truck, odo_wheel_input_t *out);

/// Latest linkage-encoder sample. Returns false iff the vehicle has no linkage encoders.
bool hal_link_read(hal_ctx_t *ctx, odo_link_input_t *out);

/// Queue one frame for transmission. Returns false iff it could not be queued (bus off, buffer
/// full, write error); the caller counts it and carries on: a step is never lost for a failed
/// send. May wait for room as long as the backend states (see the banner); never longer.
bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame);

/// Take one received frame, if any, without blocking. Returns false iff none is waiting.
/// *t_us is the receive timestamp on the hal_time_us clock.
bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us);

/// Time in microseconds, on the clock hal_can_recv stamps frames with. Monotonic on hal_test and
/// hal_sim; hal_log returns the timestamp of the frame last received and hal_socketcan the
/// kernel's CLOCK_REALTIME (its SO_TIMESTAMP clock), both of which can step backwards: the
/// application flags that (ODO_FAULT_TIME_BACKWARDS) and keeps integrating counts.
uint64_t hal_time_us(hal_ctx_t *ctx);

#ifdef __cplusplus
}
#endif
#endif
