/// bxCAN driver (odo_bxcan.h).
#include "odo_bxcan.h"

#include <string.h>

#include "odo_reg.h"

bool odo_bxcan_timing(uint32_t pclk1_hz, uint32_t bitrate, uint32_t *btr, uint32_t *sample_permille)
{
    if (bitrate == 0U || pclk1_hz % bitrate != 0U) {
        return false;
    }
    const uint32_t q_per_bit_x_brp = pclk1_hz / bitrate;
    bool found = false;
    uint32_t best_err = UINT32_MAX, best_btr = 0U, best_sp = 0U;
    for (uint32_t nq = 8U; nq <= 25U; ++nq) {
        if (q_per_bit_x_brp % nq != 0U || q_per_bit_x_brp / nq > 1024U) {
            continue;
        }
        const uint32_t brp = q_per_bit_x_brp / nq;
        /* TS2 = round(nq / 8) (87.5 %), within 1..8; TS1 = nq - 1 - TS2, within 1..16. */
        uint32_t ts2 = (nq + 4U) / 8U;
        ts2 = ts2 < 1U ? 1U : (ts2 > 8U ? 8U : ts2);
        const uint32_t ts1 = nq - 1U - ts2;
        if (ts1 < 1U || ts1 > 16U) {
            continue;
        }
        const uint32_t sp = (1000U * (1U + ts1)) / nq;
        const uint32_t err = sp > 875U ? sp - 875U : 875U - sp;
        if (err < best_err) {
            found = true;
            best_err = err;
            best_sp = sp;
            best_btr = (brp - 1U) | ((ts1 - 1U) << 16) | ((ts2 - 1U) << 20); /* SJW = 1 tq */
        }
    }
    if (found) {
        *btr = best_btr;
        if (sample_permille != NULL) {
            *sample_permille = best_sp;
        }
    }
    return found;
}

odo_bxcan_status_t odo_bxcan_init(odo_stm32_can_t *can, uint32_t pclk1_hz, uint32_t bitrate, const uint32_t *ids,
                                  uint8_t n_ids, uint32_t polls)
{
    uint32_t btr = 0U;
    if (!odo_bxcan_timing(pclk1_hz, bitrate, &btr, NULL)) {
        return ODO_BXCAN_ERR_BITRATE;
    }
    if (n_ids == 0U || n_ids > ODO_BXCAN_MAX_IDS) {
        return ODO_BXCAN_ERR_IDS;
    }
    for (uint8_t i = 0U; i < n_ids; ++i) {
        if (ids[i] > 0x7FFU) {
            return ODO_BXCAN_ERR_IDS;
        }
    }
    /* Leave sleep, enter initialisation (32.4.1). */
    odo_reg_write(&can->MCR, ODO_CAN_MCR_INRQ);
    if (!odo_reg_wait(&can->MSR, ODO_CAN_MSR_INAK | ODO_CAN_MSR_SLAK, ODO_CAN_MSR_INAK, polls)) {
        return ODO_BXCAN_ERR_INIT_MODE;
    }
    odo_reg_write(&can->MCR, ODO_CAN_MCR_INRQ | ODO_CAN_MCR_ABOM | ODO_CAN_MCR_TXFP);
    odo_reg_write(&can->BTR, btr);

    /* Filters: list mode, 16-bit scale, FIFO 0; unused slots repeat the last identifier. */
    odo_reg_modify(&can->FMR, 0U, ODO_CAN_FMR_FINIT);
    const uint8_t banks = (uint8_t)((n_ids + 3U) / 4U);
    uint32_t bank_mask = 0U;
    for (uint8_t b = 0U; b < banks; ++b) {
        uint32_t slot[4];
        for (uint8_t k = 0U; k < 4U; ++k) {
            const uint8_t i = (uint8_t)(4U * b + k);
            slot[k] = (ids[i < n_ids ? i : n_ids - 1U] & 0x7FFU) << 5;
        }
        bank_mask |= (uint32_t)1U << b;
        odo_reg_modify(&can->FA1R, (uint32_t)1U << b, 0U); /* a bank is written only while inactive */
        odo_reg_write(&can->filter[b].FR1, slot[0] | (slot[1] << 16));
        odo_reg_write(&can->filter[b].FR2, slot[2] | (slot[3] << 16));
    }
    odo_reg_modify(&can->FM1R, 0U, bank_mask);
    odo_reg_modify(&can->FS1R, bank_mask, 0U);
    odo_reg_modify(&can->FFA1R, bank_mask, 0U);
    odo_reg_modify(&can->FA1R, (1U << ODO_CAN_FILTER_BANKS) - 1U, bank_mask);
    odo_reg_modify(&can->FMR, ODO_CAN_FMR_FINIT, 0U);

    odo_reg_modify(&can->MCR, ODO_CAN_MCR_INRQ, 0U);
    if (!odo_reg_wait(&can->MSR, ODO_CAN_MSR_INAK, 0U, polls)) {
        return ODO_BXCAN_ERR_NORMAL_MODE;
    }
    return ODO_BXCAN_OK;
}

