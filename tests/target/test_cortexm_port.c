/// The STM32F4 board port (hal/cortexm) on the host, against the register-level fake
/// (fake_stm32.h): what each driver writes into which register (RM0090), that every hardware wait
/// is bounded when a peripheral never answers, the HCTL-1100 bus against the simulator's chip
/// emulator (latch order R14H, R13H, R12H), the CAN filters against can/odometry.dbc itself, and
/// the board tick's receive path: bad frames are counted and never integrated.
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_support.h"
#include "fake_stm32.h"
#include "hctl1100.h"
#include "odo/odo_app.h"
#include "odo/odo_can.h"
#include "odo/odo_status.h"
#include "odo_board_port.h"
#include "odo_bxcan.h"
#include "odo_clock.h"
#include "odo_hctl_bus.h"
#include "odo_iwdg.h"
#include "odo_timer.h"
#include "robot.h"

#define POLLS 1000U

static void setup(void) { fake_stm32_reset(); }

/* ---- clock ------------------------------------------------------------------------------- */

/// 168 MHz from an 8 MHz crystal: M 8, N 336, P /2, Q 7, source HSE; 5 wait states with prefetch
/// and caches (RM0090 3.5.1); AHB /1, APB1 /4, APB2 /2; SYSCLK switched to the PLL.
START_TEST(clock_168mhz_from_the_crystal)
{
    const odo_clock_t c = odo_clock_init(&fake.rcc, &fake.flash, 8000000UL, POLLS);
    ck_assert_int_eq(c.source, ODO_CLOCK_HSE_PLL);
    ck_assert_uint_eq(c.sysclk_hz, 168000000UL);
    ck_assert_uint_eq(c.pclk1_hz, 42000000UL);
    ck_assert_uint_eq(c.pclk2_hz, 84000000UL);
    ck_assert_uint_eq(c.tim_apb1_hz, 84000000UL);
    ck_assert_uint_eq(fake.rcc.PLLCFGR, 8UL | (336UL << 6) | (0UL << 16) | (1UL << 22) | (7UL << 24));
    ck_assert_uint_eq(fake.flash.ACR & 7U, 5U);
    ck_assert_uint_eq(fake.flash.ACR & 0x700U, 0x700U);
    ck_assert_uint_eq((fake.rcc.CFGR >> 4) & 0xFU, 0U); /* HPRE /1 */
    ck_assert_uint_eq((fake.rcc.CFGR >> 10) & 7U, 5U);  /* PPRE1 /4 */
    ck_assert_uint_eq((fake.rcc.CFGR >> 13) & 7U, 4U);  /* PPRE2 /2 */
    ck_assert_uint_eq(fake.rcc.CFGR & 0xFU, 0xAU);      /* SW = SWS = PLL */
}
END_TEST

/// No crystal: the same 168 MHz from the 16 MHz HSI (PLLM 16, PLLSRC 0), HSE switched off again.
START_TEST(clock_falls_back_to_the_hsi_when_the_crystal_does_not_start)
{
    fake.hse_works = false;
    const odo_clock_t c = odo_clock_init(&fake.rcc, &fake.flash, 8000000UL, POLLS);
    ck_assert_int_eq(c.source, ODO_CLOCK_HSI_PLL);
    ck_assert_uint_eq(c.sysclk_hz, 168000000UL);
    ck_assert_uint_eq(fake.rcc.PLLCFGR, 16UL | (336UL << 6) | (7UL << 24));
    ck_assert_uint_eq(fake.rcc.CR & ODO_RCC_CR_HSEON, 0U);
}
END_TEST

/// A PLL that never locks (or an emulator without an RCC): stay on the 16 MHz HSI, say so, and
/// take a bounded number of register reads to find out.
START_TEST(clock_stays_on_the_hsi_when_the_pll_does_not_lock)
{
    fake.pll_locks = false;
    fake.hse_works = false;
    const odo_clock_t c = odo_clock_init(&fake.rcc, &fake.flash, 8000000UL, POLLS);
    ck_assert_int_eq(c.source, ODO_CLOCK_HSI);
    ck_assert_uint_eq(c.sysclk_hz, 16000000UL);
    ck_assert_uint_eq(c.tim_apb1_hz, 16000000UL);
    ck_assert_uint_eq(fake.rcc.CR & ODO_RCC_CR_PLLON, 0U);
    ck_assert_uint_eq(fake.rcc.CFGR & 3U, 0U);
    ck_assert_uint_le(fake.reads, 4U * POLLS + 32U);
}
END_TEST

/* ---- timers ------------------------------------------------------------------------------ */

