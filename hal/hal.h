/// The hardware abstraction layer: the only door between firmware/app and the world.
///
/// A backend is a separate library that defines `struct hal_ctx` and implements every function
/// below; which backend a program uses is chosen when it is linked (hal_test for unit tests, and
/// later sim, socketcan, log and cortexm). The firmware core never calls these; only
/// firmware/app/odo_loop.c does.
///
/// Threading: a context is used from one thread. Functions never block longer than the timeout
/// their entry states. Errors are reported by return value and counted by the backend; nothing
/// here asserts on external input.
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
/// full); the caller counts it and carries on: a step is never lost for a failed send.
bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame);

/// Take one received frame, if any, without blocking. Returns false iff none is waiting.
/// *t_us is the receive timestamp on the hal_time_us clock.
bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us);

/// Monotonic time in microseconds.
uint64_t hal_time_us(hal_ctx_t *ctx);

#ifdef __cplusplus
}
#endif
#endif
