#include "odo_candump.h"

#include "hal_log.h"

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
    char line[CANDUMP_LINE_MAX];
    const size_t n = candump_format_line(line, t_us, iface, frame);
    return fwrite(line, 1, n, f) == n && !ferror(f) ? 0 : -1;
}
