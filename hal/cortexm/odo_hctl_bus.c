/// HCTL-1100 bus over GPIO (odo_hctl_bus.h).
#include "odo_hctl_bus.h"

#include "odo_reg.h"

#define DATA_MODER_MASK 0xFFFFU /* pins 0-7, two bits each */
#define DATA_MODER_OUT  0x5555U /* 01 = general-purpose output */

static void pin_high(odo_stm32_gpio_t *g, uint8_t pin) { odo_reg_write(&g->BSRR, (uint32_t)1U << pin); }

static void pin_low(odo_stm32_gpio_t *g, uint8_t pin) { odo_reg_write(&g->BSRR, (uint32_t)1U << (16U + pin)); }

static void pin_output(odo_stm32_gpio_t *g, uint8_t pin)
{
    odo_reg_modify(&g->MODER, (uint32_t)3U << (2U * pin), (uint32_t)ODO_GPIO_MODE_OUTPUT << (2U * pin));
}

void odo_hctl_bus_init(const odo_hctl_bus_t *bus)
{
    odo_stm32_gpio_t *c = bus->ctrl;
    pin_low(c, bus->ale_pin);
    pin_high(c, bus->oe_pin);
    pin_high(c, bus->rw_pin);
    pin_output(c, bus->ale_pin);
    pin_output(c, bus->oe_pin);
    pin_output(c, bus->rw_pin);
    for (uint8_t k = 0U; k < bus->chips && k < ODO_HCTL_MAX_CHIPS; ++k) {
        pin_high(c, bus->cs_pin[k]);
        pin_output(c, bus->cs_pin[k]);
    }
    odo_reg_modify(&bus->data->MODER, DATA_MODER_MASK, 0U);
}

uint8_t odo_hctl_read_reg(const odo_hctl_bus_t *bus, uint8_t chip, uint8_t reg)
{
    odo_stm32_gpio_t *c = bus->ctrl;
    odo_stm32_gpio_t *d = bus->data;
    const uint8_t cs = bus->cs_pin[chip < ODO_HCTL_MAX_CHIPS ? chip : 0U];
    /* Address phase: drive the register number, latch it on ALE's falling edge. */
    odo_reg_write(&d->BSRR, (uint32_t)reg | ((uint32_t)(uint8_t)~reg << 16));
    odo_reg_modify(&d->MODER, DATA_MODER_MASK, DATA_MODER_OUT);
    pin_low(c, cs);
    pin_high(c, bus->ale_pin);
    pin_low(c, bus->ale_pin);
    /* Data phase: release the bus, let the chip drive it. */
    odo_reg_modify(&d->MODER, DATA_MODER_MASK, 0U);
    pin_low(c, bus->oe_pin);
    for (volatile uint32_t i = 0U; i < bus->settle_loops; ++i) {
    }
    const uint8_t v = (uint8_t)(odo_reg_read(&d->IDR) & 0xFFU);
    pin_high(c, bus->oe_pin);
    pin_high(c, cs);
    return v;
}

uint32_t odo_hctl_read_position(const odo_hctl_bus_t *bus, uint8_t chip)
{
    const uint32_t lsb = odo_hctl_read_reg(bus, chip, ODO_HCTL_R14H); /* latches R12H/R13H */
    const uint32_t mid = odo_hctl_read_reg(bus, chip, ODO_HCTL_R13H);
    const uint32_t msb = odo_hctl_read_reg(bus, chip, ODO_HCTL_R12H);
    return (msb << 16) | (mid << 8) | lsb;
}
