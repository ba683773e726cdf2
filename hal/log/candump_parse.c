/// candump -l line parser (see candump_parse.h for the grammar).
#include "candump_parse.h"

#include <string.h>

#define CAN_ERR_FLAG_BIT 0x20000000UL /* linux/can.h CAN_ERR_FLAG, as candump prints it */

/// Hex digit value by character, -1 for anything else (one load instead of three range checks:
/// the parser is most of odo-replay's time besides the firmware step).
static const int8_t HEXV[256] = {
    ['0'] = 0,  ['1'] = 1,  ['2'] = 2,  ['3'] = 3,  ['4'] = 4,  ['5'] = 5,  ['6'] = 6,  ['7'] = 7,
    ['8'] = 8,  ['9'] = 9,  ['A'] = 10, ['B'] = 11, ['C'] = 12, ['D'] = 13, ['E'] = 14, ['F'] = 15,
    ['a'] = 10, ['b'] = 11, ['c'] = 12, ['d'] = 13, ['e'] = 14, ['f'] = 15,
};
static const uint8_t IS_HEX[256] = {
    ['0'] = 1, ['1'] = 1, ['2'] = 1, ['3'] = 1, ['4'] = 1, ['5'] = 1, ['6'] = 1, ['7'] = 1,
    ['8'] = 1, ['9'] = 1, ['A'] = 1, ['B'] = 1, ['C'] = 1, ['D'] = 1, ['E'] = 1, ['F'] = 1,
    ['a'] = 1, ['b'] = 1, ['c'] = 1, ['d'] = 1, ['e'] = 1, ['f'] = 1,
};

static inline int hexval(char c)
{
    const unsigned char u = (unsigned char)c;
    return IS_HEX[u] ? HEXV[u] : -1;
}

static inline int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

#define FAIL(msg)           \
    do {                    \
        *why = (msg);       \
        return CANDUMP_ERR; \
    } while (0)

