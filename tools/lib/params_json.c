/// Parameter block JSON. See params_json.h.
#include "params_json.h"

#include <errno.h>
#include <inttypes.h>
#include <jansson.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef enum { F_U8, F_U16, F_U32, F_I32 } ftype_t;

typedef struct {
    const char *key;
    ftype_t     type;
    size_t      off;
} field_t;

#define TOP(k, t) {#k, t, offsetof(odo_params_t, k)}
#define TRK(k, t) {#k, t, offsetof(odo_truck_params_t, k)}
#define LNK(k, t) {#k, t, offsetof(odo_link_params_t, k)}

static const field_t k_top[] = {
    TOP(vehicle, F_U8), TOP(counter_bits, F_U8), TOP(heading_form, F_U8), TOP(ipec_mode, F_U8),
    TOP(tick_us, F_U32), TOP(max_wheel_speed_mm_s, F_U32),
};
static const field_t k_truck[] = {
    TRK(wheel_diameter_nm, F_U32), TRK(counts_per_rev_milli, F_U32), TRK(wheelbase_nm, F_U32),
    TRK(ed_q30, F_I32), TRK(eb_q30, F_I32), TRK(es_q30, F_I32), TRK(flags, F_U8),
};
static const field_t k_link[] = {
    LNK(length_nm, F_U32), LNK(hitch_offset_nm, F_U32), LNK(length_bias_nm, F_I32),
    LNK(length_ecc_nm, F_I32), LNK(alpha_bias_bam, F_I32), LNK(beta_bias_bam, F_I32),
    LNK(rotary_bits, F_U8), LNK(stale_ticks, F_U16), LNK(max_jump_bam, F_U32),
    LNK(max_length_jump_um, F_U32), LNK(length_min_um, F_U32), LNK(length_max_um, F_U32),
};
#define N(a) (sizeof(a) / sizeof((a)[0]))

static int find_field(const field_t *f, size_t n, const char *key)
{
    for (size_t i = 0; i < n; ++i) {
        if (strcmp(f[i].key, key) == 0) {
            return (int)i;
        }
    }
    return -1;
}

