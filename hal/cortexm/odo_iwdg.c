/// Independent watchdog (odo_iwdg.h).
#include "odo_iwdg.h"

#include "odo_reg.h"

bool odo_iwdg_config(uint32_t timeout_ms, uint32_t *pr, uint32_t *rlr)
{
    if (timeout_ms == 0U || timeout_ms > 32768U) {
        return false;
    }
    for (uint32_t p = 0U; p <= 6U; ++p) {
        const uint32_t div = (uint32_t)4U << p;
        /* ticks = timeout * LSI / div, rounded; the counter runs RLR + 1 ticks. */
        const uint32_t ticks =
            (uint32_t)(((uint64_t)timeout_ms * ODO_IWDG_LSI_HZ + 500U * (uint64_t)div) / (1000U * (uint64_t)div));
        if (ticks >= 1U && ticks <= 4096U) {
            *pr = p;
            *rlr = ticks - 1U;
            return true;
        }
    }
    return false;
}

bool odo_iwdg_start(odo_stm32_iwdg_t *iwdg, uint32_t timeout_ms, uint32_t polls)
{
    uint32_t pr = 0U, rlr = 0U;
    if (!odo_iwdg_config(timeout_ms, &pr, &rlr)) {
        return false;
    }
    odo_reg_write(&iwdg->KR, ODO_IWDG_KEY_START); /* also starts the LSI (21.3.2) */
    odo_reg_write(&iwdg->KR, ODO_IWDG_KEY_UNLOCK);
    odo_reg_write(&iwdg->PR, pr);
    odo_reg_write(&iwdg->RLR, rlr);
    const bool ok = odo_reg_wait(&iwdg->SR, 3U, 0U, polls) != 0; /* PVU, RVU cleared */
    odo_reg_write(&iwdg->KR, ODO_IWDG_KEY_RELOAD);
    return ok;
}

void odo_iwdg_refresh(odo_stm32_iwdg_t *iwdg) { odo_reg_write(&iwdg->KR, ODO_IWDG_KEY_RELOAD); }
