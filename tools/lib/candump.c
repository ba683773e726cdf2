#include "candump.h"

#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int odo_log_start_parse(const char *text, uint64_t *start_us)
{
    if (text == NULL) {
        return -1;
    }
    if (strcmp(text, "now") == 0) {
        struct timespec ts;
        if (clock_gettime(CLOCK_REALTIME, &ts) != 0 || ts.tv_sec < 0) {
            return -1;
        }
        *start_us = (uint64_t)ts.tv_sec * 1000000U;
        return 0;
    }
    if (text[0] < '0' || text[0] > '9') { /* strtoull would take a sign or spaces */
        return -1;
    }
    errno = 0;
    char *end = NULL;
    const unsigned long long s = strtoull(text, &end, 10);
    if (errno != 0 || *end != '\0' || s > ODO_LOG_START_MAX_S) {
        return -1;
    }
    *start_us = (uint64_t)s * 1000000U;
    return 0;
}

int odo_log_start_default(uint64_t *start_us)
{
    const char *env = getenv("SOURCE_DATE_EPOCH");
    return odo_log_start_parse(env != NULL && env[0] != '\0' ? env : "now", start_us);
}

int odo_candump_write(FILE *f, uint64_t t_us, const char *iface, const odo_can_frame_t *frame)
{
    const int ext = (frame->flags & ODO_CAN_FLAG_EXT) != 0U;
    fprintf(f, "(%" PRIu64 ".%06" PRIu64 ") %s %0*" PRIX32 "#", t_us / 1000000U, t_us % 1000000U, iface, ext ? 8 : 3,
            frame->id);
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
