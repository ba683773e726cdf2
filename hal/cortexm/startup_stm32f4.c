/// Reset and exception vectors for a generic STM32F4-class Cortex-M4, in C.
///
/// The core loads SP from word 0 of the vector table and jumps to Reset_Handler, so no assembly
/// is needed: Reset_Handler copies .data from flash, zeroes .bss and calls main(). The FPU is left
/// off: the image is integer-only (soft-float ABI; the ctest firmware.cm4_image proves that no
/// floating-point code is linked), and newlib's crt0 is not used (-nostartfiles).
#include <stddef.h>
#include <stdint.h>

#include "odo_board.h"

/// Interrupt lines of the STM32F405/407 (RM0090: WWDG = 0 ... FPU = 81). Larger F4 parts have up
/// to 97; raise this when the board port gains drivers for them.
#define ODO_BOARD_IRQ_COUNT 82U

typedef void (*odo_isr_t)(void);

/// Layout fixed by the Armv7-M architecture: initial SP, then 15 system exceptions, then IRQs.
/// The core reads every member at reset and on exceptions; C never does (hence the cppcheck notes).
typedef struct {
    // cppcheck-suppress unusedStructMember ; read by the core at reset
    const uint32_t *initial_sp;
    // cppcheck-suppress unusedStructMember ; read by the core on each exception
    odo_isr_t exception[15]; ///< Reset (1) .. SysTick (15)
    // cppcheck-suppress unusedStructMember ; read by the NVIC on each interrupt
    odo_isr_t irq[ODO_BOARD_IRQ_COUNT];
} odo_vector_table_t;

// Provided by odo_cm4.ld.
extern const uint32_t _estack[];
extern const uint32_t _sidata[];
extern uint32_t _sdata[];
extern uint32_t _edata[];
extern uint32_t _sbss[];
extern uint32_t _ebss[];

void NMI_Handler(void) __attribute__((weak, alias("Default_Handler")));
void HardFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void MemManage_Handler(void) __attribute__((weak, alias("Default_Handler")));
void BusFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void UsageFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SVC_Handler(void) __attribute__((weak, alias("Default_Handler")));
void DebugMon_Handler(void) __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SysTick_Handler(void) __attribute__((weak, alias("Default_Handler")));

#define ODO_H1  Default_Handler
#define ODO_H2  ODO_H1, ODO_H1
#define ODO_H4  ODO_H2, ODO_H2
#define ODO_H8  ODO_H4, ODO_H4
#define ODO_H16 ODO_H8, ODO_H8
#define ODO_H32 ODO_H16, ODO_H16
#define ODO_H64 ODO_H32, ODO_H32

/// Placed first in flash by odo_cm4.ld (section .isr_vector, KEEP).
__attribute__((section(".isr_vector"), used)) static const odo_vector_table_t odo_vector_table = {
    .initial_sp = _estack,
    .exception =
        {
            Reset_Handler,
            NMI_Handler,
            HardFault_Handler,
            MemManage_Handler,
            BusFault_Handler,
            UsageFault_Handler,
            0,
            0,
            0,
            0, // reserved
            SVC_Handler,
            DebugMon_Handler,
            0, // reserved
            PendSV_Handler,
            SysTick_Handler,
        },
    // No peripheral interrupt is enabled yet; every line traps in Default_Handler.
    .irq = {ODO_H64, ODO_H16, ODO_H2},
};

/// C99 static assert: the vector table must be a packed array of 32-bit words.
typedef char odo_vector_table_is_packed[(sizeof(odo_vector_table_t) == 4U * (16U + ODO_BOARD_IRQ_COUNT)) ? 1 : -1];

void Reset_Handler(void)
{
    /* Word counts from the linker symbols' addresses: comparing pointers into different
     * objects (dst < _edata) is undefined in C, and cppcheck says so. */
    const size_t data_words = ((uintptr_t)_edata - (uintptr_t)_sdata) / sizeof(uint32_t);
    const size_t bss_words = ((uintptr_t)_ebss - (uintptr_t)_sbss) / sizeof(uint32_t);
    for (size_t i = 0U; i < data_words; ++i) {
        _sdata[i] = _sidata[i];
    }
    for (size_t i = 0U; i < bss_words; ++i) {
        _sbss[i] = 0U;
    }
    (void)main();
    for (;;) {
        // main() does not return; if it ever does, stay here rather than run off into flash.
    }
}

/// Unexpected exception or interrupt: stop here with the fault state intact for the debugger
/// (the IPSR names the vector). A production build would reset via the watchdog.
void Default_Handler(void)
{
    for (;;) {
    }
}