/// 40 ms from an 84 MHz timer clock: 1 MHz count (PSC 83), ARR 39999, counting; UIF
/// is reported once and cleared without touching the other status bits (rc_w0).
START_TEST(tick_timer_counts_microseconds_to_40_ms)
{
    odo_stm32_tim_t *t = &fake.tim[0];
    ck_assert(odo_tick_timer_init(t, 84000000UL, 40000U));
    ck_assert_uint_eq(t->PSC, 83U);
    ck_assert_uint_eq(t->ARR, 39999U);
    ck_assert_uint_eq(t->CR1 & ODO_TIM_CR1_CEN, ODO_TIM_CR1_CEN);
    ck_assert_uint_eq(t->DIER, ODO_TIM_DIER_UIE); /* for qemu's model; the NVIC line stays off */
    ck_assert(!odo_tick_timer_elapsed(t));
    t->SR = ODO_TIM_SR_UIF | (1UL << 1); /* update and CC1IF */
    ck_assert(odo_tick_timer_elapsed(t));
    ck_assert_uint_eq(t->SR, 1UL << 1);
    ck_assert(!odo_tick_timer_elapsed(t));
    t->CNT = 1234U;
    ck_assert_uint_eq(odo_tick_timer_us(t), 1234U);
}
END_TEST

START_TEST(tick_timer_refuses_clocks_it_cannot_divide_to_1_mhz)
{
    fake.tim[0].PSC = 77U;
    ck_assert(!odo_tick_timer_init(&fake.tim[0], 84500000UL, 40000U));
    ck_assert(!odo_tick_timer_init(&fake.tim[0], 84000000UL, 70000U));
    ck_assert(!odo_tick_timer_init(&fake.tim[0], 84000000UL, 0U));
    ck_assert_uint_eq(fake.tim[0].PSC, 77U); /* untouched */
}
END_TEST

/// RM0090 18.3.12: TI1 and TI2 as inputs (CC1S = CC2S = 01) with the filter, encoder mode 3
/// (SMS 011: both edges of both inputs, 4x), full-range ARR for the counter's width.
START_TEST(encoder_mode_3_on_ti1_and_ti2_at_full_width)
{
    ck_assert(odo_encoder_init(&fake.tim[1], 16U, 3U, false));
    ck_assert_uint_eq(fake.tim[1].SMCR & 7U, 3U);
    ck_assert_uint_eq(fake.tim[1].CCMR1, 0x3131U);
    ck_assert_uint_eq(fake.tim[1].ARR, 0xFFFFU);
    ck_assert_uint_eq(fake.tim[1].CCER, 0U);
    ck_assert_uint_eq(fake.tim[1].CR1 & ODO_TIM_CR1_CEN, ODO_TIM_CR1_CEN);
    ck_assert(odo_encoder_init(&fake.tim[2], 32U, 0U, true));
    ck_assert_uint_eq(fake.tim[2].ARR, 0xFFFFFFFFUL);
    ck_assert_uint_eq(fake.tim[2].CCER, 1UL << 1); /* CC1P: reversed */
    ck_assert(!odo_encoder_init(&fake.tim[3], 24U, 0U, false));
}
END_TEST

/* ---- HCTL-1100 bus ----------------------------------------------------------------------- */

static odosim_hctl_t chips[2];
static double chip_t_s[2], chip_phase[2];
static uint32_t position_at_lsb[2];

/// The wheel turns one count before every byte the host reads, and the R14H read is where the
/// chip latches: remember the count there.
static void wheel_turns(void *user, uint8_t chip, uint8_t reg)
{
    (void)user;
    chip_t_s[chip] += 1e-3;
    chip_phase[chip] += 1.0;
    ck_assert(odosim_hctl_advance(&chips[chip], chip_t_s[chip], chip_phase[chip]));
    chip_t_s[chip] += 1e-3; /* a millisecond at rest: the edge passes the chip's filter */
    ck_assert(odosim_hctl_advance(&chips[chip], chip_t_s[chip], chip_phase[chip]));
    if (reg == ODO_HCTL_R14H) {
        position_at_lsb[chip] = (uint32_t)chip_phase[chip] & ODOSIM_HCTL_POS_MASK;
    }
}

static odo_hctl_bus_t bus_for_fake(void)
{
    const odo_hctl_bus_t b = {&fake.gpio[0], &fake.gpio[1], 8U, 9U, 10U, {11U, 12U, 13U, 14U}, 2U, 0U};
    return b;
}

