/// Register-level fake of the STM32F4 peripherals the board port drives, for host tests. The
/// drivers' odo_reg_read/odo_reg_write (hal/cortexm/odo_reg.h, built with ODO_REG_FAKE) land here;
/// a register inside one of the fake peripheral blocks below gets its hardware behaviour, as RM0090
/// describes it, for the bits the port uses:
///   RCC   HSIRDY/HSERDY/PLLRDY follow HSION/HSEON/PLLON when that oscillator "works"; SWS follows
///         SW when the selected clock is ready
///   GPIO  BSRR sets/resets ODR bits and reads 0; IDR[7:0] of the data port is what an HCTL-1100
///         drives while its /CS and /OE are low (host_sim's emulator: the same chip model the
///         simulator reads)
///   TIM   SR is rc_w0; EGR.UG clears CNT
///   bxCAN INAK follows INRQ (unless stuck), SLAK follows SLEEP; FIFO 0 serves a queue of frames
///         (FMP0, RFOM0 pops, FOVR0 rc_w1); a TXRQ write logs the mailbox and frees it
///   IWDG  PR/RLR accept writes only after the 0x5555 key; 0xAAAA counts reloads and relocks
/// Every other register is plain memory. One fake per process (the drivers take addresses).
#ifndef FAKE_STM32_H
#define FAKE_STM32_H

#include <stdbool.h>
#include <stdint.h>

#include "hctl1100.h"
#include "stm32f4_regs.h"

#define FAKE_CAN_QUEUE 128U
#define FAKE_CAN_LOG   1024U
#define FAKE_TIMS      6U

typedef struct {
    uint32_t ir, dtr, dlr, dhr; ///< RIR/TIR, RDTR/TDTR, RDLR/TDLR, RDHR/TDHR as the hardware has them
} fake_can_mb_t;

typedef struct {
    odo_stm32_rcc_t rcc;
    odo_stm32_flash_t flash;
    odo_stm32_gpio_t gpio[2]; ///< [0]: HCTL data port, [1]: control port (also CAN/encoder pins)
    odo_stm32_tim_t tim[FAKE_TIMS];
    odo_stm32_can_t can;
    odo_stm32_iwdg_t iwdg;

    /* What the "hardware" does. */
    bool hse_works;
    bool pll_locks;
    bool can_stuck_in_init; ///< INAK never clears (no recessive bus), or never sets (no clock)
    bool can_no_clock;

    /* Models. */
    fake_can_mb_t rxq[FAKE_CAN_QUEUE];
    uint32_t rxq_head, rxq_len;
    bool rx_overrun;
    fake_can_mb_t txlog[FAKE_CAN_LOG];
    uint32_t txlog_len;
    bool iwdg_unlocked, iwdg_started;
    uint32_t iwdg_reloads, iwdg_ignored_writes;
    uint64_t reads; ///< every odo_reg_read, to check that waits are bounded

    /* HCTL-1100 chips on the GPIO bus (fake_stm32_hctl_attach). */
    odosim_hctl_t *chip[4];
    uint8_t n_chips;
    uint8_t ale_pin, oe_pin, cs_pin[4];
    uint8_t latched_addr[4];
    int driving; ///< chip driving D0-D7, or -1
    uint8_t driven;
    void (*on_read)(void *user, uint8_t chip, uint8_t reg); ///< before each chip read
    void *user;
} fake_stm32_t;

extern fake_stm32_t fake;

/// Reset every register to 0 and every model to its idle state (hse_works and pll_locks true).
void fake_stm32_reset(void);

/// Attach chips to the bus wired as odo_hctl_bus_t says (data = gpio[0], ctrl = gpio[1]).
void fake_stm32_hctl_attach(odosim_hctl_t *const *chips, uint8_t n, uint8_t ale_pin, uint8_t oe_pin,
                            const uint8_t *cs_pins);

/// Queue a received frame as the controller would present it: standard or extended ID, RTR,
/// raw DLC field 0..15, data bytes.
void fake_stm32_can_rx(uint32_t id, bool ext, bool rtr, uint8_t raw_dlc, const uint8_t data[8]);

#endif
