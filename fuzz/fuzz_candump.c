/// libFuzzer harness: the candump -l line parser (hal/log/candump_parse.h). Any bytes: never
/// reads past the line, never crashes, and every frame it accepts formats (hal/log/hal_log.h)
/// to a line that parses back to the same frame, time and interface.
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "candump_parse.h"
#include "hal_log.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* An exact-size heap copy: ASan sees any read past the line's end. */
    char *line = malloc(size ? size : 1U);
    if (line == NULL) {
        return 0;
    }
    memcpy(line, data, size);
    candump_line_t l;
    const char *why = NULL;
    const candump_result_t r = candump_parse_line(line, size, &l, &why);
    if (r == CANDUMP_ERR && why == NULL) {
        abort(); /* a rejection always says why */
    }
    if (r == CANDUMP_OK) {
        char out[CANDUMP_LINE_MAX];
        const size_t n = candump_format_line(out, l.t_us, l.iface, &l.frame);
        candump_line_t back;
        if (candump_parse_line(out, n, &back, &why) != CANDUMP_OK || back.t_us != l.t_us ||
            strcmp(back.iface, l.iface) != 0 || back.frame.id != l.frame.id || back.frame.dlc != l.frame.dlc ||
            back.frame.flags != l.frame.flags || memcmp(back.frame.data, l.frame.data, 8) != 0) {
            abort();
        }
    }
    free(line);
    return 0;
}
