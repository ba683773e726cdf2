/// Reset and fault vectors of the target test programs on qemu `mps2-an386` (see mps2_an386.ld).
///
/// Reset_Handler prepares C (copy .data, zero .bss), opens the semihosting console
/// (newlib's rdimon: stdout goes to qemu's stdout), runs main and passes its return value to
/// exit(), which newlib-rdimon reports with the semihosting SYS_EXIT(_EXTENDED) call, so qemu exits
/// with the program's status. A fault of any kind exits with ODO_TARGET_FAULT_EXIT, so a crash
/// fails its ctest instead of hanging it.
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define ODO_TARGET_FAULT_EXIT 70

extern uint32_t _estack[];
extern const uint32_t _sidata[];
extern uint32_t _sdata[];
extern uint32_t _edata[];
extern uint32_t _sbss[];
extern uint32_t _ebss[];

int main(void);
void initialise_monitor_handles(void);
void Reset_Handler(void);
void Fault_Handler(void);
void _init(void);
void _fini(void);

typedef void (*odo_isr_t)(void);

/// Initial SP, then Reset .. SysTick (Armv7-M B1.5.3); no peripheral interrupt is used.
__attribute__((section(".isr_vector"), used)) static const odo_isr_t vectors[16] = {
    (odo_isr_t)(uintptr_t)_estack,
    Reset_Handler,
    Fault_Handler,
    Fault_Handler,
    Fault_Handler,
    Fault_Handler,
    Fault_Handler,
    0,
    0,
    0,
    0,
    Fault_Handler,
    Fault_Handler,
    0,
    Fault_Handler,
    Fault_Handler,
};

/// newlib's exit() runs the fini array through _fini (normally from crti.o, which
/// -nostartfiles leaves out); C has nothing to run there.
void _init(void) {}
void _fini(void) {}

void Reset_Handler(void)
{
    const uint32_t *src = _sidata;
    for (uint32_t *dst = _sdata; dst < _edata; ++dst, ++src) {
        *dst = *src;
    }
    for (uint32_t *dst = _sbss; dst < _ebss; ++dst) {
        *dst = 0U;
    }
    initialise_monitor_handles();
    exit(main());
}

void Fault_Handler(void)
{
    fputs("\nFAULT: exception on the target\n", stdout);
    fflush(stdout);
    _Exit(ODO_TARGET_FAULT_EXIT);
}