static void attach_chips(double phase0)
{
    const odosim_hctl_config_t cfg = {1000000UL, ODOSIM_HCTL_CONV_1100, false};
    odosim_hctl_t *ptrs[2] = {&chips[0], &chips[1]};
    const uint8_t cs[2] = {11U, 12U};
    for (int k = 0; k < 2; ++k) { /* power-on at count 0, then roll to phase0 (+k) in 1 s */
        ck_assert(odosim_hctl_init(&chips[k], &cfg, 0.0, 0.0));
        chip_t_s[k] = 1.0;
        chip_phase[k] = phase0 + k;
        ck_assert(odosim_hctl_advance(&chips[k], chip_t_s[k], chip_phase[k]));
        chip_t_s[k] = 1.1;
        ck_assert(odosim_hctl_advance(&chips[k], chip_t_s[k], chip_phase[k]));
    }
    fake_stm32_hctl_attach(ptrs, 2U, 8U, 9U, cs);
    fake.on_read = wheel_turns;
}

/// HCTL-1100 "Actual Position Registers R12H-R14H": read LSB first (it latches), then middle,
/// then MSB: the 24-bit count is the one at the LSB read even while the wheel turns between the
/// byte reads, here across a carry into both upper bytes (0x00FFFF -> 0x010000).
START_TEST(hctl_position_is_read_in_latch_order_and_never_tears)
{
    attach_chips((double)0x00FFFEU);
    const odo_hctl_bus_t bus = bus_for_fake();
    odo_hctl_bus_init(&bus);
    for (int i = 0; i < 6; ++i) {
        for (uint8_t k = 0; k < 2U; ++k) {
            const uint32_t pos = odo_hctl_read_position(&bus, k);
            ck_assert_uint_eq(pos, position_at_lsb[k]);
        }
    }
    /* Idle afterwards: /CS and /OE high, ALE low, D0-D7 released. */
    ck_assert_uint_eq(fake.gpio[1].ODR & ((1U << 11) | (1U << 12) | (1U << 9)), (1U << 11) | (1U << 12) | (1U << 9));
    ck_assert_uint_eq(fake.gpio[1].ODR & (1U << 8), 0U);
    ck_assert_uint_eq(fake.gpio[0].MODER & 0xFFFFU, 0U);
}
END_TEST

/// The negative control: the same moving wheel read MSB first tears at the carry, so the test
/// above can tell the orders apart.
START_TEST(hctl_position_read_msb_first_tears_at_a_carry)
{
    attach_chips((double)0x00FFFEU);
    const odo_hctl_bus_t bus = bus_for_fake();
    odo_hctl_bus_init(&bus);
    int torn = 0;
    for (int i = 0; i < 6; ++i) {
        const uint32_t msb = odo_hctl_read_reg(&bus, 0, ODO_HCTL_R12H);
        const uint32_t mid = odo_hctl_read_reg(&bus, 0, ODO_HCTL_R13H);
        const uint32_t lsb = odo_hctl_read_reg(&bus, 0, ODO_HCTL_R14H);
        const uint32_t pos = (msb << 16) | (mid << 8) | lsb;
        const uint32_t truth = (uint32_t)chip_phase[0] & ODOSIM_HCTL_POS_MASK;
        torn += (truth - pos) > 2U; /* more than the counts turned during the read */
    }
    ck_assert_int_gt(torn, 0);
}
END_TEST

/* ---- bxCAN ------------------------------------------------------------------------------- */

/// Every standard bit rate from the 42 MHz APB1 clock: exact, 8..25 quanta, SJW 1, sample point
/// 80-90 % (32.7.7); a rate that does not divide the clock is refused.
START_TEST(can_bit_timing_is_exact_at_every_standard_rate)
{
    const uint32_t rates[] = {125000UL, 250000UL, 500000UL, 1000000UL};
    for (unsigned i = 0; i < 4; ++i) {
        uint32_t btr = 0, sp = 0;
        ck_assert(odo_bxcan_timing(42000000UL, rates[i], &btr, &sp));
        const uint32_t brp = (btr & 0x3FFU) + 1U, ts1 = ((btr >> 16) & 0xFU) + 1U, ts2 = ((btr >> 20) & 7U) + 1U;
        const uint32_t nq = 1U + ts1 + ts2;
        ck_assert_uint_eq(42000000UL / (brp * nq), rates[i]);
        ck_assert_uint_eq(42000000UL % (brp * nq), 0U);
        ck_assert_uint_eq((btr >> 24) & 3U, 0U);
        ck_assert(nq >= 8U && nq <= 25U);
        ck_assert_uint_eq(sp, 1000U * (1U + ts1) / nq);
        ck_assert(sp >= 800U && sp <= 900U);
    }
    uint32_t btr = 0;
    ck_assert(!odo_bxcan_timing(42000000UL, 33333UL, &btr, NULL));
    ck_assert(!odo_bxcan_timing(42000000UL, 0UL, &btr, NULL));
}
END_TEST

