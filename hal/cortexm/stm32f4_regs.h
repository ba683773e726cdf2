/// STM32F405/407 (and F401) peripheral registers the board port uses, as laid out in ST's
/// reference manual RM0090 ("STM32F405/415, STM32F407/417, STM32F427/437 and STM32F429/439
/// advanced Arm-based 32-bit MCUs"). Each block cites its register-map section; offsets are
/// checked below with static asserts, so a typo in a reserved gap fails the build. Only the bits
/// the drivers use are named. Datasheet facts, not code: change only against the manual.
#ifndef STM32F4_REGS_H
#define STM32F4_REGS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef volatile uint32_t odo_reg32_t;

/* ---- RCC: RM0090 chapter 'Reset and clock control for STM32F405xx/07xx and STM32F415xx/17xx',
 *      section 'RCC registers' (register map at its end); cited by register name below, since the
 *      chapter's number differs between manual revisions. ----------------------------------------- */
typedef struct {
    odo_reg32_t CR;        ///< 0x00 RCC_CR, clock control
    odo_reg32_t PLLCFGR;   ///< 0x04 RCC_PLLCFGR, PLL configuration
    odo_reg32_t CFGR;      ///< 0x08 RCC_CFGR, clock configuration
    odo_reg32_t CIR;       ///< 0x0C clock interrupt
    odo_reg32_t AHB1RSTR;  ///< 0x10
    odo_reg32_t AHB2RSTR;  ///< 0x14
    odo_reg32_t AHB3RSTR;  ///< 0x18
    odo_reg32_t reserved0; ///< 0x1C
    odo_reg32_t APB1RSTR;  ///< 0x20
    odo_reg32_t APB2RSTR;  ///< 0x24
    odo_reg32_t reserved1[2];
    odo_reg32_t AHB1ENR;   ///< 0x30 RCC_AHB1ENR, AHB1 peripheral clock enable
    odo_reg32_t AHB2ENR;   ///< 0x34
    odo_reg32_t AHB3ENR;   ///< 0x38
    odo_reg32_t reserved2; ///< 0x3C
    odo_reg32_t APB1ENR;   ///< 0x40 RCC_APB1ENR
    odo_reg32_t APB2ENR;   ///< 0x44 RCC_APB2ENR
    odo_reg32_t reserved3[10];
    odo_reg32_t BDCR; ///< 0x70
    odo_reg32_t CSR;  ///< 0x74 clock control & status (LSI for the IWDG)
} odo_stm32_rcc_t;

#define ODO_RCC_CR_HSION  (1U << 0)
#define ODO_RCC_CR_HSIRDY (1U << 1)
#define ODO_RCC_CR_HSEON  (1U << 16)
#define ODO_RCC_CR_HSERDY (1U << 17)
#define ODO_RCC_CR_HSEBYP (1U << 18)
#define ODO_RCC_CR_PLLON  (1U << 24)
#define ODO_RCC_CR_PLLRDY (1U << 25)
/* PLLCFGR: PLLM[5:0], PLLN[14:6], PLLP[17:16] (00: /2), PLLSRC[22] (1: HSE), PLLQ[27:24]. */
#define ODO_RCC_PLLCFGR(m, n, p_div, src_hse, q)                                                                      \
    ((uint32_t)(m) | ((uint32_t)(n) << 6) | ((uint32_t)(((p_div) / 2U) - 1U) << 16) | ((src_hse) ? (1U << 22) : 0U) | \
     ((uint32_t)(q) << 24))
/* CFGR: SW[1:0], SWS[3:2] (00 HSI, 01 HSE, 10 PLL), HPRE[7:4], PPRE1[12:10], PPRE2[15:13]. */
#define ODO_RCC_CFGR_SW_MASK    (3U << 0)
#define ODO_RCC_CFGR_SWS_MASK   (3U << 2)
#define ODO_RCC_CFGR_SW_HSI     0U
#define ODO_RCC_CFGR_SW_HSE     1U
#define ODO_RCC_CFGR_SW_PLL     2U
#define ODO_RCC_CFGR_SWS(sw)    ((uint32_t)(sw) << 2)
#define ODO_RCC_CFGR_HPRE_MASK  (0xFU << 4)
#define ODO_RCC_CFGR_PPRE1_MASK (7U << 10)
#define ODO_RCC_CFGR_PPRE2_MASK (7U << 13)
#define ODO_RCC_CFGR_PPRE1_DIV4 (5U << 10)
#define ODO_RCC_CFGR_PPRE2_DIV2 (4U << 13)
#define ODO_RCC_CSR_LSION       (1U << 0)
#define ODO_RCC_CSR_LSIRDY      (1U << 1)

