/// bxCAN (RM0090 chapter 32, "Controller area network (bxCAN)"): classic CAN at a configurable
/// bit rate, acceptance filters in identifier-list mode holding exactly the identifiers the board
/// consumes, polled transmit mailboxes and receive FIFO 0.
///
/// Bit timing (32.7.7): one bit = (1 + TS1 + TS2) time quanta of (BRP + 1) / f_APB1. The driver
/// looks for 8..25 quanta per bit that divide f_APB1 / bit rate exactly, preferring a sample point
/// closest to 87.5 % (CiA 301's recommendation), and refuses a rate it cannot hit exactly.
/// Filters (32.7.4): 16-bit scale, list mode, four standard data-frame identifiers per bank
/// (STID << 5, RTR = IDE = 0), all to FIFO 0; a frame matching none is dropped in hardware.
/// Automatic bus-off recovery (ABOM) and transmit order by request (TXFP) are on.
///
/// Every wait is bounded by `polls` register reads. Nothing here allocates or blocks.
#ifndef ODO_BXCAN_H
#define ODO_BXCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_types.h"
#include "stm32f4_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Most identifiers the filters hold: 4 per bank in list mode, ODO_CAN_FILTER_BANKS banks.
#define ODO_BXCAN_MAX_IDS (4U * ODO_CAN_FILTER_BANKS)

typedef enum {
    ODO_BXCAN_OK = 0,
    ODO_BXCAN_ERR_BITRATE,    ///< no exact timing for this bit rate at this APB1 clock
    ODO_BXCAN_ERR_IDS,        ///< no identifiers, too many, or one above 0x7FF
    ODO_BXCAN_ERR_INIT_MODE,  ///< the controller did not enter initialisation mode
    ODO_BXCAN_ERR_NORMAL_MODE ///< ... or did not leave it (no 11 recessive bits: bus stuck)
} odo_bxcan_status_t;

/// BTR value for bitrate at pclk1_hz (SJW 1 quantum). Returns false iff no exact timing exists.
/// *sample_permille (if not NULL) receives the sample point in 0.1 %.
bool odo_bxcan_timing(uint32_t pclk1_hz, uint32_t bitrate, uint32_t *btr, uint32_t *sample_permille);

/// Initialise: init mode, timing, filters for ids[0..n_ids), normal mode.
odo_bxcan_status_t odo_bxcan_init(odo_stm32_can_t *can, uint32_t pclk1_hz, uint32_t bitrate, const uint32_t *ids,
                                  uint8_t n_ids, uint32_t polls);

/// Queue a frame in a free mailbox. Returns false iff all three are busy or the frame is not a
/// classic data or remote frame (dlc > 8).
bool odo_bxcan_send(odo_stm32_can_t *can, const odo_can_frame_t *f);

/// Take the oldest frame of FIFO 0. Returns false iff the FIFO is empty. *overrun is set (never
/// cleared) when the FIFO had overflowed, i.e. frames were lost before this one. f->dlc is capped
/// at 8 (classic CAN: a DLC of 9..15 carries 8 bytes); *raw_dlc receives the DLC field as sent, so
/// the caller can reject such a frame as having the wrong length.
bool odo_bxcan_recv(odo_stm32_can_t *can, odo_can_frame_t *f, uint8_t *raw_dlc, bool *overrun);

/// Bus-off state (ESR.BOFF).
bool odo_bxcan_bus_off(odo_stm32_can_t *can);

#ifdef __cplusplus
}
#endif
#endif
