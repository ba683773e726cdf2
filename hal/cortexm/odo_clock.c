/// System clock setup (odo_clock.h).
#include "odo_clock.h"

#include "odo_reg.h"

#define PLLN                     336U
#define PLLP                     2U
#define PLLQ                     7U
#define FLASH_WAIT_STATES_168MHZ 5U /* RM0090 3.5.1: 150 < HCLK <= 168 MHz at 2.7-3.6 V */

static odo_clock_t tree(odo_clock_source_t source, uint32_t sysclk_hz, int divided)
{
    odo_clock_t c;
    c.source = source;
    c.sysclk_hz = sysclk_hz;
    c.hclk_hz = sysclk_hz;
    c.pclk1_hz = divided ? sysclk_hz / 4U : sysclk_hz;
    c.pclk2_hz = divided ? sysclk_hz / 2U : sysclk_hz;
    c.tim_apb1_hz = divided ? 2U * c.pclk1_hz : c.pclk1_hz;
    return c;
}

odo_clock_t odo_clock_init(odo_stm32_rcc_t *rcc, odo_stm32_flash_t *flash, uint32_t hse_hz, uint32_t polls)
{
    /* Start from the reset state: on HSI, PLL off (it cannot be reconfigured while on). */
    odo_reg_modify(&rcc->CR, 0U, ODO_RCC_CR_HSION);
    (void)odo_reg_wait(&rcc->CR, ODO_RCC_CR_HSIRDY, ODO_RCC_CR_HSIRDY, polls);
    odo_reg_modify(&rcc->CFGR, ODO_RCC_CFGR_SW_MASK, ODO_RCC_CFGR_SW_HSI);
    odo_reg_modify(&rcc->CR, ODO_RCC_CR_PLLON, 0U);

    int use_hse = 0;
    const uint32_t hse_mhz = hse_hz / 1000000U;
    if (hse_mhz >= 4U && hse_mhz <= 26U && hse_mhz * 1000000U == hse_hz) {
        odo_reg_modify(&rcc->CR, ODO_RCC_CR_HSEBYP, ODO_RCC_CR_HSEON);
        use_hse = odo_reg_wait(&rcc->CR, ODO_RCC_CR_HSERDY, ODO_RCC_CR_HSERDY, polls);
        if (!use_hse) {
            odo_reg_modify(&rcc->CR, ODO_RCC_CR_HSEON, 0U); /* no crystal: stop trying */
        }
    }
    const uint32_t pllm = use_hse ? hse_mhz : ODO_CLOCK_HSI_HZ / 1000000U;
    odo_reg_write(&rcc->PLLCFGR, ODO_RCC_PLLCFGR(pllm, PLLN, PLLP, use_hse, PLLQ));
    odo_reg_modify(&rcc->CR, 0U, ODO_RCC_CR_PLLON);
    if (!odo_reg_wait(&rcc->CR, ODO_RCC_CR_PLLRDY, ODO_RCC_CR_PLLRDY, polls)) {
        odo_reg_modify(&rcc->CR, ODO_RCC_CR_PLLON | ODO_RCC_CR_HSEON, 0U); /* stay on HSI */
        return tree(ODO_CLOCK_HSI, ODO_CLOCK_HSI_HZ, 0);
    }
    /* Wait states before the clock goes up, prescalers before the switch. */
    odo_reg_modify(&flash->ACR, ODO_FLASH_ACR_LATENCY_MASK,
                   FLASH_WAIT_STATES_168MHZ | ODO_FLASH_ACR_PRFTEN | ODO_FLASH_ACR_ICEN | ODO_FLASH_ACR_DCEN);
    odo_reg_modify(&rcc->CFGR, ODO_RCC_CFGR_HPRE_MASK | ODO_RCC_CFGR_PPRE1_MASK | ODO_RCC_CFGR_PPRE2_MASK,
                   ODO_RCC_CFGR_PPRE1_DIV4 | ODO_RCC_CFGR_PPRE2_DIV2);
    odo_reg_modify(&rcc->CFGR, ODO_RCC_CFGR_SW_MASK, ODO_RCC_CFGR_SW_PLL);
    if (!odo_reg_wait(&rcc->CFGR, ODO_RCC_CFGR_SWS_MASK, ODO_RCC_CFGR_SWS(ODO_RCC_CFGR_SW_PLL), polls)) {
        /* Not switched: still on HSI with the prescalers set. */
        odo_reg_modify(&rcc->CFGR, ODO_RCC_CFGR_SW_MASK, ODO_RCC_CFGR_SW_HSI);
        return tree(ODO_CLOCK_HSI, ODO_CLOCK_HSI_HZ, 1);
    }
    return tree(use_hse ? ODO_CLOCK_HSE_PLL : ODO_CLOCK_HSI_PLL, ODO_CLOCK_TARGET_HZ, 1);
}
