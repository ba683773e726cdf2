/// Register-level fake (fake_stm32.h).
#include "fake_stm32.h"

#include <string.h>

#include "odo_reg.h"

fake_stm32_t fake;

void fake_stm32_reset(void)
{
    memset(&fake, 0, sizeof fake);
    fake.hse_works = true;
    fake.pll_locks = true;
    fake.driving = -1;
    /* Reset values that matter: bxCAN starts in sleep mode (32.9.2: MSR reset 0x0C02),
     * all three transmit mailboxes empty (TSR reset 0x1C000000). */
    fake.can.MCR = ODO_CAN_MCR_SLEEP;
    fake.can.MSR = ODO_CAN_MSR_SLAK;
    fake.can.TSR = ODO_CAN_TSR_TME(0) | ODO_CAN_TSR_TME(1) | ODO_CAN_TSR_TME(2);
}

void fake_stm32_hctl_attach(odosim_hctl_t *const *chips, uint8_t n, uint8_t ale_pin, uint8_t oe_pin,
                            const uint8_t *cs_pins)
{
    fake.n_chips = n;
    for (uint8_t k = 0; k < n; ++k) {
        fake.chip[k] = chips[k];
        fake.cs_pin[k] = cs_pins[k];
    }
    fake.ale_pin = ale_pin;
    fake.oe_pin = oe_pin;
}

void fake_stm32_can_rx(uint32_t id, bool ext, bool rtr, uint8_t raw_dlc, const uint8_t data[8])
{
    if (fake.rxq_len == 3U) { /* FIFO 0 holds three frames (32.7.5); the next one overruns */
        fake.rx_overrun = true;
    }
    fake_can_mb_t *m = &fake.rxq[(fake.rxq_head + fake.rxq_len) % FAKE_CAN_QUEUE];
    fake.rxq_len++;
    m->ir = ext ? (id << 3) | ODO_CAN_XIR_IDE : id << 21;
    if (rtr) {
        m->ir |= ODO_CAN_XIR_RTR;
    }
    m->dtr = raw_dlc & 0xFU;
    m->dlr = (uint32_t)data[0] | ((uint32_t)data[1] << 8) | ((uint32_t)data[2] << 16) | ((uint32_t)data[3] << 24);
    m->dhr = (uint32_t)data[4] | ((uint32_t)data[5] << 8) | ((uint32_t)data[6] << 16) | ((uint32_t)data[7] << 24);
}

#define IN(block, reg)                                                  \
    ((const volatile void *)(reg) >= (const volatile void *)&(block) && \
     (const volatile void *)(reg) < (const volatile void *)(&(block) + 1))

static bool pin_low(const odo_stm32_gpio_t *g, uint8_t pin) { return (g->ODR & (1UL << pin)) == 0U; }

static int selected_chip(void)
{
    for (uint8_t k = 0; k < fake.n_chips; ++k) {
        if (pin_low(&fake.gpio[1], fake.cs_pin[k])) {
            return k;
        }
    }
    return -1;
}

/// Control-port edges: ALE falling latches the address, /OE falling makes the chip drive.
static void ctrl_changed(uint32_t old_odr)
{
    const uint32_t odr = fake.gpio[1].ODR;
    const uint32_t ale = 1UL << fake.ale_pin, oe = 1UL << fake.oe_pin;
    const int k = selected_chip();
    if ((old_odr & ale) != 0U && (odr & ale) == 0U && k >= 0) {
        fake.latched_addr[k] = (uint8_t)(fake.gpio[0].ODR & 0xFFU);
    }
    if ((old_odr & oe) != 0U && (odr & oe) == 0U && k >= 0) {
        if (fake.on_read != NULL) {
            fake.on_read(fake.user, (uint8_t)k, fake.latched_addr[k]);
        }
        fake.driven = odosim_hctl_read(fake.chip[k], fake.latched_addr[k]);
        fake.driving = k;
    }
    if ((odr & oe) != 0U || k < 0) {
        fake.driving = -1;
    }
}

uint32_t odo_reg_read(const volatile uint32_t *reg)
{
    fake.reads++;
    if (reg == &fake.gpio[0].IDR) {
        const bool inputs = (fake.gpio[0].MODER & 0xFFFFU) == 0U;
        return (fake.gpio[0].IDR & ~(uint32_t)0xFFU) | (fake.driving >= 0 && inputs ? fake.driven : 0U);
    }
    if (reg == &fake.gpio[0].BSRR || reg == &fake.gpio[1].BSRR) {
        return 0U; /* write-only */
    }
    if (reg == &fake.can.RF0R) {
        const uint32_t fmp = fake.rxq_len > 3U ? 3U : fake.rxq_len;
        return fmp | (fake.rxq_len >= 3U ? (1UL << 3) : 0U) | (fake.rx_overrun ? ODO_CAN_RF0R_FOVR0 : 0U);
    }
    if (IN(fake.can.rx[0], reg)) {
        if (fake.rxq_len == 0U) {
            return 0U;
        }
        const fake_can_mb_t *m = &fake.rxq[fake.rxq_head];
        const uint32_t words[4] = {m->ir, m->dtr, m->dlr, m->dhr};
        return words[(const volatile uint32_t *)reg - &fake.can.rx[0].RIR];
    }
    return *reg;
}

