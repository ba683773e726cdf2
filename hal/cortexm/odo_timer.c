/// Tick timer and encoder counters (odo_timer.h).
#include "odo_timer.h"

#include "odo_reg.h"

bool odo_tick_timer_init(odo_stm32_tim_t *tim, uint32_t tim_hz, uint32_t period_us)
{
    const uint32_t mhz = tim_hz / 1000000U;
    if (mhz == 0U || mhz > 65536U || mhz * 1000000U != tim_hz || period_us == 0U || period_us > 65536U) {
        return false;
    }
    odo_reg_write(&tim->CR1, 0U);
    /* Polled: the NVIC line stays disabled, so UIE takes no interrupt. It is set all the same
     * because QEMU's STM32F405 timer model (stm32f2xx_timer) raises UIF only with UIE; on the
     * part UIF is set either way (RM0090 18.4.5). */
    odo_reg_write(&tim->DIER, ODO_TIM_DIER_UIE);
    odo_reg_write(&tim->PSC, mhz - 1U);
    odo_reg_write(&tim->ARR, period_us - 1U);
    odo_reg_write(&tim->CNT, 0U);
    /* UG loads PSC/ARR now; URS keeps that forced update from raising UIF (18.4.1). */
    odo_reg_write(&tim->CR1, ODO_TIM_CR1_URS);
    odo_reg_write(&tim->EGR, ODO_TIM_EGR_UG);
    odo_reg_write(&tim->SR, 0U);
    odo_reg_write(&tim->CR1, ODO_TIM_CR1_URS | ODO_TIM_CR1_CEN);
    return true;
}

bool odo_tick_timer_elapsed(odo_stm32_tim_t *tim)
{
    if ((odo_reg_read(&tim->SR) & ODO_TIM_SR_UIF) == 0U) {
        return false;
    }
    odo_reg_write(&tim->SR, (uint32_t)~ODO_TIM_SR_UIF); /* rc_w0: writing 0 clears, 1 leaves the others */
    return true;
}

uint32_t odo_tick_timer_us(odo_stm32_tim_t *tim) { return odo_reg_read(&tim->CNT); }

bool odo_encoder_init(odo_stm32_tim_t *tim, uint8_t bits, uint8_t filter, bool invert)
{
    if (bits != 16U && bits != 32U) {
        return false;
    }
    odo_reg_write(&tim->CR1, 0U);
    odo_reg_write(&tim->SMCR, 0U);
    odo_reg_write(&tim->CCER, 0U); /* CCxE off while the channel mode is written (18.4.7) */
    odo_reg_write(&tim->CCMR1, ODO_TIM_CCMR1_CC1S_TI1 | ODO_TIM_CCMR1_CC2S_TI2 | ODO_TIM_CCMR1_IC1F(filter & 0xFU) |
                                   ODO_TIM_CCMR1_IC2F(filter & 0xFU));
    odo_reg_write(&tim->CCER, invert ? (1U << 1) : 0U); /* CC1P: TI1 inverted -> counts down */
    odo_reg_write(&tim->PSC, 0U);
    odo_reg_write(&tim->ARR, bits == 32U ? 0xFFFFFFFFU : 0xFFFFU);
    odo_reg_write(&tim->SMCR, ODO_TIM_SMCR_SMS_ENCODER3);
    odo_reg_write(&tim->CNT, 0U);
    odo_reg_write(&tim->CR1, ODO_TIM_CR1_CEN);
    return true;
}

uint32_t odo_encoder_read(odo_stm32_tim_t *tim) { return odo_reg_read(&tim->CNT); }
