/// odo-canvec: the firmware CAN codec (firmware/include/odo/odo_can.h) on stdin/stdout, one command
/// per line, so a script can cross-check thousands of vectors against another reading of
/// can/odometry.dbc (tests/python/test_can_dbc.py uses cantools) in one process.
///
/// Every value is a raw signal value (the integer on the wire, before DBC scaling). Each command
/// line gives exactly one output line (`list` gives a block ending in `end`); a bad line gives an
/// `error <kind>: <detail>` line and the batch goes on. The exit status is non-zero only for usage
/// errors (bad command-line arguments) or when output cannot be written.
#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo_cli.h"
#include "odo/odo_can.h"

#define LINE_MAX_CHARS     1024
#define MAX_SIGNALS        ODO_CAN_MAX_SIGNALS
#define MAX_TOKENS         (MAX_SIGNALS + 8)
#define CAN_ERR_FLAG_IN_ID 0x20000000UL

static const char usage_text[] =
    "usage: odo-canvec [--help | --version]\n"
    "\n"
    "Reads commands from stdin, one per line, and answers each on stdout with the firmware's own\n"
    "CAN codec (odo_can.h), so the codec can be checked against can/odometry.dbc in bulk.\n"
    "Values are raw signal values (integers on the wire, before DBC scaling); decimal, or hex\n"
    "with a 0x prefix.\n"
    "\n"
    "commands:\n"
    "  encode <MESSAGE> <Signal>=<value> ...   every signal of the message exactly once\n"
    "      -> <ID>#<DATA>                      candump style: 3 hex digits, DLC bytes of hex\n"
    "      e.g. encode POSE_XY_A X=-2147483648 Y=5  ->  180#0000008005000000\n"
    "  decode <ID>#<DATA>                      ID of 1-3 hex digits (standard) or 8 (extended;\n"
    "                                          bit 29 set: error frame, as candump prints it),\n"
    "                                          DATA up to 8 bytes of hex, or R for a remote frame\n"
    "      -> <MESSAGE> <Signal>=<value> ...   signals in DBC order\n"
    "  list                                    the codec's layout table:\n"
    "      -> message <NAME> <0xID> <DLC>      per message, then per signal\n"
    "         signal <MESSAGE> <Signal> <start> <length> signed|unsigned\n"
    "         end\n"
    "  blank lines and lines starting with '#' are ignored.\n"
    "\n"
    "errors: a bad line prints `error <kind>: <detail>` (kind: syntax, command, message, signal,\n"
    "range, unknown-id, dlc, flags) and the batch continues; exit status 0.\n"
    "exit status: 0 when stdin was processed, 1 if stdout failed, 2 for a usage error.\n";

/* ---- small parsing helpers (C99, no POSIX) ---- */

static int tokenize(char *line, char **tok, int max)
{
    int n = 0;
    char *p = line;
    while (*p != '\0') {
        while (*p != '\0' && isspace((unsigned char)*p)) {
            *p++ = '\0';
        }
        if (*p == '\0') {
            break;
        }
        if (n == max) {
            return -1;
        }
        tok[n++] = p;
        while (*p != '\0' && !isspace((unsigned char)*p)) {
            p++;
        }
    }
    return n;
}

/* Decimal with optional sign, or 0x-prefixed hex. No octal surprises, no trailing junk. */
static bool parse_int(const char *s, int64_t *out)
{
    const char *digits = s;
    bool neg = false;
    if (*digits == '-' || *digits == '+') {
        neg = (*digits == '-');
        digits++;
    }
    int base = 10;
    if (digits[0] == '0' && (digits[1] == 'x' || digits[1] == 'X')) {
        base = 16;
        digits += 2;
    }
    if (*digits == '\0' || !isxdigit((unsigned char)*digits)) {
        return false;
    }
    char *end = NULL;
    errno = 0;
    unsigned long long mag = strtoull(digits, &end, base);
    if (errno != 0 || *end != '\0' || mag > (1ULL << 40)) {
        return false; /* far beyond any 32-bit signal; keeps the arithmetic below exact */
    }
    *out = neg ? -(int64_t)mag : (int64_t)mag;
    return true;
}

