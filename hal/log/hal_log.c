/// hal_log: candump -l reader (see hal_log.h).
#include "hal_log.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

int hal_log_open(hal_log_t *l, const char *path)
{
    memset(l, 0, sizeof *l);
    (void)snprintf(l->path, sizeof l->path, "%s", strcmp(path, "-") == 0 ? "<stdin>" : path);
    if (strcmp(path, "-") == 0) {
        l->f = stdin;
    } else {
        l->f = fopen(path, "rb");
        l->own_f = true;
    }
    if (l->f == NULL) {
        (void)snprintf(l->err, sizeof l->err, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    l->buf = malloc(HAL_LOG_CHUNK);
    if (l->buf == NULL) {
        (void)snprintf(l->err, sizeof l->err, "%s: out of memory", path);
        hal_log_close(l);
        return -1;
    }
    return 0;
}

void hal_log_close(hal_log_t *l)
{
    if (l->own_f && l->f != NULL) {
        (void)fclose(l->f);
    }
    l->f = NULL;
    free(l->buf);
    l->buf = NULL;
}

/// Make sure buf[start, end) holds a whole line or the rest of the file. Returns the line
/// length (newline included, if any), 0 at end of file, or -1 on error.
static long next_line(hal_log_t *l)
{
    for (;;) {
        const char *s = l->buf + l->start;
        const char *nl = memchr(s, '\n', l->end - l->start);
        if (nl != NULL) {
            return (long)(nl - s + 1);
        }
        if (l->eof) {
            return (long)(l->end - l->start);
        }
        if (l->start > 0U) {
            memmove(l->buf, l->buf + l->start, l->end - l->start);
            l->end -= l->start;
            l->start = 0U;
        }
        if (l->end == HAL_LOG_CHUNK) {
            (void)snprintf(l->err, sizeof l->err, "%s:%llu: line longer than %u bytes", l->path,
                           (unsigned long long)l->line_no + 1U, HAL_LOG_CHUNK);
            return -1;
        }
        const size_t got = fread(l->buf + l->end, 1U, HAL_LOG_CHUNK - l->end, l->f);
        l->end += got;
        if (got == 0U) {
            if (ferror(l->f)) {
                (void)snprintf(l->err, sizeof l->err, "%s:%llu: read error: %s", l->path,
                               (unsigned long long)l->line_no + 1U, strerror(errno));
                return -1;
            }
            l->eof = true;
        }
    }
}

hal_log_status_t hal_log_next(hal_log_t *l, candump_line_t *out)
{
    if (l->buf == NULL) {
        (void)snprintf(l->err, sizeof l->err, "%s: reader not open", l->path);
        return HAL_LOG_ERROR;
    }
    for (;;) {
        const long n = next_line(l);
        if (n < 0) {
            return HAL_LOG_ERROR;
        }
        if (n == 0) {
            return HAL_LOG_EOF;
        }
        const char *s = l->buf + l->start;
        l->start += (size_t)n;
        l->line_no++;
        l->stats.lines++;
        const char *why = "";
        const candump_result_t r = candump_parse_line(s, (size_t)n, out, &why);
        if (r == CANDUMP_BLANK) {
            l->stats.blank++;
            continue;
        }
        if (r == CANDUMP_FD) {
            l->stats.fd_skipped++;
            continue;
        }
        if (r != CANDUMP_OK) {
            (void)snprintf(l->err, sizeof l->err, "%s:%llu: %s", l->path, (unsigned long long)l->line_no, why);
            return HAL_LOG_ERROR;
        }
        l->stats.frames++;
        l->stats.error_frames += (out->frame.flags & ODO_CAN_FLAG_ERR) != 0U;
        l->stats.rtr_frames += (out->frame.flags & ODO_CAN_FLAG_RTR) != 0U;
        l->stats.ext_frames += (out->frame.flags & ODO_CAN_FLAG_EXT) != 0U;
        return HAL_LOG_FRAME;
    }
}

static const char HEX[] = "0123456789ABCDEF";

size_t candump_format_line(char *buf, uint64_t t_us, const char *iface, const odo_can_frame_t *f)
{
    char *p = buf;
    *p++ = '(';
    char digits[24];
    int nd = 0;
    uint64_t sec = t_us / 1000000U;
    do {
        digits[nd++] = (char)('0' + (int)(sec % 10U));
        sec /= 10U;
    } while (sec != 0U);
    while (nd > 0) {
        *p++ = digits[--nd];
    }
    *p++ = '.';
    uint32_t us = (uint32_t)(t_us % 1000000U);
    for (int k = 5; k >= 0; --k) {
        p[k] = (char)('0' + (int)(us % 10U));
        us /= 10U;
    }
    p += 6;
    *p++ = ')';
    *p++ = ' ';
    for (size_t k = 0U; k < CANDUMP_IFACE_MAX && iface[k] != '\0'; ++k) {
        *p++ = iface[k];
    }
    *p++ = ' ';
    uint32_t id = f->id;
    int width = 3;
    if ((f->flags & ODO_CAN_FLAG_ERR) != 0U) {
        id = (f->id & 0x1FFFFFFFUL) | 0x20000000UL;
        width = 8;
    } else if ((f->flags & ODO_CAN_FLAG_EXT) != 0U) {
        width = 8;
    }
    for (int k = width - 1; k >= 0; --k) {
        *p++ = HEX[(id >> (4 * k)) & 0xFU];
    }
    *p++ = '#';
    if ((f->flags & ODO_CAN_FLAG_RTR) != 0U) {
        *p++ = 'R'; /* and the requested length, as can-utils writes it ("#R3"); found by fuzz_candump */
        if (f->dlc > 0U && f->dlc <= 8U) {
            *p++ = (char)('0' + f->dlc);
        }
    } else {
        for (uint8_t k = 0U; k < f->dlc && k < 8U; ++k) {
            *p++ = HEX[f->data[k] >> 4];
            *p++ = HEX[f->data[k] & 0xFU];
        }
    }
    *p++ = '\n';
    return (size_t)(p - buf);
}