bool odo_bxcan_send(odo_stm32_can_t *can, const odo_can_frame_t *f)
{
    if (f->dlc > 8U || (f->flags & ODO_CAN_FLAG_ERR) != 0U) {
        return false;
    }
    const uint32_t tsr = odo_reg_read(&can->TSR);
    for (uint32_t m = 0U; m < 3U; ++m) {
        if ((tsr & ODO_CAN_TSR_TME(m)) == 0U) {
            continue;
        }
        odo_stm32_can_tx_t *mb = &can->tx[m];
        const bool ext = (f->flags & ODO_CAN_FLAG_EXT) != 0U;
        uint32_t tir = ext ? ((f->id & 0x1FFFFFFFU) << 3) | ODO_CAN_XIR_IDE : (f->id & 0x7FFU) << 21;
        if ((f->flags & ODO_CAN_FLAG_RTR) != 0U) {
            tir |= ODO_CAN_XIR_RTR;
        }
        uint32_t lo = 0U, hi = 0U;
        for (uint32_t i = 0U; i < 4U; ++i) {
            lo |= (uint32_t)f->data[i] << (8U * i);
            hi |= (uint32_t)f->data[4U + i] << (8U * i);
        }
        odo_reg_write(&mb->TDTR, f->dlc);
        odo_reg_write(&mb->TDLR, lo);
        odo_reg_write(&mb->TDHR, hi);
        odo_reg_write(&mb->TIR, tir | ODO_CAN_TIR_TXRQ);
        return true;
    }
    return false;
}

bool odo_bxcan_recv(odo_stm32_can_t *can, odo_can_frame_t *f, uint8_t *raw_dlc, bool *overrun)
{
    const uint32_t rf0r = odo_reg_read(&can->RF0R);
    if ((rf0r & ODO_CAN_RF0R_FOVR0) != 0U) {
        *overrun = true;
        odo_reg_write(&can->RF0R, ODO_CAN_RF0R_FOVR0); /* rc_w1 */
    }
    if ((rf0r & ODO_CAN_RF0R_FMP0_MASK) == 0U) {
        return false;
    }
    const odo_stm32_can_rx_t *mb = &can->rx[0];
    const uint32_t rir = odo_reg_read(&mb->RIR);
    const uint32_t rdtr = odo_reg_read(&mb->RDTR);
    const uint32_t lo = odo_reg_read(&mb->RDLR);
    const uint32_t hi = odo_reg_read(&mb->RDHR);
    odo_reg_write(&can->RF0R, ODO_CAN_RF0R_RFOM0); /* release the FIFO slot */
    memset(f, 0, sizeof *f);
    if ((rir & ODO_CAN_XIR_IDE) != 0U) {
        f->flags |= ODO_CAN_FLAG_EXT;
        f->id = (rir >> 3) & 0x1FFFFFFFU;
    } else {
        f->id = (rir >> 21) & 0x7FFU;
    }
    if ((rir & ODO_CAN_XIR_RTR) != 0U) {
        f->flags |= ODO_CAN_FLAG_RTR;
    }
    const uint32_t dlc = rdtr & 0xFU;
    *raw_dlc = (uint8_t)dlc;
    f->dlc = (uint8_t)(dlc > 8U ? 8U : dlc); /* DLC 9..15 mean 8 bytes in classic CAN */
    const uint8_t n = (f->flags & ODO_CAN_FLAG_RTR) != 0U ? 0U : f->dlc;
    for (uint8_t i = 0U; i < n; ++i) {
        f->data[i] = (uint8_t)((i < 4U ? lo >> (8U * i) : hi >> (8U * (i - 4U))) & 0xFFU);
    }
    return true;
}

bool odo_bxcan_bus_off(odo_stm32_can_t *can) { return (odo_reg_read(&can->ESR) & ODO_CAN_ESR_BOFF) != 0U; }