/* ---- Embedded flash interface: RM0090 section 3.9 (FLASH_ACR 3.9.1), wait states 3.5.1 ------- */
typedef struct {
    odo_reg32_t ACR; ///< 0x00 access control: LATENCY[2:0], PRFTEN 8, ICEN 9, DCEN 10
    odo_reg32_t KEYR;
    odo_reg32_t OPTKEYR;
    odo_reg32_t SR;
    odo_reg32_t CR;
    odo_reg32_t OPTCR;
} odo_stm32_flash_t;

#define ODO_FLASH_ACR_LATENCY_MASK 7U
#define ODO_FLASH_ACR_PRFTEN       (1U << 8)
#define ODO_FLASH_ACR_ICEN         (1U << 9)
#define ODO_FLASH_ACR_DCEN         (1U << 10)

/* ---- GPIO: RM0090 section 8.4 (GPIO registers), map in 8.4.11 -------------------------------- */
typedef struct {
    odo_reg32_t MODER;   ///< 0x00 2 bits per pin: 00 input, 01 output, 10 alternate, 11 analog
    odo_reg32_t OTYPER;  ///< 0x04
    odo_reg32_t OSPEEDR; ///< 0x08
    odo_reg32_t PUPDR;   ///< 0x0C 2 bits per pin: 00 none, 01 pull-up, 10 pull-down
    odo_reg32_t IDR;     ///< 0x10 input data
    odo_reg32_t ODR;     ///< 0x14 output data
    odo_reg32_t BSRR;    ///< 0x18 write-only: bits 0-15 set, bits 16-31 reset the pin
    odo_reg32_t LCKR;    ///< 0x1C
    odo_reg32_t AFR[2];  ///< 0x20 AFRL (pins 0-7), 0x24 AFRH (pins 8-15): 4 bits per pin
} odo_stm32_gpio_t;

#define ODO_GPIO_MODE_INPUT  0U
#define ODO_GPIO_MODE_OUTPUT 1U
#define ODO_GPIO_MODE_AF     2U
#define ODO_GPIO_PULL_UP     1U

/* ---- General-purpose timers TIM2-TIM5: RM0090 section 18.4, map 18.4.21; TIM6/7 (20.4) share
 *      the offsets of every register used here (CR1, DIER, SR, EGR, CNT, PSC, ARR). -------------- */
typedef struct {
    odo_reg32_t CR1;   ///< 0x00 CEN bit 0, URS bit 2
    odo_reg32_t CR2;   ///< 0x04
    odo_reg32_t SMCR;  ///< 0x08 SMS[2:0]: 011 encoder mode 3 (18.3.12)
    odo_reg32_t DIER;  ///< 0x0C
    odo_reg32_t SR;    ///< 0x10 UIF bit 0, rc_w0
    odo_reg32_t EGR;   ///< 0x14 UG bit 0
    odo_reg32_t CCMR1; ///< 0x18 CC1S[1:0], IC1F[7:4], CC2S[9:8], IC2F[15:12]
    odo_reg32_t CCMR2; ///< 0x1C
    odo_reg32_t CCER;  ///< 0x20 CC1P bit 1, CC2P bit 5
    odo_reg32_t CNT;   ///< 0x24 16 bits (TIM3/4) or 32 bits (TIM2/5)
    odo_reg32_t PSC;   ///< 0x28
    odo_reg32_t ARR;   ///< 0x2C
    odo_reg32_t reserved0;
    odo_reg32_t CCR[4]; ///< 0x34..0x40
    odo_reg32_t reserved1;
    odo_reg32_t DCR;  ///< 0x48
    odo_reg32_t DMAR; ///< 0x4C
    odo_reg32_t OR;   ///< 0x50
} odo_stm32_tim_t;

