/// Cortex-M4 board port (generic STM32F4-class part): what the startup code, main.c and the
/// generated parameter block share. Built only by the cm4 preset; see hal/cortexm/README.md.
///
/// This is the imperative shell's outermost layer: it owns reset, the memory map (odo_cm4.ld) and
/// the static application state, and calls the portable core only through odo/odo_app.h. GNU C
/// attributes (section, used, weak, alias) are allowed here and nowhere in firmware/.
#ifndef ODO_BOARD_H
#define ODO_BOARD_H

#include <stdint.h>

#include "odo/odo_params.h"
#include "odo_board_port.h"
#include "odo_selftest.h"

#ifdef __cplusplus
extern "C" {
#endif

/// The parameter block in flash: section .odo_params, fixed at 0x08004000 (flash sector 1) by
/// odo_cm4.ld. Defined in the build-generated odo_param_block.c (gen_param_block.c writes it from
/// odo_params_defaults() with a valid magic, version, length and CRC-32); `odo-calib write`
/// replaces those ODO_PARAMS_SIZE (256) bytes in the .bin/.hex or on the part. Defined in its own translation unit
/// so the compiler can never fold its contents into main(): the firmware reads what is in flash.
extern const uint8_t odo_param_block[ODO_PARAMS_SIZE];

/// The board's peripherals and pins (odo_board_config.c).
extern const odo_board_config_t odo_board_config;

/// What start-up found and the loop's counters (odo_board_port.h), refreshed every tick.
extern volatile odo_board_status_t odo_board_status;

/// Result of the boot self-test (odo_selftest.h), kept in RAM for a debugger and for
/// tests/target, which reads it under qemu and compares it with the host's.
extern volatile odo_board_selftest_t odo_board_selftest;

/// Exception entry points named as in CMSIS, so a later CMSIS/HAL backend can override the weak
/// defaults by defining a function of the same name.
void Reset_Handler(void);
void Default_Handler(void);
void NMI_Handler(void);
void HardFault_Handler(void);
void MemManage_Handler(void);
void BusFault_Handler(void);
void UsageFault_Handler(void);
void SVC_Handler(void);
void DebugMon_Handler(void);
void PendSV_Handler(void);
void SysTick_Handler(void);

int main(void);

#ifdef __cplusplus
}
#endif
#endif
