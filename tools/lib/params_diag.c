/// Parameter block diagnostics. See params_diag.h.
#include "params_diag.h"

#include <inttypes.h>
#include <stdio.h>

static unsigned le16(const uint8_t *b) { return (unsigned)b[0] | ((unsigned)b[1] << 8); }

static uint32_t le32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

void odo_params_qualified_name(odo_param_field_t f, uint8_t truck, char *out, size_t cap)
{
    if (odo_params_field_is_truck(f)) {
        snprintf(out, cap, "truck[%u].%s", (unsigned)truck, odo_params_field_name(f));
    } else {
        snprintf(out, cap, "%s", odo_params_field_name(f));
    }
}

void odo_params_explain(odo_params_status_t st, const uint8_t *b, size_t n, char *field, size_t fcap, char *detail,
                        size_t dcap)
{
    field[0] = '\0';
    detail[0] = '\0';
    switch (st) {
    case ODO_PARAMS_ERR_SHORT: {
        const size_t want = n >= ODO_PARAMS_HEADER_SIZE ? odo_params_version_size((uint16_t)le16(&b[4])) : 0U;
        if (want != 0U) {
            snprintf(detail, dcap, "%zu bytes, a version-%u block is %zu", n, le16(&b[4]), want);
        } else {
            snprintf(detail, dcap, "%zu bytes, fewer than the %u-byte header", n, ODO_PARAMS_HEADER_SIZE);
        }
        break;
    }
    case ODO_PARAMS_ERR_MAGIC:
        snprintf(field, fcap, "magic");
        snprintf(detail, dcap, "first bytes %02X %02X %02X %02X, expected 4F 44 4F 50 ('ODOP')", b[0], b[1], b[2],
                 b[3]);
        break;
    case ODO_PARAMS_ERR_VERSION:
        snprintf(field, fcap, "version");
        snprintf(detail, dcap, "version %u, this tool reads 1 and %u", le16(&b[4]), ODO_PARAMS_VERSION);
        break;
    case ODO_PARAMS_ERR_LENGTH:
        snprintf(field, fcap, "length");
        snprintf(detail, dcap, "declared length %u, version-%u blocks are %zu", le16(&b[6]), le16(&b[4]),
                 odo_params_version_size((uint16_t)le16(&b[4])));
        break;
    case ODO_PARAMS_ERR_CRC: {
        const size_t crc_off = odo_params_version_size((uint16_t)le16(&b[4])) - 4U;
        snprintf(field, fcap, "crc32");
        snprintf(detail, dcap, "stored CRC-32 0x%08" PRIX32 ", computed 0x%08" PRIX32 " over bytes [0, %zu)",
                 le32(&b[crc_off]), odo_crc32(b, crc_off), crc_off);
        break;
    }
    case ODO_PARAMS_ERR_RANGE: {
        /* Header and CRC are good: a reserved byte, or a field the validator names. */
        const size_t at = odo_params_reserved_offset(b, n);
        if (at != 0U) {
            snprintf(field, fcap, "reserved");
            snprintf(detail, dcap, "reserved byte at offset %zu is 0x%02X, must be 0", at, b[at]);
            break;
        }
        odo_params_t p;
        odo_param_field_t f = ODO_PF_NONE;
        uint8_t t = 0U;
        (void)odo_params_parse(b, n, &p);
        (void)odo_params_validate(&p, &f, &t);
        odo_params_qualified_name(f, t, field, fcap);
        const odo_param_field_info_t *fi = odo_params_field_info(f);
        if (fi != NULL) {
            snprintf(detail, dcap, "field %s = %" PRId64 " is outside [%" PRId64 ", %" PRId64 "]", field,
                     odo_params_get(&p, f, t), fi->min, fi->max);
        } else {
            snprintf(detail, dcap, "field %s = %" PRIu32 "/%" PRIu32 ": the minimum must be below the maximum", field,
                     p.link.length_min_um, p.link.length_max_um);
        }
        break;
    }
    case ODO_PARAMS_OK:
    case ODO_PARAMS_ERR_ARG: break;
    }
}