/// Read every field of table f from object o into base; unknown keys (other than `allowed`) fail.
static int read_fields(json_t *o, const field_t *f, size_t n, void *base, const char *origin,
                       const char *prefix, const char *const *allowed, char *err, size_t errlen)
{
    const char *key;
    json_t *v;
    json_object_foreach(o, key, v) {
        int known = find_field(f, n, key) >= 0;
        for (const char *const *a = allowed; !known && a != NULL && *a != NULL; ++a) {
            known = strcmp(*a, key) == 0;
        }
        if (!known) {
            snprintf(err, errlen, "%s: %s%s: unknown key", origin, prefix, key);
            return -1;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        json_t *x = json_object_get(o, f[i].key);
        if (x == NULL) {
            snprintf(err, errlen, "%s: %s%s: missing", origin, prefix, f[i].key);
            return -1;
        }
        if (!json_is_integer(x)) {
            snprintf(err, errlen, "%s: %s%s: must be an integer", origin, prefix, f[i].key);
            return -1;
        }
        const json_int_t val = json_integer_value(x);
        long long lo = 0, hi = 0;
        switch (f[i].type) {
        case F_U8: hi = UINT8_MAX; break;
        case F_U16: hi = UINT16_MAX; break;
        case F_U32: hi = UINT32_MAX; break;
        case F_I32: lo = INT32_MIN; hi = INT32_MAX; break;
        }
        if (val < lo || val > hi) {
            snprintf(err, errlen, "%s: %s%s: %lld does not fit its field [%lld, %lld]", origin, prefix,
                     f[i].key, (long long)val, lo, hi);
            return -1;
        }
        unsigned char *dst = (unsigned char *)base + f[i].off;
        switch (f[i].type) {
        case F_U8: { const uint8_t t = (uint8_t)val; memcpy(dst, &t, sizeof t); break; }
        case F_U16: { const uint16_t t = (uint16_t)val; memcpy(dst, &t, sizeof t); break; }
        case F_U32: { const uint32_t t = (uint32_t)val; memcpy(dst, &t, sizeof t); break; }
        case F_I32: { const int32_t t = (int32_t)val; memcpy(dst, &t, sizeof t); break; }
        }
    }
    return 0;
}

int odo_params_json_parse(const char *text, const char *origin, odo_params_t *out, char *err, size_t errlen)
{
    json_error_t je;
    json_t *root = json_loads(text, JSON_REJECT_DUPLICATES, &je);
    if (root == NULL) {
        snprintf(err, errlen, "%s: line %d column %d: %s", origin, je.line, je.column, je.text);
        return -1;
    }
    int rc = -1;
    odo_params_t p;
    odo_params_defaults(&p);
    static const char *const k_meta[] = {"file", "status", "magic", "version", "length", "crc32",
                                         "comment", "truck", "link", NULL};
    if (!json_is_object(root)) {
        snprintf(err, errlen, "%s: the top level must be an object", origin);
        goto done;
    }
    json_t *st = json_object_get(root, "status");
    json_t *mg = json_object_get(root, "magic");
    json_t *ve = json_object_get(root, "version");
    json_t *le = json_object_get(root, "length");
    if (st != NULL && !(json_is_string(st) && strcmp(json_string_value(st), "ok") == 0)) {
        snprintf(err, errlen, "%s: status: a block whose status is not \"ok\" cannot be used", origin);
        goto done;
    }
    if (mg != NULL && !(json_is_string(mg) && strcmp(json_string_value(mg), "ODOP") == 0)) {
        snprintf(err, errlen, "%s: magic: must be \"ODOP\"", origin);
        goto done;
    }
    if (ve != NULL && !(json_is_integer(ve) && json_integer_value(ve) == ODO_PARAMS_VERSION)) {
        snprintf(err, errlen, "%s: version: this tool writes layout version %u only", origin,
                 ODO_PARAMS_VERSION);
        goto done;
    }
    if (le != NULL && !(json_is_integer(le) && json_integer_value(le) == ODO_PARAMS_SIZE)) {
        snprintf(err, errlen, "%s: length: a version-%u block is %u bytes", origin, ODO_PARAMS_VERSION,
                 ODO_PARAMS_SIZE);
        goto done;
    }
    if (read_fields(root, k_top, N(k_top), &p, origin, "", k_meta, err, errlen) != 0) {
        goto done;
    }
    json_t *tr = json_object_get(root, "truck");
    if (!json_is_array(tr) || json_array_size(tr) != ODO_TRUCKS) {
        snprintf(err, errlen, "%s: truck: must be an array of %u objects", origin, (unsigned)ODO_TRUCKS);
        goto done;
    }
    for (size_t t = 0; t < ODO_TRUCKS; ++t) {
        char prefix[32];
        snprintf(prefix, sizeof prefix, "truck[%zu].", t);
        json_t *o = json_array_get(tr, t);
        if (!json_is_object(o)) {
            snprintf(err, errlen, "%s: truck[%zu]: must be an object", origin, t);
            goto done;
        }
        if (read_fields(o, k_truck, N(k_truck), &p.truck[t], origin, prefix, NULL, err, errlen) != 0) {
            goto done;
        }
    }
    json_t *lk = json_object_get(root, "link");
    if (!json_is_object(lk)) {
        snprintf(err, errlen, "%s: link: must be an object", origin);
        goto done;
    }
    if (read_fields(lk, k_link, N(k_link), &p.link, origin, "link.", NULL, err, errlen) != 0) {
        goto done;
    }
    odo_param_field_t bad = ODO_PF_NONE;
    uint8_t bad_truck = 0;
    if (odo_params_validate(&p, &bad, &bad_truck) != ODO_PARAMS_OK) {
        if (bad >= ODO_PF_WHEEL_DIAMETER && bad <= ODO_PF_TRUCK_FLAGS) {
            snprintf(err, errlen, "%s: truck[%u].%s: outside the documented range (odo_params.h)", origin,
                     (unsigned)bad_truck, odo_params_field_name(bad));
        } else {
            snprintf(err, errlen, "%s: %s: outside the documented range (odo_params.h)", origin, odo_params_field_name(bad));
        }
        goto done;
    }
    *out = p;
    rc = 0;
done:
    json_decref(root);
    return rc;
}

/// Read a whole (small) file. Returns a malloc'd NUL-terminated buffer and its length, or NULL.
static char *slurp(const char *path, size_t *len, char *err, size_t errlen)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    const size_t cap = 1U << 20;
    char *buf = malloc(cap + 1U);
    if (buf == NULL) {
        fclose(f);
        snprintf(err, errlen, "%s: out of memory", path);
        return NULL;
    }
    const size_t n = fread(buf, 1, cap + 1U, f);
    const int bad = ferror(f);
    fclose(f);
    if (bad || n > cap) {
        snprintf(err, errlen, bad ? "%s: read error" : "%s: larger than 1 MiB, not a parameter file", path);
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    *len = n;
    return buf;
}

int odo_params_json_load(const char *path, odo_params_t *p, char *err, size_t errlen)
{
    size_t n = 0;
    char *text = slurp(path, &n, err, errlen);
    if (text == NULL) {
        return -1;
    }
    if (strlen(text) != n) {
        snprintf(err, errlen, "%s: contains a NUL byte: not a JSON parameter file", path);
        free(text);
        return -1;
    }
    const int rc = odo_params_json_parse(text, path, p, err, errlen);
    free(text);
    return rc;
}

int odo_params_file_load(const char *path, odo_params_t *p, char *err, size_t errlen)
{
    size_t n = 0;
    char *buf = slurp(path, &n, err, errlen);
    if (buf == NULL) {
        return -1;
    }
    int rc;
    if (n >= 4 && memcmp(buf, "ODOP", 4) == 0) {
        odo_params_t q;
        const odo_params_status_t st = n == ODO_PARAMS_SIZE ? odo_params_decode((const uint8_t *)buf, n, &q)
                                                             : ODO_PARAMS_ERR_SHORT;
        if (st != ODO_PARAMS_OK) {
            snprintf(err, errlen, "%s: not a valid %u-byte parameter block (%zu bytes): %s", path,
                     ODO_PARAMS_SIZE, n, n == ODO_PARAMS_SIZE ? odo_params_status_str(st) : "wrong size");
            rc = -1;
        } else {
            *p = q;
            rc = 0;
        }
    } else if (strlen(buf) != n) {
        snprintf(err, errlen, "%s: neither a parameter block (no 'ODOP' magic) nor JSON text", path);
        rc = -1;
    } else {
        rc = odo_params_json_parse(buf, path, p, err, errlen);
    }
    free(buf);
    return rc;
}

void odo_params_json_fields(FILE *f, const odo_params_t *p)
{
    fprintf(f, " \"vehicle\": %u, \"counter_bits\": %u, \"heading_form\": %u, \"ipec_mode\": %u, "
               "\"tick_us\": %" PRIu32 ", \"max_wheel_speed_mm_s\": %" PRIu32 ",\n \"truck\": [",
            p->vehicle, p->counter_bits, p->heading_form, p->ipec_mode, p->tick_us,
            p->max_wheel_speed_mm_s);
    for (unsigned t = 0; t < ODO_TRUCKS; t++) {
        const odo_truck_params_t *tr = &p->truck[t];
        fprintf(f,
                "%s\n  {\"wheel_diameter_nm\": %" PRIu32 ", \"counts_per_rev_milli\": %" PRIu32
                ", \"wheelbase_nm\": %" PRIu32 ", \"ed_q30\": %" PRId32 ", \"eb_q30\": %" PRId32
                ", \"es_q30\": %" PRId32 ", \"flags\": %u}",
                t == 0 ? "" : ",", tr->wheel_diameter_nm, tr->counts_per_rev_milli, tr->wheelbase_nm,
                tr->ed_q30, tr->eb_q30, tr->es_q30, tr->flags);
    }
    const odo_link_params_t *l = &p->link;
    fprintf(f, "],\n \"link\": {\"length_nm\": %" PRIu32 ", \"hitch_offset_nm\": %" PRIu32
               ", \"length_bias_nm\": %" PRId32 ", \"length_ecc_nm\": %" PRId32
               ", \"alpha_bias_bam\": %" PRId32 ", \"beta_bias_bam\": %" PRId32
               ", \"rotary_bits\": %u, \"stale_ticks\": %u, \"max_jump_bam\": %" PRIu32
               ", \"max_length_jump_um\": %" PRIu32 ", \"length_min_um\": %" PRIu32
               ", \"length_max_um\": %" PRIu32 "}",
            l->length_nm, l->hitch_offset_nm, l->length_bias_nm, l->length_ecc_nm, l->alpha_bias_bam,
            l->beta_bias_bam, l->rotary_bits, l->stale_ticks, l->max_jump_bam, l->max_length_jump_um,
            l->length_min_um, l->length_max_um);
}

int odo_params_json_write(FILE *f, const odo_params_t *p)
{
    uint8_t block[ODO_PARAMS_SIZE];
    (void)odo_params_encode(p, block, sizeof block);
    fprintf(f, "{\"status\": \"ok\", \"magic\": \"ODOP\", \"version\": %u, \"length\": %u, "
               "\"crc32\": \"0x%08" PRIX32 "\",\n",
            ODO_PARAMS_VERSION, ODO_PARAMS_SIZE, odo_crc32(block, ODO_PARAMS_CRC_OFFSET));
    odo_params_json_fields(f, p);
    fputs("}\n", f);
    return ferror(f) ? -1 : 0;
}
