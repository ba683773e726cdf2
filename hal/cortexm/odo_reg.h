/// Register access for the board drivers: every read and write of a peripheral register goes
/// through these two functions, so the drivers run unchanged against real hardware (volatile
/// accesses, inlined) and, on the host, against a register-level fake (tests/target/fake_stm32.c)
/// that gives each register its hardware behaviour (ready flags, write-1-to-clear, FIFOs).
///
/// ODO_REG_FAKE selects the fake: the two functions are then defined by the test program.
#ifndef ODO_REG_H
#define ODO_REG_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#ifdef ODO_REG_FAKE
uint32_t odo_reg_read(const volatile uint32_t *reg);
void odo_reg_write(volatile uint32_t *reg, uint32_t value);
#else
static inline uint32_t odo_reg_read(const volatile uint32_t *reg) { return *reg; }

static inline void odo_reg_write(volatile uint32_t *reg, uint32_t value) { *reg = value; }
#endif

/// Read-modify-write: clear `clear`, then set `set`. Not atomic; the drivers call it from the
/// main loop only (no interrupt handler touches these registers).
static inline void odo_reg_modify(volatile uint32_t *reg, uint32_t clear, uint32_t set)
{
    odo_reg_write(reg, (odo_reg_read(reg) & ~clear) | set);
}

/// Poll until (reg & mask) == want, at most `polls` reads. Returns true iff it got there.
static inline int odo_reg_wait(const volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t polls)
{
    for (uint32_t i = 0U; i < polls; ++i) {
        if ((odo_reg_read(reg) & mask) == want) {
            return 1;
        }
    }
    return 0;
}

#ifdef __cplusplus
}
#endif
#endif
