/// The tick-timer driver (hal/cortexm/odo_timer.c) on qemu's netduinoplus2, whose STM32F405 model
/// has TIM2-TIM5 (QEMU's stm32f2xx_timer) but no RCC: the driver's register writes must land
/// where the model reads them (PSC, ARR, CR1.CEN), and the update flag must come and be cleared
/// by odo_tick_timer_elapsed, period after period. The model's counting rate is its own (no RCC),
/// and its CNT does not wrap at ARR (it counts on; only the flag follows ARR), so periods are
/// counted, not timed. Exit 0 iff every check holds (semihosting exit code).
#include <stdint.h>
#include <stdio.h>

#include "odo_timer.h"
#include "stm32f4_regs.h"

#define PERIODS        3U
#define SPIN_LIMIT     500000000UL
/* qemu's model counts at 1 GHz / (PSC + 1) whatever the RCC says. Claiming a 4,294 MHz kernel
 * clock (PSC 4293) and the longest period (ARR 65535) makes a period 0.28 s of qemu time, so the
 * flag cannot come back between clearing it and checking that it is clear on a loaded host
 * (with PSC 15 and ARR 39999, 0.64 ms, it sometimes did). */
#define CLAIMED_TIM_HZ 4294000000UL

static int failures;

static void check(int ok, const char *what)
{
    printf("%s: %s\n", ok ? "ok" : "FAILED", what);
    failures += ok ? 0 : 1;
}

int main(void)
{
    odo_stm32_tim_t *tim = (odo_stm32_tim_t *)ODO_STM32_TIM2_BASE;
    check(!odo_tick_timer_init(tim, 16500000UL, 40000U), "16.5 MHz refused (not whole MHz)");
    check(odo_tick_timer_init(tim, 16000000UL, 40000U), "odo_tick_timer_init(TIM2, 16 MHz, 40 ms)");
    check(tim->PSC == 15U, "PSC = 15 (1 MHz count)");
    check(tim->ARR == 39999U, "ARR = 39999 (40 ms)");
    check(odo_tick_timer_init(tim, CLAIMED_TIM_HZ, 65536U), "re-initialised: PSC 4293, ARR 65535");
    check(tim->PSC == 4293U && tim->ARR == 65535U, "PSC and ARR read back");
    check((tim->CR1 & ODO_TIM_CR1_CEN) != 0U, "counter enabled");
    for (uint32_t p = 0U; p < PERIODS; ++p) {
        uint32_t spins = 0U;
        while (!odo_tick_timer_elapsed(tim) && spins < SPIN_LIMIT) {
            ++spins;
        }
        check(spins < SPIN_LIMIT, "a period ended (UIF)");
        check((tim->SR & ODO_TIM_SR_UIF) == 0U, "UIF cleared by odo_tick_timer_elapsed");
    }
    printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
}