/// The identifiers SENSOR sends, read from can/odometry.dbc itself ("BO_ <id> <name>: <dlc> SENSOR").
static unsigned dbc_sensor_ids(uint32_t *ids, unsigned cap)
{
    FILE *f = fopen(ODO_SOURCE_DIR "/can/odometry.dbc", "r");
    ck_assert_ptr_nonnull(f);
    char line[512];
    unsigned n = 0;
    while (fgets(line, sizeof line, f) != NULL) {
        unsigned id = 0, dlc = 0;
        char name[128], sender[128];
        if (sscanf(line, "BO_ %u %127[^:]: %u %127s", &id, name, &dlc, sender) == 4 && strcmp(sender, "SENSOR") == 0 &&
            n < cap) {
            ids[n++] = id;
        }
    }
    fclose(f);
    return n;
}

static void fake_filter_ids(uint32_t *ids, unsigned *n)
{
    *n = 0;
    for (unsigned b = 0; b < ODO_CAN_FILTER_BANKS; ++b) {
        if ((fake.can.FA1R & (1UL << b)) == 0U) {
            continue;
        }
        ck_assert_uint_ne(fake.can.FM1R & (1UL << b), 0U);  /* list mode */
        ck_assert_uint_eq(fake.can.FS1R & (1UL << b), 0U);  /* 16-bit */
        ck_assert_uint_eq(fake.can.FFA1R & (1UL << b), 0U); /* FIFO 0 */
        const uint32_t words[2] = {fake.can.filter[b].FR1, fake.can.filter[b].FR2};
        for (unsigned w = 0; w < 2; ++w) {
            for (unsigned h = 0; h < 2; ++h) {
                const uint32_t slot = (words[w] >> (16U * h)) & 0xFFFFU;
                ck_assert_uint_eq(slot & 0x1FU, 0U); /* RTR = IDE = 0: standard data frames */
                ids[(*n)++] = slot >> 5;
            }
        }
    }
}

static odo_board_config_t fake_config(odo_wheel_source_t wheels)
{
    odo_board_config_t c;
    memset(&c, 0, sizeof c);
    c.rcc = &fake.rcc;
    c.flash = &fake.flash;
    c.iwdg = &fake.iwdg;
    c.can = &fake.can;
    c.tick_tim = &fake.tim[5];
    c.hse_hz = 8000000UL;
    c.tick_us = 40000UL;
    c.can_bitrate = 500000UL;
    c.can_rx = (odo_pin_t){&fake.gpio[1], 1U, 8U, 9U};
    c.can_tx = (odo_pin_t){&fake.gpio[1], 1U, 9U, 9U};
    c.watchdog_ms = 200U;
    c.polls = POLLS;
    c.encoder_filter = 3U;
    for (int t = 0; t < 2; ++t) {
        c.truck[t].source = wheels;
        c.truck[t].tim[0] = &fake.tim[2 * t + 1];
        c.truck[t].tim[1] = &fake.tim[2 * t + 2];
        c.truck[t].tim_bits[0] = t == 0 ? 32U : 16U;
        c.truck[t].tim_bits[1] = t == 0 ? 32U : 16U;
    }
    return c;
}

/// The filters pass exactly the frames the board consumes, and those are the DBC's SENSOR
/// messages: the board's list (from odo/odo_can.h) compared with the DBC file, not retyped.
START_TEST(can_filters_hold_the_dbc_sensor_identifiers)
{
    const odo_board_config_t cfg = fake_config(ODO_WHEELS_ENCODER);
    static hal_ctx_t hal;
    odo_board_init(&hal, &cfg);
    ck_assert_int_eq(hal.status.can, ODO_BXCAN_OK);
    uint32_t want[16], got[64];
    unsigned nw = dbc_sensor_ids(want, 16), ng = 0;
    ck_assert_uint_eq(nw, 4U);
    fake_filter_ids(got, &ng);
    ck_assert_uint_eq(ng, 4U);
    for (unsigned i = 0; i < nw; ++i) {
        ck_assert_uint_eq(got[i], want[i]);
    }
    ck_assert_uint_eq(fake.can.FMR & ODO_CAN_FMR_FINIT, 0U);
    ck_assert_uint_eq(fake.can.MCR & (ODO_CAN_MCR_INRQ | ODO_CAN_MCR_SLEEP), 0U);
    ck_assert_uint_eq(fake.can.MCR & ODO_CAN_MCR_ABOM, ODO_CAN_MCR_ABOM);
    uint32_t btr = 0;
    ck_assert(odo_bxcan_timing(42000000UL, 500000UL, &btr, NULL));
    ck_assert_uint_eq(fake.can.BTR, btr);
}
END_TEST