void odo_reg_write(volatile uint32_t *reg, uint32_t value)
{
    if (IN(fake.rcc, reg)) {
        *reg = value;
        odo_stm32_rcc_t *r = &fake.rcc;
        uint32_t cr = r->CR & ~(uint32_t)(ODO_RCC_CR_HSIRDY | ODO_RCC_CR_HSERDY | ODO_RCC_CR_PLLRDY);
        cr |= (cr & ODO_RCC_CR_HSION) != 0U ? ODO_RCC_CR_HSIRDY : 0U;
        cr |= (cr & ODO_RCC_CR_HSEON) != 0U && fake.hse_works ? ODO_RCC_CR_HSERDY : 0U;
        cr |= (cr & ODO_RCC_CR_PLLON) != 0U && fake.pll_locks ? ODO_RCC_CR_PLLRDY : 0U;
        r->CR = cr;
        const uint32_t sw = r->CFGR & ODO_RCC_CFGR_SW_MASK;
        const uint32_t ready[3] = {ODO_RCC_CR_HSIRDY, ODO_RCC_CR_HSERDY, ODO_RCC_CR_PLLRDY};
        if (sw < 3U && (cr & ready[sw]) != 0U) {
            r->CFGR = (r->CFGR & ~(uint32_t)ODO_RCC_CFGR_SWS_MASK) | (uint32_t)ODO_RCC_CFGR_SWS(sw);
        }
        return;
    }
    for (unsigned g = 0; g < 2U; ++g) {
        if (reg == &fake.gpio[g].BSRR) {
            const uint32_t old = fake.gpio[g].ODR;
            fake.gpio[g].ODR = (old | (value & 0xFFFFU)) & ~(value >> 16);
            if (g == 1U) {
                ctrl_changed(old);
            }
            return;
        }
        if (reg == &fake.gpio[g].ODR) {
            const uint32_t old = fake.gpio[g].ODR;
            fake.gpio[g].ODR = value;
            if (g == 1U) {
                ctrl_changed(old);
            }
            return;
        }
    }
    for (unsigned t = 0; t < FAKE_TIMS; ++t) {
        if (reg == &fake.tim[t].SR) {
            fake.tim[t].SR &= value; /* rc_w0 */
            return;
        }
        if (reg == &fake.tim[t].EGR) {
            if ((value & ODO_TIM_EGR_UG) != 0U) {
                fake.tim[t].CNT = 0U;
            }
            return;
        }
    }
    if (reg == &fake.can.MCR) {
        fake.can.MCR = value;
        uint32_t msr = fake.can.MSR & ~(uint32_t)(ODO_CAN_MSR_INAK | ODO_CAN_MSR_SLAK);
        if (!fake.can_no_clock) {
            const bool inrq = (value & ODO_CAN_MCR_INRQ) != 0U;
            msr |= (inrq || fake.can_stuck_in_init) ? ODO_CAN_MSR_INAK : 0U;
            msr |= (value & ODO_CAN_MCR_SLEEP) != 0U ? ODO_CAN_MSR_SLAK : 0U;
        } else {
            msr |= fake.can.MSR & (ODO_CAN_MSR_INAK | ODO_CAN_MSR_SLAK);
        }
        fake.can.MSR = msr;
        return;
    }
    if (reg == &fake.can.RF0R) {
        if ((value & ODO_CAN_RF0R_FOVR0) != 0U) {
            fake.rx_overrun = false;
        }
        if ((value & ODO_CAN_RF0R_RFOM0) != 0U && fake.rxq_len > 0U) {
            fake.rxq_head = (fake.rxq_head + 1U) % FAKE_CAN_QUEUE;
            fake.rxq_len--;
        }
        return;
    }
    for (unsigned m = 0; m < 3U; ++m) {
        if (reg == &fake.can.tx[m].TIR) {
            fake.can.tx[m].TIR = value;
            if ((value & ODO_CAN_TIR_TXRQ) != 0U && fake.txlog_len < FAKE_CAN_LOG) {
                const odo_stm32_can_tx_t *mb = &fake.can.tx[m];
                fake_can_mb_t *l = &fake.txlog[fake.txlog_len++];
                l->ir = value & ~(uint32_t)ODO_CAN_TIR_TXRQ;
                l->dtr = mb->TDTR;
                l->dlr = mb->TDLR;
                l->dhr = mb->TDHR;
                fake.can.tx[m].TIR = l->ir; /* sent at once: the mailbox is empty again */
            }
            return;
        }
    }
    if (reg == &fake.iwdg.KR) {
        if (value == ODO_IWDG_KEY_UNLOCK) {
            fake.iwdg_unlocked = true;
        } else if (value == ODO_IWDG_KEY_START) {
            fake.iwdg_started = true;
        } else if (value == ODO_IWDG_KEY_RELOAD) {
            fake.iwdg_reloads++;
            fake.iwdg_unlocked = false;
        }
        return;
    }
    if (reg == &fake.iwdg.PR || reg == &fake.iwdg.RLR) {
        if (fake.iwdg_unlocked) {
            *reg = value;
        } else {
            fake.iwdg_ignored_writes++;
        }
        return;
    }
    *reg = value;
}
