#include "candump.h"

#include <inttypes.h>

int odo_candump_write(FILE *f, uint64_t t_us, const char *iface, const odo_can_frame_t *frame)
{
    const int ext = (frame->flags & ODO_CAN_FLAG_EXT) != 0U;
    fprintf(f, "(%" PRIu64 ".%06" PRIu64 ") %s %0*" PRIX32 "#", t_us / 1000000U, t_us % 1000000U, iface,
            ext ? 8 : 3, frame->id);
    if ((frame->flags & ODO_CAN_FLAG_RTR) != 0U) {
        fputc('R', f); /* and the requested length, as can-utils writes it ("#R3") */
        if (frame->dlc > 0U && frame->dlc <= 8U) {
            fputc('0' + frame->dlc, f);
        }
    } else {
        for (uint8_t i = 0U; i < frame->dlc && i < 8U; ++i) {
            fprintf(f, "%02X", frame->data[i]);
        }
    }
    fputc('\n', f);
    return ferror(f) ? -1 : 0;
}
