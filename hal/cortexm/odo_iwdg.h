/// Independent watchdog (RM0090 chapter 21, IWDG): once started it cannot be stopped, and it resets
/// the part unless odo_iwdg_refresh runs at least every timeout. The board loop refreshes it once
/// per tick, after the step, so a hung step or a stuck loop resets the controller.
///
/// Clock: the LSI RC, ~32 kHz (17-47 kHz over temperature and parts: the datasheet's spread), so
/// the timeout is nominal; pick it several ticks long.
#ifndef ODO_IWDG_H
#define ODO_IWDG_H

#include <stdbool.h>
#include <stdint.h>

#include "stm32f4_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_IWDG_LSI_HZ 32000U

/// Prescaler and reload for a nominal timeout_ms (1..32768): the smallest prescaler 4 * 2^PR
/// whose 12-bit reload can hold it. Returns false iff out of range.
bool odo_iwdg_config(uint32_t timeout_ms, uint32_t *pr, uint32_t *rlr);

/// Start the watchdog with timeout_ms (unlock, PR, RLR, wait for both updates, reload, start).
/// Returns false iff timeout_ms is out of range or an update did not finish within `polls` reads
/// of SR (the watchdog is then started anyway with whatever was accepted: a board that asked for
/// a watchdog gets one).
bool odo_iwdg_start(odo_stm32_iwdg_t *iwdg, uint32_t timeout_ms, uint32_t polls);

/// Reload the counter.
void odo_iwdg_refresh(odo_stm32_iwdg_t *iwdg);

#ifdef __cplusplus
}
#endif
#endif
