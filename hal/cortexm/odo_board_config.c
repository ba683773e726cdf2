/// The default board: a generic STM32F405/407 motor controller. Edit this table (or add one per
/// board) to match a schematic; nothing else in the port names a pin or a peripheral.
///
///   truck A wheels   TIM2 (32-bit) PA15/PB3 AF1, TIM5 (32-bit) PA0/PA1 AF2   (encoder mode)
///   truck B wheels   TIM3 (16-bit) PA6/PA7 AF2,  TIM4 (16-bit) PB6/PB7 AF2   (encoder mode)
///   HCTL-1100 bus    D0-D7 PE0-PE7; ALE PE8, /OE PE9, R/W PE10, /CS PE11-PE14 (ODO_CM4_WHEELS=hctl)
///   CAN1             PB8 RX, PB9 TX, AF9; 500 kbit/s
///   tick             TIM7, 40 ms; watchdog 200 ms (five ticks); HSE 8 MHz crystal
/// Pin functions: STM32F405xx/407xx datasheet (DS8626), "Alternate function mapping".
#include "odo_board.h"

#define GPIO(port) ((odo_stm32_gpio_t *)ODO_STM32_GPIO_BASE(port))
#define PA         0U
#define PB         1U
#define PE         4U
#define TIM(base)  ((odo_stm32_tim_t *)(base))

#ifndef ODO_CM4_WHEEL_SOURCE
#define ODO_CM4_WHEEL_SOURCE ODO_WHEELS_ENCODER
#endif

const odo_board_config_t odo_board_config = {
    .rcc = (odo_stm32_rcc_t *)ODO_STM32_RCC_BASE,
    .flash = (odo_stm32_flash_t *)ODO_STM32_FLASH_BASE,
    .iwdg = (odo_stm32_iwdg_t *)ODO_STM32_IWDG_BASE,
    .can = (odo_stm32_can_t *)ODO_STM32_CAN1_BASE,
    .tick_tim = TIM(ODO_STM32_TIM7_BASE),
    .tick_tim_apb1enr = ODO_RCC_APB1ENR_TIM7,
    .hse_hz = 8000000U,
    .tick_us = 40000U,
    .can_bitrate = 500000U,
    .can_rx = {GPIO(PB), PB, 8U, 9U},
    .can_tx = {GPIO(PB), PB, 9U, 9U},
    .watchdog_ms = 200U,
    .polls = 200000U,
    .encoder_filter = 3U,
    .truck =
        {
            {.source = ODO_CM4_WHEEL_SOURCE,
             .tim = {TIM(ODO_STM32_TIM2_BASE), TIM(ODO_STM32_TIM5_BASE)},
             .tim_apb1enr = {ODO_RCC_APB1ENR_TIM2, ODO_RCC_APB1ENR_TIM5},
             .tim_bits = {32U, 32U},
             .ti = {{{GPIO(PA), PA, 15U, 1U}, {GPIO(PB), PB, 3U, 1U}},
                    {{GPIO(PA), PA, 0U, 2U}, {GPIO(PA), PA, 1U, 2U}}},
             .hctl_chip = {0U, 1U}},
            {.source = ODO_CM4_WHEEL_SOURCE,
             .tim = {TIM(ODO_STM32_TIM3_BASE), TIM(ODO_STM32_TIM4_BASE)},
             .tim_apb1enr = {ODO_RCC_APB1ENR_TIM3, ODO_RCC_APB1ENR_TIM4},
             .tim_bits = {16U, 16U},
             .ti = {{{GPIO(PA), PA, 6U, 2U}, {GPIO(PA), PA, 7U, 2U}}, {{GPIO(PB), PB, 6U, 2U}, {GPIO(PB), PB, 7U, 2U}}},
             .hctl_chip = {2U, 3U}},
        },
    .hctl = {GPIO(PE), GPIO(PE), 8U, 9U, 10U, {11U, 12U, 13U, 14U}, 4U, 8U},
    .hctl_port_index = {PE, PE},
};
