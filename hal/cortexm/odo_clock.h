/// System clock of the STM32F405/407: 168 MHz from the HSE crystal through the main PLL, or from
/// the 16 MHz HSI through the same PLL when the crystal does not start (RM0090, RCC chapter for
/// F405xx/07xx: 'Clocks'; flash wait states: section 3.5.1).
///
///   VCO input = source / PLLM = 1 MHz, VCO = 336 MHz (PLLN 336), SYSCLK = VCO / 2 = 168 MHz,
///   PLL48CK = VCO / 7 = 48 MHz; AHB /1 (168 MHz), APB1 /4 (42 MHz, its timers 84 MHz),
///   APB2 /2 (84 MHz, its timers 168 MHz); flash 5 wait states with prefetch and both caches
///   (168 MHz at 2.7-3.6 V).
///
/// Every wait is bounded: HSE startup, PLL lock and the switch each get `polls` register reads. A
/// part (or an emulator) whose PLL never locks stays on its source oscillator and says so in the
/// result: the caller derives every peripheral clock from the result, never from a constant.
#ifndef ODO_CLOCK_H
#define ODO_CLOCK_H

#include <stdint.h>

#include "stm32f4_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_CLOCK_HSI_HZ    16000000U
#define ODO_CLOCK_TARGET_HZ 168000000U

typedef enum {
    ODO_CLOCK_HSE_PLL = 0, ///< 168 MHz from the crystal (the normal case)
    ODO_CLOCK_HSI_PLL = 1, ///< 168 MHz from the internal RC: no crystal (CAN timing is less exact)
    ODO_CLOCK_HSI = 2      ///< 16 MHz: the PLL did not lock; everything runs, slowly
} odo_clock_source_t;

typedef struct {
    odo_clock_source_t source;
    uint32_t sysclk_hz;
    uint32_t hclk_hz;
    uint32_t pclk1_hz; ///< APB1: bxCAN, TIM2-7
    uint32_t pclk2_hz;
    uint32_t tim_apb1_hz; ///< TIM2-7 kernel clock: pclk1, doubled when APB1 is divided
} odo_clock_t;

/// Configure the clocks as above. hse_hz: the board's crystal, a whole number of MHz in [4, 26]
/// (0: no crystal fitted, go straight to HSI). Returns the clock tree actually running. Bounded:
/// at most 4 * polls register reads.
odo_clock_t odo_clock_init(odo_stm32_rcc_t *rcc, odo_stm32_flash_t *flash, uint32_t hse_hz, uint32_t polls);

#ifdef __cplusplus
}
#endif
#endif