#define ODO_TIM_CR1_CEN           (1U << 0)
#define ODO_TIM_CR1_URS           (1U << 2)
#define ODO_TIM_DIER_UIE          (1U << 0)
#define ODO_TIM_SR_UIF            (1U << 0)
#define ODO_TIM_EGR_UG            (1U << 0)
#define ODO_TIM_SMCR_SMS_ENCODER3 3U
#define ODO_TIM_CCMR1_CC1S_TI1    (1U << 0)
#define ODO_TIM_CCMR1_CC2S_TI2    (1U << 8)
#define ODO_TIM_CCMR1_IC1F(f)     ((uint32_t)(f) << 4)
#define ODO_TIM_CCMR1_IC2F(f)     ((uint32_t)(f) << 12)

/* ---- bxCAN: RM0090 section 32.9 (CAN registers), map 32.9.5 ---------------------------------- */
typedef struct {
    odo_reg32_t TIR;  ///< STID[31:21], EXID[20:3], IDE 2, RTR 1, TXRQ 0
    odo_reg32_t TDTR; ///< DLC[3:0]
    odo_reg32_t TDLR;
    odo_reg32_t TDHR;
} odo_stm32_can_tx_t;

typedef struct {
    odo_reg32_t RIR;  ///< STID[31:21], EXID[20:3], IDE 2, RTR 1
    odo_reg32_t RDTR; ///< DLC[3:0], FMI[15:8], TIME[31:16]
    odo_reg32_t RDLR;
    odo_reg32_t RDHR;
} odo_stm32_can_rx_t;

typedef struct {
    odo_reg32_t FR1;
    odo_reg32_t FR2;
} odo_stm32_can_filter_t;

typedef struct {
    odo_reg32_t MCR;  ///< 0x000 INRQ 0, SLEEP 1, TXFP 2, ABOM 6
    odo_reg32_t MSR;  ///< 0x004 INAK 0, SLAK 1
    odo_reg32_t TSR;  ///< 0x008 TME0..2 bits 26..28
    odo_reg32_t RF0R; ///< 0x00C FMP0[1:0], FULL0 3, FOVR0 4 (rc_w1), RFOM0 5
    odo_reg32_t RF1R; ///< 0x010
    odo_reg32_t IER;  ///< 0x014
    odo_reg32_t ESR;  ///< 0x018 EWGF 0, EPVF 1, BOFF 2, LEC[6:4], TEC[23:16], REC[31:24]
    odo_reg32_t BTR;  ///< 0x01C BRP[9:0], TS1[19:16], TS2[22:20], SJW[25:24] (32.7.7, 32.9.2)
    odo_reg32_t reserved0[88];
    odo_stm32_can_tx_t tx[3]; ///< 0x180
    odo_stm32_can_rx_t rx[2]; ///< 0x1B0
    odo_reg32_t reserved1[12];
    odo_reg32_t FMR;  ///< 0x200 FINIT 0, CAN2SB[13:8]
    odo_reg32_t FM1R; ///< 0x204 1: identifier list mode
    odo_reg32_t reserved2;
    odo_reg32_t FS1R; ///< 0x20C 0: dual 16-bit scale
    odo_reg32_t reserved3;
    odo_reg32_t FFA1R; ///< 0x214 0: FIFO 0
    odo_reg32_t reserved4;
    odo_reg32_t FA1R; ///< 0x21C 1: filter active
    odo_reg32_t reserved5[8];
    odo_stm32_can_filter_t filter[28]; ///< 0x240
} odo_stm32_can_t;

#define ODO_CAN_MCR_INRQ       (1U << 0)
#define ODO_CAN_MCR_SLEEP      (1U << 1)
#define ODO_CAN_MCR_TXFP       (1U << 2)
#define ODO_CAN_MCR_ABOM       (1U << 6)
#define ODO_CAN_MSR_INAK       (1U << 0)
#define ODO_CAN_MSR_SLAK       (1U << 1)
#define ODO_CAN_TSR_TME(n)     (1U << (26U + (n)))
#define ODO_CAN_RF0R_FMP0_MASK 3U
#define ODO_CAN_RF0R_FOVR0     (1U << 4)
#define ODO_CAN_RF0R_RFOM0     (1U << 5)
#define ODO_CAN_ESR_BOFF       (1U << 2)
#define ODO_CAN_TIR_TXRQ       (1U << 0)
#define ODO_CAN_XIR_RTR        (1U << 1)
#define ODO_CAN_XIR_IDE        (1U << 2)
#define ODO_CAN_FMR_FINIT      (1U << 0)
#define ODO_CAN_FILTER_BANKS   14U ///< banks of CAN1 with the reset CAN2SB (32.7.4)