/// Mailbox and FIFO words as 32.9.3 lays them out, both ways; a full set of mailboxes refuses.
START_TEST(can_frames_round_trip_through_mailboxes_and_fifo)
{
    const odo_can_frame_t f = {0x181U, 6U, 0U, {1, 2, 3, 4, 5, 6, 0, 0}};
    ck_assert(odo_bxcan_send(&fake.can, &f));
    ck_assert_uint_eq(fake.txlog_len, 1U);
    ck_assert_uint_eq(fake.txlog[0].ir, 0x181UL << 21);
    ck_assert_uint_eq(fake.txlog[0].dtr, 6U);
    ck_assert_uint_eq(fake.txlog[0].dlr, 0x04030201UL);
    ck_assert_uint_eq(fake.txlog[0].dhr, 0x00000605UL);
    fake.can.TSR = 0U;
    ck_assert(!odo_bxcan_send(&fake.can, &f));

    const uint8_t d[8] = {9, 8, 7, 6, 5, 4, 3, 2};
    fake_stm32_can_rx(0x1ABCDEFUL, true, false, 3U, d);
    fake_stm32_can_rx(0x120U, false, true, 6U, d);
    fake_stm32_can_rx(0x110U, false, false, 12U, d);
    odo_can_frame_t r;
    uint8_t raw = 0;
    bool ovr = false;
    ck_assert(odo_bxcan_recv(&fake.can, &r, &raw, &ovr));
    ck_assert_uint_eq(r.id, 0x1ABCDEFUL);
    ck_assert_uint_eq(r.flags, ODO_CAN_FLAG_EXT);
    ck_assert_uint_eq(r.dlc, 3U);
    ck_assert_mem_eq(r.data, d, 3);
    ck_assert_uint_eq(r.data[3], 0U);
    ck_assert(odo_bxcan_recv(&fake.can, &r, &raw, &ovr));
    ck_assert_uint_eq(r.flags, ODO_CAN_FLAG_RTR);
    ck_assert_uint_eq(r.data[0], 0U); /* a remote frame carries no data */
    ck_assert(odo_bxcan_recv(&fake.can, &r, &raw, &ovr));
    ck_assert_uint_eq(r.dlc, 8U);
    ck_assert_uint_eq(raw, 12U);
    ck_assert(!odo_bxcan_recv(&fake.can, &r, &raw, &ovr));
    ck_assert(!ovr);
}
END_TEST

/// A controller without a clock (or stuck without recessive bits) is reported, in bounded time.
START_TEST(can_init_gives_up_in_bounded_time)
{
    const uint32_t ids[1] = {0x110U};
    fake.can_no_clock = true;
    fake.can.MSR = 0U;
    fake.reads = 0;
    ck_assert_int_eq(odo_bxcan_init(&fake.can, 42000000UL, 500000UL, ids, 1U, POLLS), ODO_BXCAN_ERR_INIT_MODE);
    ck_assert_uint_le(fake.reads, POLLS + 8U);
    fake_stm32_reset();
    fake.can_stuck_in_init = true;
    ck_assert_int_eq(odo_bxcan_init(&fake.can, 42000000UL, 500000UL, ids, 1U, POLLS), ODO_BXCAN_ERR_NORMAL_MODE);
    ck_assert_int_eq(odo_bxcan_init(&fake.can, 42000000UL, 33333UL, ids, 1U, POLLS), ODO_BXCAN_ERR_BITRATE);
    ck_assert_int_eq(odo_bxcan_init(&fake.can, 42000000UL, 500000UL, ids, 0U, POLLS), ODO_BXCAN_ERR_IDS);
}
END_TEST

/* ---- IWDG -------------------------------------------------------------------------------- */

/// 200 ms nominal on the 32 kHz LSI: (4 * 2^PR) * (RLR + 1) / 32 kHz within one LSI step; the
/// registers written after the unlock key, then reload and start.
START_TEST(watchdog_200_ms_on_the_lsi)
{
    ck_assert(odo_iwdg_start(&fake.iwdg, 200U, POLLS));
    const uint32_t div = 4UL << fake.iwdg.PR;
    const double t_ms = 1000.0 * div * (fake.iwdg.RLR + 1U) / 32000.0;
    ck_assert(t_ms > 199.0 && t_ms < 201.0);
    ck_assert(fake.iwdg_started);
    ck_assert_uint_eq(fake.iwdg_ignored_writes, 0U);
    ck_assert_uint_eq(fake.iwdg_reloads, 1U);
    odo_iwdg_refresh(&fake.iwdg);
    ck_assert_uint_eq(fake.iwdg_reloads, 2U);
    uint32_t pr = 0, rlr = 0;
    ck_assert(odo_iwdg_config(32768U, &pr, &rlr));
    ck_assert_uint_eq(pr, 6U);
    ck_assert(!odo_iwdg_config(40000U, &pr, &rlr));
    ck_assert(!odo_iwdg_config(0U, &pr, &rlr));
}
END_TEST

