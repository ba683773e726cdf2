/// Wheel counters from HCTL-1100 decoders on GPIO: the chip's 8-bit multiplexed bus driven by
/// port pins (HCTL-1100 data sheet: "Bus Interface", "Actual Position Registers R12H-R14H").
///
/// Wiring: D0-D7 on pins 0-7 of `data` (the low byte of one port), ALE, /OE and R/W on `ctrl`,
/// one /CS per chip on `ctrl`. R/W is held high (read): the driver never writes to the chip.
/// One register read:
///   1. D0-D7 as outputs carrying the register address; /CS low; ALE high then low: the chip
///      latches the address on ALE's falling edge;
///   2. D0-D7 as inputs; /OE low; wait `settle_loops`; read IDR[7:0]; /OE high; /CS high.
/// Position: R14H (LSB, which latches the upper bytes), R13H, R12H, in that order: the latch
/// order of the chip and of the simulator's emulator (host_sim/src/hctl1100.h), so the three
/// bytes belong to one count even while the wheel turns. The 24-bit count wraps; samples carry
/// bits = 24.
///
/// GPIO registers: RM0090 section 8.4 (MODER, IDR, BSRR). Cost: 3 x (4 BSRR writes, 2 MODER
/// writes, 1 IDR read) plus the settle loops per position. Not reentrant per bus.
#ifndef ODO_HCTL_BUS_H
#define ODO_HCTL_BUS_H

#include <stdint.h>

#include "stm32f4_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_HCTL_MAX_CHIPS 4U

#define ODO_HCTL_R12H 0x12U ///< actual position bits 23..16
#define ODO_HCTL_R13H 0x13U ///< actual position bits 15..8
#define ODO_HCTL_R14H 0x14U ///< actual position bits 7..0; reading it latches R12H/R13H
#define ODO_HCTL_BITS 24U

typedef struct {
    odo_stm32_gpio_t *data; ///< D0-D7 on pins 0-7
    odo_stm32_gpio_t *ctrl; ///< ALE, /OE, R/W and the /CS lines
    uint8_t ale_pin;
    uint8_t oe_pin;
    uint8_t rw_pin;
    uint8_t cs_pin[ODO_HCTL_MAX_CHIPS];
    uint8_t chips;         ///< 1..ODO_HCTL_MAX_CHIPS
    uint32_t settle_loops; ///< busy-wait iterations between /OE low and the IDR read
} odo_hctl_bus_t;

/// Idle levels (/CS, /OE high, ALE low, R/W high), control pins as outputs, data pins as inputs.
void odo_hctl_bus_init(const odo_hctl_bus_t *bus);

/// One register of chip `chip` (< bus->chips) as described above.
uint8_t odo_hctl_read_reg(const odo_hctl_bus_t *bus, uint8_t chip, uint8_t reg);

/// The 24-bit actual position of chip `chip`: R14H, R13H, R12H.
uint32_t odo_hctl_read_position(const odo_hctl_bus_t *bus, uint8_t chip);

#ifdef __cplusplus
}
#endif
#endif