candump_result_t candump_parse_line(const char *line, size_t len, candump_line_t *out, const char **why)
{
    /* Drop the line end ("\n", "\r\n"); a line of blanks only is BLANK. */
    while (len > 0U && (line[len - 1U] == '\n' || line[len - 1U] == '\r')) {
        len--;
    }
    size_t i = 0U;
    while (i < len && is_blank(line[i])) {
        i++;
    }
    if (i == len) {
        return CANDUMP_BLANK;
    }
    if (i != 0U) {
        FAIL("leading whitespace before the '(' of the timestamp");
    }
    const char *p = line, *end = line + len;

    /* "(" seconds "." fraction ")" */
    if (*p != '(') {
        FAIL("expected '(' starting the timestamp (sec.usec)");
    }
    p++;
    uint64_t sec = 0U;
    unsigned nd = 0U;
    while (p < end && *p >= '0' && *p <= '9') {
        if (++nd > 19U) { /* 19 digits cannot overflow 64 bits; 10^19 s is far beyond any log */
            FAIL("timestamp seconds out of range");
        }
        sec = sec * 10U + (uint64_t)(*p - '0');
        p++;
    }
    if (nd == 0U || p >= end || *p != '.') {
        FAIL("timestamp must be (seconds.fraction), e.g. (1700000000.123456)");
    }
    p++;
    uint64_t usec = 0U;
    nd = 0U;
    while (p < end && *p >= '0' && *p <= '9') {
        if (nd < 6U) {
            usec = usec * 10U + (uint64_t)(*p - '0');
        }
        nd++;
        p++;
    }
    if (nd == 0U || nd > 9U) {
        FAIL("timestamp fraction must have 1 to 9 digits");
    }
    for (unsigned k = nd; k < 6U; ++k) {
        usec *= 10U;
    }
    if (p >= end || *p != ')') {
        FAIL("expected ')' closing the timestamp");
    }
    p++;
    if (sec > (UINT64_MAX - usec) / 1000000U) {
        FAIL("timestamp seconds out of range (microseconds overflow 64 bits)");
    }
    out->t_us = sec * 1000000U + usec;

    /* " " iface " " */
    if (p >= end || *p != ' ') {
        FAIL("expected one space after the timestamp");
    }
    p++;
    size_t n = 0U;
    while (p < end && *p != ' ') {
        /* Printable ASCII only: a NUL or control byte would cut or garble the name the outputs
         * carry (found by fuzz/fuzz_candump: "(1.0) \0\a0 178#..." read back as an empty name). */
        if (n >= CANDUMP_IFACE_MAX || is_blank(*p) || *p == '(' || *p == ')' || (unsigned char)*p < 0x21U ||
            (unsigned char)*p > 0x7EU) {
            FAIL("interface name must be 1 to 15 printable characters, without blanks or parentheses");
        }
        out->iface[n++] = *p++;
    }
    if (n == 0U) {
        FAIL("missing interface name");
    }
    out->iface[n] = '\0';
    if (p >= end || *p != ' ') {
        FAIL("expected one space between the interface and the frame");
    }
    p++;

    /* identifier: 3 or 8 hex digits, then '#' */
    const char *id0 = p;
    uint32_t id = 0U;
    while (p < end && *p != '#') {
        const int v = hexval(*p);
        if (v < 0) {
            FAIL(is_blank(*p) ? "missing '#' between identifier and data"
                              : "identifier must be hex digits followed by '#'");
        }
        if (p - id0 >= 8) {
            FAIL("identifier must have 3 (standard) or 8 (extended) hex digits");
        }
        id = (id << 4) | (uint32_t)v;
        p++;
    }
    const ptrdiff_t id_len = p - id0;
    if (p >= end) {
        FAIL("missing '#' between identifier and data");
    }
    memset(&out->frame, 0, sizeof out->frame);
    if (id_len == 3) {
        if (id > 0x7FFU) {
            FAIL("standard identifier above 0x7FF");
        }
        out->frame.id = id;
    } else if (id_len == 8) {
        if ((id & 0xC0000000UL) != 0U) {
            FAIL("identifier bits 30..31 set (not a classic CAN identifier)");
        }
        if ((id & CAN_ERR_FLAG_BIT) != 0U) {
            out->frame.id = id & 0x1FFFFFFFUL;
            out->frame.flags = ODO_CAN_FLAG_ERR;
        } else {
            out->frame.id = id;
            out->frame.flags = ODO_CAN_FLAG_EXT;
        }
    } else {
        FAIL("identifier must have 3 (standard) or 8 (extended) hex digits");
    }
    p++; /* '#' */

    if (p < end && *p == '#') {
        /* CAN FD: "##" flags-digit data (0..64 bytes). Well-formed ones are another node's traffic
         * on a mixed bus: reported as CANDUMP_FD so a reader counts and skips them. */
        p++;
        if (p >= end || hexval(*p) < 0) {
            FAIL("CAN FD frame ('##') without its flags digit");
        }
        p++;
        size_t fd_digits = 0;
        while (p < end && *p != ' ') {
            if (hexval(*p) < 0) {
                FAIL("CAN FD frame: data must be hex digits");
            }
            fd_digits++;
            p++;
        }
        if (fd_digits % 2U != 0U || fd_digits > 128U) {
            FAIL("CAN FD frame: odd number of hex digits or more than 64 data bytes");
        }
        if (end - p == 2 && p[0] == ' ' && (p[1] == 'R' || p[1] == 'T')) {
            p += 2;
        }
        if (p != end) {
            FAIL("unexpected text after the CAN FD frame");
        }
        return CANDUMP_FD;
    }
    if (p < end && (*p == 'R' || *p == 'r')) {
        if ((out->frame.flags & ODO_CAN_FLAG_ERR) != 0U) {
            FAIL("an error frame cannot be a remote request");
        }
        out->frame.flags |= ODO_CAN_FLAG_RTR;
        p++;
        if (p < end && *p >= '0' && *p <= '9') {
            if (*p > '8') {
                FAIL("remote request DLC above 8");
            }
            out->frame.dlc = (uint8_t)(*p - '0');
            p++;
        }
    } else {
        uint8_t nb = 0U;
        for (;;) {
            if (p + 1 < end && IS_HEX[(unsigned char)p[0]] && IS_HEX[(unsigned char)p[1]]) {
                if (nb >= 8U) {
                    FAIL("more than 8 data bytes (CAN FD?): only classic CAN is supported");
                }
                out->frame.data[nb++] = (uint8_t)((HEXV[(unsigned char)p[0]] << 4) | HEXV[(unsigned char)p[1]]);
                p += 2;
            } else if (p < end && *p == '.') {
                p++; /* canplayer's optional byte separator */
            } else {
                break;
            }
        }
        if (p < end && !is_blank(*p)) {
            FAIL(*p == '_'         ? "CAN XL frame: only classic CAN is supported"
                 : hexval(*p) >= 0 ? "data must be hex digit pairs (odd number of digits)"
                                   : "data must be hex digit pairs");
        }
        out->frame.dlc = nb;
    }

    /* optional " R" / " T" (candump -x: received / transmitted) */
    out->direction = 0;
    if (p < end) {
        if (end - p == 2 && p[0] == ' ' && (p[1] == 'R' || p[1] == 'T')) {
            out->direction = p[1];
        } else {
            FAIL("unexpected text after the frame (only \" R\" or \" T\" may follow)");
        }
    }
    return CANDUMP_OK;
}