/* ---- IWDG: RM0090 section 21.4 (IWDG registers), map 21.4.5 ---------------------------------- */
typedef struct {
    odo_reg32_t KR;  ///< 0x00 key: 0x5555 unlock PR/RLR, 0xAAAA reload, 0xCCCC start
    odo_reg32_t PR;  ///< 0x04 prescaler: 4 * 2^PR, PR in 0..6
    odo_reg32_t RLR; ///< 0x08 reload, 12 bits
    odo_reg32_t SR;  ///< 0x0C PVU 0, RVU 1: an update is in progress
} odo_stm32_iwdg_t;

#define ODO_IWDG_KEY_UNLOCK 0x5555U
#define ODO_IWDG_KEY_RELOAD 0xAAAAU
#define ODO_IWDG_KEY_START  0xCCCCU

/* ---- Memory map: RM0090 section 2.3, Table 1 ------------------------------------------------- */
#define ODO_STM32_TIM2_BASE       0x40000000U
#define ODO_STM32_TIM3_BASE       0x40000400U
#define ODO_STM32_TIM4_BASE       0x40000800U
#define ODO_STM32_TIM5_BASE       0x40000C00U
#define ODO_STM32_TIM6_BASE       0x40001000U
#define ODO_STM32_TIM7_BASE       0x40001400U
#define ODO_STM32_IWDG_BASE       0x40003000U
#define ODO_STM32_CAN1_BASE       0x40006400U
#define ODO_STM32_GPIO_BASE(port) (0x40020000U + 0x400U * (uint32_t)(port)) ///< A = 0 .. I = 8
#define ODO_STM32_RCC_BASE        0x40023800U
#define ODO_STM32_FLASH_BASE      0x40023C00U

/* RCC enable bits of the peripherals above (RCC_AHB1ENR, RCC_APB1ENR). */
#define ODO_RCC_AHB1ENR_GPIO(port) (1U << (port))
#define ODO_RCC_APB1ENR_TIM2       (1U << 0)
#define ODO_RCC_APB1ENR_TIM3       (1U << 1)
#define ODO_RCC_APB1ENR_TIM4       (1U << 2)
#define ODO_RCC_APB1ENR_TIM5       (1U << 3)
#define ODO_RCC_APB1ENR_TIM6       (1U << 4)
#define ODO_RCC_APB1ENR_TIM7       (1U << 5)
#define ODO_RCC_APB1ENR_CAN1       (1U << 25)

/* Layout checks: C99 has no _Static_assert, so a negative array size fails the build. */
#define ODO_REG_AT(type, field, off) typedef char odo_reg_at_##type##_##field[(offsetof(type, field) == (off)) ? 1 : -1]
ODO_REG_AT(odo_stm32_rcc_t, APB1ENR, 0x40);
ODO_REG_AT(odo_stm32_rcc_t, CSR, 0x74);
ODO_REG_AT(odo_stm32_gpio_t, AFR, 0x20);
ODO_REG_AT(odo_stm32_tim_t, CNT, 0x24);
ODO_REG_AT(odo_stm32_tim_t, CCR, 0x34);
ODO_REG_AT(odo_stm32_tim_t, OR, 0x50);
ODO_REG_AT(odo_stm32_can_t, BTR, 0x01C);
ODO_REG_AT(odo_stm32_can_t, tx, 0x180);
ODO_REG_AT(odo_stm32_can_t, rx, 0x1B0);
ODO_REG_AT(odo_stm32_can_t, FMR, 0x200);
ODO_REG_AT(odo_stm32_can_t, FA1R, 0x21C);
ODO_REG_AT(odo_stm32_can_t, filter, 0x240);
ODO_REG_AT(odo_stm32_iwdg_t, SR, 0x0C);

#ifdef __cplusplus
}
#endif
#endif
