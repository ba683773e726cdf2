/// libFuzzer harness: the parameter block codec (firmware/include/odo/odo_params.h), versions 1
/// and 2. The first byte chooses whether the CRC-32 is made right before decoding, so the fuzzer
/// reaches the field checks rather than stopping at the CRC. Whatever decodes encodes to a v2
/// block that decodes to the same parameters and the same bytes again; odo_params_load always
/// leaves a block the firmware accepts.
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "odo/odo_params.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1U) {
        return 0;
    }
    const int fix_crc = data[0] & 1;
    size--;
    data++;
    uint8_t *buf = malloc(size ? size : 1U); /* exact size: ASan sees any overread */
    if (buf == NULL) {
        return 0;
    }
    memcpy(buf, data, size);
    if (fix_crc && size >= 8U) {
        const size_t n = odo_params_version_size((uint16_t)(buf[4] | buf[5] << 8));
        if (n >= 8U && size >= n) {
            const uint32_t c = odo_crc32(buf, n - 4U);
            buf[n - 4U] = (uint8_t)c;
            buf[n - 3U] = (uint8_t)(c >> 8);
            buf[n - 2U] = (uint8_t)(c >> 16);
            buf[n - 1U] = (uint8_t)(c >> 24);
        }
    }
    odo_params_t p, q;
    (void)odo_params_reserved_offset(buf, size);
    if (odo_params_parse(buf, size, &p) == ODO_PARAMS_OK) {
        (void)odo_params_validate(&p, NULL, NULL);
    }
    if (odo_params_decode(buf, size, &p) == ODO_PARAMS_OK) {
        uint8_t a[ODO_PARAMS_SIZE], b[ODO_PARAMS_SIZE];
        if (odo_params_encode(&p, a, sizeof a) != ODO_PARAMS_SIZE ||
            odo_params_decode(a, sizeof a, &q) != ODO_PARAMS_OK ||
            odo_params_encode(&q, b, sizeof b) != ODO_PARAMS_SIZE || memcmp(a, b, sizeof a) != 0) {
            abort();
        }
    }
    (void)odo_params_load(buf, size, &p);
    uint8_t c[ODO_PARAMS_SIZE];
    if (odo_params_encode(&p, c, sizeof c) != ODO_PARAMS_SIZE || odo_params_decode(c, sizeof c, &q) != ODO_PARAMS_OK) {
        abort(); /* the boot path never ends on a block the firmware itself refuses */
    }
    free(buf);
    return 0;
}