/* ---- the board tick ---------------------------------------------------------------------- */

static odo_params_t clapper_params(void)
{
    static sim_robot_t r;
    char err[256];
    odo_params_t p;
    ck_assert_msg(sim_robot_parse_file(ODO_SOURCE_DIR "/host_sim/robots/clapper.json", &r, err, sizeof err) == 0, "%s",
                  err);
    ck_assert_msg(sim_robot_to_params(&r, &p, err, sizeof err) == 0, "%s", err);
    p.ipec_mode = (uint8_t)ODO_IPEC_PAPER;
    return p;
}

static void push(const odo_can_frame_t *f) { fake_stm32_can_rx(f->id, false, false, f->dlc, f->data); }

/// The sensor frames of tick k: both trucks straight ahead, the link straight and at length.
static void sensor_frames(uint32_t k, uint32_t link_um)
{
    odo_can_frame_t f;
    for (uint8_t t = 0; t < 2; ++t) {
        const odo_msg_wheel_counts_t w = {(0xFFFF00U + 300U * k) & ODO_CAN_COUNT_MASK,
                                          (0xFFFF00U + 300U * k) & ODO_CAN_COUNT_MASK, (uint8_t)k, 0U};
        odo_can_pack_wheel_counts(t, &w, &f);
        push(&f);
    }
    const odo_msg_link_rotary_t rot = {0U, 0U, (uint8_t)k, ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID};
    odo_can_pack_link_rotary(&rot, &f);
    push(&f);
    const odo_msg_link_linear_t lin = {link_um, (uint8_t)k, ODO_LINK_STATUS_LENGTH_VALID};
    odo_can_pack_link_linear(&lin, &f);
    push(&f);
}

/// One board over N ticks, with or without bad frames mixed in; returns the final output.
typedef struct {
    odo_tick_output_t last;
    uint32_t faults_or;
    uint16_t rejected;
    odo_board_rx_counts_t counts;
    uint32_t frames_sent;
} board_run_t;

static board_run_t run_board(bool with_bad_frames, uint32_t ticks)
{
    fake_stm32_reset();
    const odo_board_config_t cfg = fake_config(ODO_WHEELS_CAN);
    static hal_ctx_t hal;
    static odo_app_t app;
    static odo_tick_input_t in;
    board_run_t res;
    memset(&res, 0, sizeof res);
    odo_board_init(&hal, &cfg);
    ck_assert_int_eq(hal.status.can, ODO_BXCAN_OK);
    const odo_params_t p = clapper_params();
    ck_assert_int_eq(odo_app_init_params(&app, &p), ODO_PARAMS_OK);
    const uint32_t link_um = p.link.length_nm / 1000U;
    for (uint32_t k = 0; k < ticks; ++k) {
        if (with_bad_frames && k % 5U == 2U) {
            odo_can_frame_t f;
            /* A wheel frame one byte short whose counts would be a huge jump. */
            const odo_msg_wheel_counts_t w = {0x123456U, 0x654321U, (uint8_t)k, 0U};
            odo_can_pack_wheel_counts(ODO_TRUCK_A, &w, &f);
            fake_stm32_can_rx(f.id, false, false, 7U, f.data);
            fake_stm32_can_rx(f.id, false, false, 15U, f.data);                    /* DLC 15: 8 bytes, not 8 */
            fake_stm32_can_rx(0x7FFU, false, false, 8U, f.data);                   /* an identifier we don't know */
            fake_stm32_can_rx(ODO_CAN_ID_WHEEL_COUNTS_A, true, false, 8U, f.data); /* extended 0x110 */
            fake_stm32_can_rx(ODO_CAN_ID_LINK_ROTARY, false, true, 6U, f.data);    /* remote request */
            odo_can_pack_pose_xy(ODO_TRUCK_A, &(odo_msg_pose_xy_t){1, 2}, &f);     /* someone's output */
            push(&f);
        }
        sensor_frames(k, link_um);
        hal.periods = k + 1U;
        odo_board_tick(&hal, &app, &in, &res.last);
        res.faults_or |= res.last.faults;
        odo_msg_status_t st;
        ck_assert_int_eq(odo_can_unpack_status(&res.last.frames[res.last.n_frames - 1U], &st), ODO_CAN_OK);
        res.rejected = st.rejected;
        if (with_bad_frames && k % 5U == 2U) {
            ck_assert_uint_eq(st.faults & (ODO_FAULT_CAN_BAD_DLC | ODO_FAULT_CAN_UNKNOWN_ID),
                              ODO_FAULT_CAN_BAD_DLC | ODO_FAULT_CAN_UNKNOWN_ID);
        }
    }
    res.counts = hal.rx.count;
    res.frames_sent = fake.txlog_len;
    ck_assert_uint_eq(fake.iwdg_reloads, 1U + ticks);
    return res;
}

