/// The STM32F405/407 board port: which peripheral does what (odo_board_config_t), the hal.h
/// backend over those peripherals (struct hal_ctx), board start-up and the 40 ms tick.
///
/// Wheel counters per truck come from one of: two timers in quadrature-encoder mode (the modern
/// stand-in for the HCTL-1100), two HCTL-1100 decoders on the GPIO bus, or WHEEL_COUNTS frames on
/// CAN. The linkage encoders of a two-truck vehicle arrive on CAN (LINK_ROTARY, LINK_LINEAR). The
/// acceptance filters hold the identifiers of the frames consumed, taken from odo/odo_can.h (which
/// tests/python/test_can_dbc.py checks against can/odometry.dbc).
///
/// odo_board_tick is the board's version of firmware/app's odo_loop_tick: the same read-step-
/// publish order through hal.h, plus the receive path (odo_board_rx.h), whose fault bits reach the
/// step through odo_tick_input_t.rx_faults (odo_loop_tick has no path for them).
#ifndef ODO_BOARD_PORT_H
#define ODO_BOARD_PORT_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"
#include "odo/odo_app.h"
#include "odo_board_rx.h"
#include "odo_bxcan.h"
#include "odo_clock.h"
#include "odo_hctl_bus.h"
#include "stm32f4_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    ODO_WHEELS_NONE = 0,    ///< no such truck (hal_wheel_read returns false)
    ODO_WHEELS_ENCODER = 1, ///< timers in encoder mode
    ODO_WHEELS_HCTL = 2,    ///< HCTL-1100 decoders on the GPIO bus
    ODO_WHEELS_CAN = 3      ///< WHEEL_COUNTS frames
} odo_wheel_source_t;

/// One pin in alternate-function mode (RM0090 8.3.2: AF number per pin in AFRL/AFRH).
typedef struct {
    odo_stm32_gpio_t *port;
    uint8_t port_index; ///< 0 = GPIOA .. 8 = GPIOI (its RCC_AHB1ENR bit)
    uint8_t pin;
    uint8_t af;
} odo_pin_t;

typedef struct {
    odo_wheel_source_t source;
    odo_stm32_tim_t *tim[2]; ///< ENCODER: left, right
    uint32_t tim_apb1enr[2]; ///< their RCC_APB1ENR bits
    uint8_t tim_bits[2];     ///< 16 (TIM3/4) or 32 (TIM2/5)
    odo_pin_t ti[2][2];      ///< ENCODER: TI1, TI2 of each wheel
    bool invert[2];          ///< count direction reversed (encoder mounted mirrored)
    uint8_t hctl_chip[2];    ///< HCTL: chip index of left, right on the bus
} odo_truck_io_t;

typedef struct {
    odo_stm32_rcc_t *rcc;
    odo_stm32_flash_t *flash;
    odo_stm32_iwdg_t *iwdg;
    odo_stm32_can_t *can;
    odo_stm32_tim_t *tick_tim;
    uint32_t tick_tim_apb1enr;
    uint32_t hse_hz;      ///< crystal (0: none, run from HSI)
    uint32_t tick_us;     ///< step period; the parameter block's tick_us should match
    uint32_t can_bitrate; ///< bit/s, e.g. 500000
    odo_pin_t can_rx;
    odo_pin_t can_tx;
    uint32_t watchdog_ms;   ///< 0: no watchdog
    uint32_t polls;         ///< bound of every hardware wait, in register reads
    uint8_t encoder_filter; ///< IC1F/IC2F of the encoder timers
    odo_truck_io_t truck[ODO_TRUCKS];
    odo_hctl_bus_t hctl;
    uint8_t hctl_port_index[2]; ///< data, ctrl ports (RCC_AHB1ENR bits)
} odo_board_config_t;

/// What start-up found; kept in RAM (odo_board_status in the image) for a debugger.
typedef struct {
    odo_clock_t clock;
    odo_bxcan_status_t can; ///< ODO_BXCAN_OK or why CAN is down (the loop runs anyway)
    bool tick_ok;
    bool watchdog_ok;
    uint32_t tick_overruns; ///< periods that ended while the previous tick still ran
    uint32_t tx_refused;    ///< frames no mailbox took
} odo_board_status_t;

/// The hal.h backend's context.
struct hal_ctx {
    const odo_board_config_t *cfg;
    odo_board_status_t status;
    odo_board_rx_t rx;
    odo_wheel_input_t can_wheel[ODO_TRUCKS]; ///< this tick's WHEEL_COUNTS samples
    odo_link_input_t link;                   ///< this tick's linkage samples
    uint8_t seq[ODO_TRUCKS];                 ///< sample numbers of local counters
    uint64_t periods;                        ///< tick periods elapsed since start
};

/// Clocks, pins, counters, CAN, tick timer and (last) the watchdog, from *cfg (kept by pointer).
/// Never blocks beyond cfg->polls reads per wait; a peripheral that does not come up is recorded
/// in hal->status and the board runs without it.
void odo_board_init(hal_ctx_t *hal, const odo_board_config_t *cfg);

/// Wait for the next period of the tick timer (polling; counts overruns). Returns false iff the
/// tick timer is not running (then it returns at once).
bool odo_board_wait_tick(hal_ctx_t *hal);

/// One tick: drain received frames into the receive path, read the counters (hal_wheel_read),
/// take the linkage samples (hal_link_read), odo_app_step with the receive faults in rx_faults,
/// send the output frames (refusals counted in app->tx_dropped), refresh the watchdog.
void odo_board_tick(hal_ctx_t *hal, odo_app_t *app, odo_tick_input_t *in, odo_tick_output_t *out);

#ifdef __cplusplus
}
#endif
#endif