static int hex_nibble(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

static void sig_range(const odo_can_signal_info_t *s, int64_t *lo, int64_t *hi)
{
    if (s->is_signed) {
        *lo = -((int64_t)1 << (s->bit_len - 1U));
        *hi = ((int64_t)1 << (s->bit_len - 1U)) - 1;
    } else {
        *lo = 0;
        *hi = ((int64_t)1 << s->bit_len) - 1;
    }
}

static const odo_can_msg_info_t *find_msg(const char *name, odo_can_msg_t *which)
{
    for (unsigned i = 1U; i <= ODO_CAN_MSG_COUNT; i++) {
        const odo_can_msg_info_t *info = odo_can_msg_info((odo_can_msg_t)i);
        if (info != NULL && strcmp(info->name, name) == 0) {
            *which = (odo_can_msg_t)i;
            return info;
        }
    }
    return NULL;
}

/* ---- commands ---- */

static const char *frame_kind(const odo_can_frame_t *f)
{
    if ((f->flags & ODO_CAN_FLAG_ERR) != 0U) {
        return "error";
    }
    return (f->flags & ODO_CAN_FLAG_RTR) != 0U ? "remote" : "extended";
}

static void cmd_encode(char **tok, int n)
{
    if (n < 2) {
        printf("error syntax: encode needs a message name, e.g. encode POSE_XY_A X=1 Y=2\n");
        return;
    }
    odo_can_msg_t m = ODO_CAN_MSG_UNKNOWN;
    const odo_can_msg_info_t *info = find_msg(tok[1], &m);
    if (info == NULL) {
        printf("error message: unknown message '%s' (see `list`)\n", tok[1]);
        return;
    }
    int64_t v[MAX_SIGNALS] = {0};
    bool seen[MAX_SIGNALS] = {false};
    for (int t = 2; t < n; t++) {
        char *eq = strchr(tok[t], '=');
        if (eq == NULL || eq == tok[t]) {
            printf("error syntax: '%s' is not <Signal>=<value>\n", tok[t]);
            return;
        }
        *eq = '\0';
        const char *name = tok[t];
        const char *val = eq + 1;
        unsigned k = 0U;
        while (k < info->n_signals && strcmp(info->signals[k].name, name) != 0) {
            k++;
        }
        if (k == info->n_signals) {
            printf("error signal: %s has no signal '%s'\n", info->name, name);
            return;
        }
        if (seen[k]) {
            printf("error signal: %s given twice\n", name);
            return;
        }
        if (!parse_int(val, &v[k])) {
            printf("error syntax: %s='%s' is not an integer (decimal or 0x hex)\n", name, val);
            return;
        }
        int64_t lo, hi;
        sig_range(&info->signals[k], &lo, &hi);
        if (v[k] < lo || v[k] > hi) {
            printf("error range: %s=%" PRId64 " outside the raw range [%" PRId64 ", %" PRId64 "]\n", name, v[k], lo,
                   hi);
            return;
        }
        seen[k] = true;
    }
    for (unsigned k = 0U; k < info->n_signals; k++) {
        if (!seen[k]) {
            printf("error signal: %s needs %s\n", info->name, info->signals[k].name);
            return;
        }
    }
    odo_can_frame_t f;
    (void)odo_can_pack_signals(m, v, &f);
    printf("%03" PRIX32 "#", f.id);
    for (unsigned i = 0U; i < f.dlc; i++) {
        printf("%02X", f.data[i]);
    }
    printf("\n");
}

static bool parse_frame(const char *s, odo_can_frame_t *f)
{
    memset(f, 0, sizeof *f);
    const char *hash = strchr(s, '#');
    if (hash == NULL) {
        return false;
    }
    size_t id_len = (size_t)(hash - s);
    if (id_len == 0U || (id_len > 3U && id_len != 8U)) {
        return false;
    }
    uint32_t id = 0U;
    for (size_t i = 0U; i < id_len; i++) {
        int d = hex_nibble(s[i]);
        if (d < 0) {
            return false;
        }
        id = (id << 4) | (uint32_t)d;
    }
    if (id_len == 8U) {
        if ((id & CAN_ERR_FLAG_IN_ID) != 0U) {
            /* candump prints error frames with Linux's CAN_ERR_FLAG in the 8-digit identifier */
            f->flags |= ODO_CAN_FLAG_ERR;
            id &= 0x1FFFFFFFUL;
        } else if (id > 0x1FFFFFFFUL) {
            return false;
        } else {
            f->flags |= ODO_CAN_FLAG_EXT;
        }
    } else if (id > 0x7FFU) {
        return false;
    }
    f->id = id;
    const char *p = hash + 1;
    if (*p == 'R' || *p == 'r') {
        f->flags |= ODO_CAN_FLAG_RTR;
        p++;
        if (*p == '\0') {
            return true;
        }
        /* candump writes R<dlc> for a remote frame with a length */
        int d = hex_nibble(*p);
        if (d < 0 || d > 8 || p[1] != '\0') {
            return false;
        }
        f->dlc = (uint8_t)d;
        return true;
    }
    uint8_t n = 0U;
    while (*p != '\0') {
        if (*p == '.') { /* cansend allows dots between bytes */
            p++;
            continue;
        }
        int hi = hex_nibble(p[0]);
        int lo = (hi < 0) ? -1 : hex_nibble(p[1]);
        if (hi < 0 || lo < 0 || n == 8U) {
            return false;
        }
        f->data[n++] = (uint8_t)((hi << 4) | lo);
        p += 2;
    }
    f->dlc = n;
    return true;
}

static void cmd_decode(char **tok, int n)
{
    if (n != 2) {
        printf("error syntax: decode takes one frame, e.g. decode 180#0000008005000000\n");
        return;
    }
    odo_can_frame_t f;
    if (!parse_frame(tok[1], &f)) {
        printf("error syntax: '%s' is not <ID>#<DATA> (1-3 or 8 hex digits of ID, up to 8 bytes "
               "of hex, or R)\n",
               tok[1]);
        return;
    }
    /* Pick the unpacker by identifier alone, then let it judge flags and length itself. */
    odo_can_frame_t plain = f;
    plain.flags = 0U;
    odo_can_msg_t m = odo_can_classify(&plain);
    if (m == ODO_CAN_MSG_UNKNOWN) {
        if (f.flags != 0U) {
            printf("error flags: %s frame 0x%" PRIX32 " is not a data frame of this protocol\n", frame_kind(&f), f.id);
        } else {
            printf("error unknown-id: 0x%03" PRIX32 " is not in can/odometry.dbc\n", f.id);
        }
        return;
    }
    const odo_can_msg_info_t *info = odo_can_msg_info(m);
    int64_t v[MAX_SIGNALS] = {0};
    odo_can_result_t r = odo_can_unpack_signals(m, &f, v);
    switch (r) {
    case ODO_CAN_OK:
        printf("%s", info->name);
        for (unsigned k = 0U; k < info->n_signals; k++) {
            printf(" %s=%" PRId64, info->signals[k].name, v[k]);
        }
        printf("\n");
        break;
    case ODO_CAN_ERR_DLC:
        printf("error dlc: %s needs DLC %u, frame has %u\n", info->name, (unsigned)info->dlc, (unsigned)f.dlc);
        break;
    case ODO_CAN_ERR_FLAGS:
        printf("error flags: %s frame 0x%" PRIX32 " is not a data frame of this protocol\n", frame_kind(&f), f.id);
        break;
    case ODO_CAN_ERR_ID:
    default: printf("error unknown-id: codec rejected 0x%03" PRIX32 " as %s\n", f.id, info->name); break;
    }
}

static void cmd_list(void)
{
    for (unsigned i = 1U; i <= ODO_CAN_MSG_COUNT; i++) {
        const odo_can_msg_info_t *info = odo_can_msg_info((odo_can_msg_t)i);
        printf("message %s 0x%03" PRIX32 " %u\n", info->name, info->id, (unsigned)info->dlc);
        for (unsigned k = 0U; k < info->n_signals; k++) {
            const odo_can_signal_info_t *s = &info->signals[k];
            printf("signal %s %s %u %u %s\n", info->name, s->name, (unsigned)s->start_bit, (unsigned)s->bit_len,
                   s->is_signed ? "signed" : "unsigned");
        }
    }
    printf("end\n");
}

static void run_line(char *line)
{
    char *tok[MAX_TOKENS];
    int n = tokenize(line, tok, MAX_TOKENS);
    if (n < 0) {
        printf("error syntax: more than %d words on one line\n", MAX_TOKENS);
        return;
    }
    if (n == 0 || tok[0][0] == '#') {
        return;
    }
    if (strcmp(tok[0], "encode") == 0) {
        cmd_encode(tok, n);
    } else if (strcmp(tok[0], "decode") == 0) {
        cmd_decode(tok, n);
    } else if (strcmp(tok[0], "list") == 0 && n == 1) {
        cmd_list();
    } else {
        printf("error command: '%s' (expected encode, decode or list; see --help)\n", tok[0]);
    }
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(usage_text, stdout);
            return 0;
        }
        if (strcmp(argv[i], "--version") == 0) {
            odo_cli_print_version("odo-canvec");
            return 0;
        }
        fprintf(stderr, "odo-canvec: unexpected argument '%s'\n\n%s", argv[i], usage_text);
        return 2;
    }
    /* Line buffered so the tool also works as an interactive co-process. */
    setvbuf(stdout, NULL, _IOLBF, 0);

    char line[LINE_MAX_CHARS + 2];
    while (fgets(line, sizeof line, stdin) != NULL) {
        size_t len = strlen(line);
        if (len > 0U && line[len - 1U] == '\n') {
            run_line(line);
        } else if (feof(stdin)) {
            run_line(line); /* last line without a newline */
        } else {
            int c;
            while ((c = getchar()) != EOF && c != '\n') {
            }
            printf("error syntax: line longer than %d characters\n", LINE_MAX_CHARS);
        }
    }
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "odo-canvec: cannot write output\n");
        return 1;
    }
    return 0;
}