/// Bad input on the target: frames with the wrong DLC (short, or 9..15), unknown or extended
/// identifiers, remote requests and other nodes' outputs are counted (board counters, STATUS
/// fault bits and its Rejected field) and never integrated: the poses equal the clean run's bit
/// for bit.
START_TEST(bad_frames_are_counted_and_never_integrated)
{
    const uint32_t ticks = 50U;
    const board_run_t clean = run_board(false, ticks);
    const board_run_t dirty = run_board(true, ticks);
    for (int t = 0; t < 2; ++t) {
        ck_assert_int_eq(dirty.last.pose[t].x_mm_q32, clean.last.pose[t].x_mm_q32);
        ck_assert_int_eq(dirty.last.pose[t].y_mm_q32, clean.last.pose[t].y_mm_q32);
        ck_assert_uint_eq(dirty.last.pose[t].heading_q64, clean.last.pose[t].heading_q64);
    }
    ck_assert_int_gt(clean.last.pose[0].x_mm_q32, 0); /* it did drive */
    ck_assert_uint_eq(clean.faults_or & (ODO_FAULT_CAN_BAD_DLC | ODO_FAULT_CAN_UNKNOWN_ID | ODO_FAULT_COUNTER_JUMP_A |
                                         ODO_FAULT_IPEC_GATED),
                      0U);
    ck_assert_uint_eq(dirty.faults_or & ODO_FAULT_COUNTER_JUMP_A, 0U);
    const uint32_t bursts = 10U; /* ticks 2, 7, ... 47 */
    ck_assert_uint_eq(dirty.counts.bad_dlc, 2U * bursts);
    ck_assert_uint_eq(dirty.counts.unknown_id, 4U * bursts);
    ck_assert_uint_eq(dirty.counts.accepted, 4U * ticks);
    ck_assert_uint_eq(clean.counts.accepted, 4U * ticks);
    ck_assert_uint_eq(dirty.rejected, 2U * bursts); /* ticks with BAD_DLC + ticks with UNKNOWN_ID */
    ck_assert_uint_eq(dirty.frames_sent, clean.frames_sent);
    ck_assert_uint_eq(clean.frames_sent, 6U * ticks); /* POSE XY/THETA x2, IPEC_CORR, STATUS */
}
END_TEST

/// Error frames raise BUS_ERROR; a FIFO overrun is counted (its lost frames show as sequence gaps).
START_TEST(error_frames_and_overruns_are_counted)
{
    odo_board_rx_t rx;
    odo_board_rx_init(&rx, true, false);
    const odo_can_frame_t err = {0x0U, 8U, ODO_CAN_FLAG_ERR, {0}};
    odo_board_rx_frame(&rx, &err, 8U);
    odo_board_rx_overrun(&rx);
    odo_wheel_input_t w[2];
    odo_link_input_t l;
    uint32_t f = 0;
    odo_board_rx_take(&rx, w, &l, &f);
    ck_assert_uint_eq(f, ODO_FAULT_BUS_ERROR);
    ck_assert_uint_eq(rx.count.error_frames, 1U);
    ck_assert_uint_eq(rx.count.overruns, 1U);
    ck_assert(!w[0].present && !w[1].present && !l.rotary_present && !l.linear_present);
    odo_board_rx_take(&rx, w, &l, &f);
    ck_assert_uint_eq(f, 0U); /* per tick */
}
END_TEST

