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

#ifdef __cplusplus
extern "C" {
#endif

/// The parameter block in flash: section .odo_params, fixed at 0x08004000 (flash sector 1) by
/// odo_cm4.ld. Defined in the build-generated odo_param_block.c (gen_param_block.c writes it from
/// odo_params_defaults() with a valid magic, version, length and CRC-32); `odo-calib write`
/// replaces those ODO_PARAMS_SIZE (256) bytes in the .bin/.hex or on the part. Defined in its own translation unit
/// so the compiler can never fold its contents into main(): the firmware reads what is in flash.
extern const uint8_t odo_param_block[ODO_PARAMS_SIZE];

/// Result of the boot self-test in main(), kept in RAM for a debugger or a later qemu test to read
/// (symbol odo_board_selftest). `done` becomes ODO_BOARD_SELFTEST_DONE once all fields are final.
typedef struct {
    uint32_t params_status; ///< odo_params_status_t of odo_app_init on odo_param_block (0: OK)
    uint32_t steps;         ///< synthetic ticks run through odo_app_step
    uint32_t faults_or;     ///< OR of the ODO_FAULT_* bits every step raised
    uint32_t frames;        ///< output frames produced in total
    int64_t  x_mm_q32;      ///< final pose of truck A (odo_pose_t units)
    int64_t  y_mm_q32;
    uint32_t heading_bam;   ///< top 32 bits of the final heading_q64 of truck A
    uint32_t done;          ///< ODO_BOARD_SELFTEST_DONE when the above are complete
} odo_board_selftest_t;

#define ODO_BOARD_SELFTEST_DONE 0x600DF00DUL

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
