/// The 40 ms tick timer and the quadrature-encoder wheel counters, on the STM32F4's timers
/// (RM0090 chapter 18 "General-purpose timers (TIM2 to TIM5)", chapter 20 "Basic timers (TIM6 and
/// TIM7)"; the registers used here sit at the same offsets in both).
///
/// Tick: the timer counts microseconds (PSC = f_tim / 1 MHz - 1) up to ARR = period - 1 and sets
/// UIF at each wrap; the main loop polls it (the NVIC line stays disabled), so a late loop sees at
/// most one flag per missed period and counts the overrun.
///
/// Encoder (18.3.12 "Encoder interface mode"): TI1 and TI2 as inputs with a digital filter, SMS =
/// 011 (count on both edges of both inputs: 4 counts per line, the HCTL-1100's 4x decoding), ARR
/// at the counter's full range so it wraps like the HCTL's 24-bit counter does at its width: the
/// firmware's modular delta (odo_count_delta) takes the width from the sample's `bits`.
#ifndef ODO_TIMER_H
#define ODO_TIMER_H

#include <stdbool.h>
#include <stdint.h>

#include "stm32f4_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Start tim as a free-running tick of period_us microseconds (1..65536) from a kernel clock of
/// tim_hz (a whole number of MHz). Returns false (timer untouched) iff tim_hz is not a multiple
/// of 1 MHz in [1, 65536] MHz or period_us is out of range.
bool odo_tick_timer_init(odo_stm32_tim_t *tim, uint32_t tim_hz, uint32_t period_us);

/// True iff a period ended since the last call (UIF set); clears the flag. One register read, plus
/// one write when set.
bool odo_tick_timer_elapsed(odo_stm32_tim_t *tim);

/// Microseconds into the current period (CNT).
uint32_t odo_tick_timer_us(odo_stm32_tim_t *tim);

/// Put tim in encoder mode 3 on TI1/TI2 with input filter `filter` (0..15, IC1F/IC2F; 3 = 8
/// samples at f_CK_INT) and a counter of `bits` (16 for TIM3/4, 32 for TIM2/5); `invert` swaps
/// the counting direction (CC1P). Counting starts at 0. Returns false iff bits is not 16 or 32.
bool odo_encoder_init(odo_stm32_tim_t *tim, uint8_t bits, uint8_t filter, bool invert);

/// Current count (low `bits` bits meaningful).
uint32_t odo_encoder_read(odo_stm32_tim_t *tim);

#ifdef __cplusplus
}
#endif
#endif