/// Encoder counters straight into the step: a 16-bit truck B counter wrapping between ticks
/// integrates as the modular delta, exactly as odo_app_step does on the same raw values.
START_TEST(encoder_counters_feed_the_step_at_their_width)
{
    const odo_board_config_t cfg = fake_config(ODO_WHEELS_ENCODER);
    static hal_ctx_t hal;
    static odo_app_t app, ref;
    static odo_tick_input_t in, rin;
    static odo_tick_output_t out, rout;
    odo_board_init(&hal, &cfg);
    const odo_params_t p = clapper_params();
    ck_assert_int_eq(odo_app_init_params(&app, &p), ODO_PARAMS_OK);
    ck_assert_int_eq(odo_app_init_params(&ref, &p), ODO_PARAMS_OK);
    uint32_t a = 0xFFFFFF00UL, b = 0xFF00U;
    for (uint32_t k = 0; k < 20U; ++k) {
        a += 250U;
        b = (b + 250U) & 0xFFFFU;
        fake.tim[1].CNT = a;
        fake.tim[2].CNT = a + 1U;
        fake.tim[3].CNT = b;
        fake.tim[4].CNT = b;
        hal.periods = k + 1U;
        odo_board_tick(&hal, &app, &in, &out);
        ck_assert_uint_eq(in.wheel[0].bits, 32U);
        ck_assert_uint_eq(in.wheel[1].bits, 16U);
        memset(&rin, 0, sizeof rin);
        rin.t_us = in.t_us;
        rin.wheel[0] = (odo_wheel_input_t){true, 32U, (uint8_t)k, 0U, a, a + 1U};
        rin.wheel[1] = (odo_wheel_input_t){true, 16U, (uint8_t)k, 0U, b, b};
        odo_app_step(&ref, &rin, &rout);
        ck_assert_int_eq(out.pose[1].x_mm_q32, rout.pose[1].x_mm_q32);
        ck_assert_uint_eq(out.pose[0].heading_q64, rout.pose[0].heading_q64);
    }
    ck_assert_int_gt(out.pose[1].x_mm_q32, rout.pose[1].x_mm_q32 - 1); /* moved forward */
    ck_assert_uint_eq(out.faults & (ODO_FAULT_COUNTER_JUMP_A | ODO_FAULT_COUNTER_JUMP_B), 0U);
}
END_TEST

/// A part where nothing answers (no crystal, no PLL lock, CAN without clock; as on qemu's
/// netduinoplus2, which models none of them): start-up finishes in bounded time, says what is
/// missing, and the tick still runs and counts the frames it could not send.
START_TEST(board_comes_up_when_no_peripheral_answers)
{
    fake.hse_works = false;
    fake.pll_locks = false;
    fake.can_no_clock = true;
    fake.can.MSR = 0U;
    const odo_board_config_t cfg = fake_config(ODO_WHEELS_ENCODER);
    static hal_ctx_t hal;
    static odo_app_t app;
    static odo_tick_input_t in;
    static odo_tick_output_t out;
    fake.reads = 0;
    odo_board_init(&hal, &cfg);
    ck_assert_uint_le(fake.reads, 6U * POLLS);
    ck_assert_int_eq(hal.status.clock.source, ODO_CLOCK_HSI);
    ck_assert_int_eq(hal.status.can, ODO_BXCAN_ERR_INIT_MODE);
    ck_assert(hal.status.tick_ok);
    ck_assert_uint_eq(fake.tim[5].PSC, 15U); /* 1 MHz from the 16 MHz HSI */
    const odo_params_t p = clapper_params();
    ck_assert_int_eq(odo_app_init_params(&app, &p), ODO_PARAMS_OK);
    odo_board_tick(&hal, &app, &in, &out);
    ck_assert_uint_eq(app.tx_dropped, out.n_frames);
    ck_assert_uint_eq(hal.status.tx_refused, out.n_frames);
    ck_assert_uint_eq(fake.txlog_len, 0U);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("cortexm_port");
    TCase *tc = tcase_create("drivers");
    tcase_add_checked_fixture(tc, setup, NULL);
    tcase_add_test(tc, clock_168mhz_from_the_crystal);
    tcase_add_test(tc, clock_falls_back_to_the_hsi_when_the_crystal_does_not_start);
    tcase_add_test(tc, clock_stays_on_the_hsi_when_the_pll_does_not_lock);
    tcase_add_test(tc, tick_timer_counts_microseconds_to_40_ms);
    tcase_add_test(tc, tick_timer_refuses_clocks_it_cannot_divide_to_1_mhz);
    tcase_add_test(tc, encoder_mode_3_on_ti1_and_ti2_at_full_width);
    tcase_add_test(tc, hctl_position_is_read_in_latch_order_and_never_tears);
    tcase_add_test(tc, hctl_position_read_msb_first_tears_at_a_carry);
    tcase_add_test(tc, can_bit_timing_is_exact_at_every_standard_rate);
    tcase_add_test(tc, can_filters_hold_the_dbc_sensor_identifiers);
    tcase_add_test(tc, can_frames_round_trip_through_mailboxes_and_fifo);
    tcase_add_test(tc, can_init_gives_up_in_bounded_time);
    tcase_add_test(tc, watchdog_200_ms_on_the_lsi);
    tcase_add_test(tc, bad_frames_are_counted_and_never_integrated);
    tcase_add_test(tc, error_frames_and_overruns_are_counted);
    tcase_add_test(tc, encoder_counters_feed_the_step_at_their_width);
    tcase_add_test(tc, board_comes_up_when_no_peripheral_answers);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
