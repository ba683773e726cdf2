/// Parameter block JSON. See params_json.h.
#include "params_json.h"

#include <errno.h>
#include <inttypes.h>
#include <jansson.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "params_diag.h"

#define LINK_PREFIX "link."

/// The key a field has inside its JSON object: link fields drop their "link." prefix.
static const char *json_key(const odo_param_field_info_t *f)
{
    return f->scope == (uint8_t)ODO_PSCOPE_LINK ? f->name + strlen(LINK_PREFIX) : f->name;
}

static const odo_param_field_info_t *find_field(odo_param_scope_t scope, const char *key)
{
    for (size_t i = 0; i < odo_params_field_count(); ++i) {
        const odo_param_field_info_t *f = odo_params_field_at(i);
        if (f->scope == (uint8_t)scope && strcmp(json_key(f), key) == 0) {
            return f;
        }
    }
    return NULL;
}

/// Read the fields of `scope` (instance `truck`) from object o into *p for layout `version`:
/// every field the version carries is required, one it does not carry must be absent, and any
/// key that is neither a field nor in `allowed` fails.
static int read_fields(json_t *o, odo_param_scope_t scope, uint8_t truck, unsigned version, odo_params_t *p,
                       const char *origin, const char *prefix, const char *const *allowed, char *err, size_t errlen)
{
    const char *key;
    json_t *v;
    json_object_foreach(o, key, v)
    {
        const odo_param_field_info_t *f = find_field(scope, key);
        int known = f != NULL;
        for (const char *const *a = allowed; !known && a != NULL && *a != NULL; ++a) {
            known = strcmp(*a, key) == 0;
        }
        if (!known) {
            snprintf(err, errlen, "%s: %s%s: unknown key", origin, prefix, key);
            return -1;
        }
        if (f != NULL && f->since > version) {
            snprintf(err, errlen, "%s: %s%s: not part of a version-%u block (it came with version %u)", origin, prefix,
                     key, version, f->since);
            return -1;
        }
    }
    for (size_t i = 0; i < odo_params_field_count(); ++i) {
        const odo_param_field_info_t *f = odo_params_field_at(i);
        if (f->scope != (uint8_t)scope || f->since > version) {
            continue;
        }
        json_t *x = json_object_get(o, json_key(f));
        if (x == NULL) {
            snprintf(err, errlen, "%s: %s%s: missing", origin, prefix, json_key(f));
            return -1;
        }
        if (!json_is_integer(x)) {
            snprintf(err, errlen, "%s: %s%s: must be an integer", origin, prefix, json_key(f));
            return -1;
        }
        const json_int_t val = json_integer_value(x);
        long long lo = 0, hi = 0;
        switch ((odo_param_type_t)f->type) {
        case ODO_PTYPE_U8: hi = UINT8_MAX; break;
        case ODO_PTYPE_U16: hi = UINT16_MAX; break;
        case ODO_PTYPE_U32: hi = UINT32_MAX; break;
        case ODO_PTYPE_I32:
            lo = INT32_MIN;
            hi = INT32_MAX;
            break;
        }
        if (val < lo || val > hi) {
            snprintf(err, errlen, "%s: %s%s: %lld does not fit its field [%lld, %lld]", origin, prefix, json_key(f),
                     (long long)val, lo, hi);
            return -1;
        }
        (void)odo_params_set(p, (odo_param_field_t)f->id, truck, (int64_t)val);
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
    static const char *const k_meta[] = {"file",  "status",  "magic", "version", "length",
                                         "crc32", "comment", "truck", "link",    NULL};
    unsigned version = ODO_PARAMS_VERSION;
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
    if (ve != NULL) {
        if (!json_is_integer(ve) || json_integer_value(ve) < 1 || json_integer_value(ve) > ODO_PARAMS_VERSION) {
            snprintf(err, errlen, "%s: version: this tool reads layout versions 1 to %u", origin, ODO_PARAMS_VERSION);
            goto done;
        }
        version = (unsigned)json_integer_value(ve);
    }
    const size_t size = odo_params_version_size((uint16_t)version);
    if (le != NULL && !(json_is_integer(le) && json_integer_value(le) == (json_int_t)size)) {
        snprintf(err, errlen, "%s: length: a version-%u block is %zu bytes", origin, version, size);
        goto done;
    }
    if (read_fields(root, ODO_PSCOPE_TOP, 0, version, &p, origin, "", k_meta, err, errlen) != 0) {
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
        if (read_fields(o, ODO_PSCOPE_TRUCK, (uint8_t)t, version, &p, origin, prefix, NULL, err, errlen) != 0) {
            goto done;
        }
    }
    json_t *lk = json_object_get(root, "link");
    if (!json_is_object(lk)) {
        snprintf(err, errlen, "%s: link: must be an object", origin);
        goto done;
    }
    if (read_fields(lk, ODO_PSCOPE_LINK, 0, version, &p, origin, LINK_PREFIX, NULL, err, errlen) != 0) {
        goto done;
    }
    odo_param_field_t bad = ODO_PF_NONE;
    uint8_t bad_truck = 0;
    if (odo_params_validate(&p, &bad, &bad_truck) != ODO_PARAMS_OK) {
        char name[64];
        odo_params_qualified_name(bad, bad_truck, name, sizeof name);
        snprintf(err, errlen, "%s: %s: outside the documented range (odo_params.h)", origin, name);
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
    /* As large as the file (up to the 1 MiB cap), not the cap each time. */
    struct stat sb;
    const size_t limit = 1U << 20;
    const size_t cap = (fstat(fileno(f), &sb) == 0 && sb.st_size >= 0 && (uint64_t)sb.st_size < limit)
                           ? (size_t)sb.st_size + 1U
                           : limit;
    char *buf = malloc(cap + 1U);
    if (buf == NULL) {
        fclose(f);
        snprintf(err, errlen, "%s: out of memory", path);
        return NULL;
    }
    const size_t n = fread(buf, 1, cap + 1U, f);
    const int bad = ferror(f);
    fclose(f);
    if (bad || n > limit || (n == cap && cap < limit)) { /* over the cap, or grew while read */
        snprintf(err, errlen,
                 bad         ? "%s: read error"
                 : n > limit ? "%s: larger than 1 MiB, not a parameter file"
                             : "%s: changed while it was read",
                 path);
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
        /* A raw block of any version this firmware reads (a version-1 block reads with scrub 0);
         * the file must be exactly the block. */
        const uint8_t *b = (const uint8_t *)buf;
        const size_t want = n >= ODO_PARAMS_HEADER_SIZE ? odo_params_version_size((uint16_t)(b[4] | b[5] << 8)) : 0U;
        odo_params_t q;
        const odo_params_status_t st = odo_params_decode(b, n, &q);
        if (st != ODO_PARAMS_OK) {
            char field[64], detail[192];
            odo_params_explain(st, b, n, field, sizeof field, detail, sizeof detail);
            snprintf(err, errlen, "%s: not a valid parameter block (%zu bytes): %s%s%s", path, n,
                     odo_params_status_str(st), detail[0] != '\0' ? ": " : "", detail);
            rc = -1;
        } else if (n != want) {
            snprintf(err, errlen, "%s: %zu bytes: a raw parameter block file must be exactly its %zu bytes", path, n,
                     want);
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

/// The fields of one scope (instance `truck`) that layout `version` carries, as `"key": value`
/// members, comma separated.
static void write_scope(FILE *f, const odo_params_t *p, odo_param_scope_t scope, uint8_t truck, unsigned version)
{
    const char *sep = "";
    for (size_t i = 0; i < odo_params_field_count(); ++i) {
        const odo_param_field_info_t *fi = odo_params_field_at(i);
        if (fi->scope != (uint8_t)scope || fi->since > version) {
            continue;
        }
        fprintf(f, "%s\"%s\": %" PRId64, sep, json_key(fi), odo_params_get(p, (odo_param_field_t)fi->id, truck));
        sep = ", ";
    }
}

void odo_params_json_fields(FILE *f, const odo_params_t *p, unsigned version)
{
    fputc(' ', f);
    write_scope(f, p, ODO_PSCOPE_TOP, 0, version);
    fputs(",\n \"truck\": [", f);
    for (unsigned t = 0; t < ODO_TRUCKS; t++) {
        fprintf(f, "%s\n  {", t == 0 ? "" : ",");
        write_scope(f, p, ODO_PSCOPE_TRUCK, (uint8_t)t, version);
        fputc('}', f);
    }
    fputs("],\n \"link\": {", f);
    write_scope(f, p, ODO_PSCOPE_LINK, 0, version);
    fputc('}', f);
}

int odo_params_json_write_stored(FILE *f, const odo_params_t *p, unsigned version, uint32_t crc)
{
    fprintf(f,
            "{\"status\": \"ok\", \"magic\": \"ODOP\", \"version\": %u, \"length\": %zu, "
            "\"crc32\": \"0x%08" PRIX32 "\",\n",
            version, odo_params_version_size((uint16_t)version), crc);
    odo_params_json_fields(f, p, version);
    fputs("}\n", f);
    return ferror(f) ? -1 : 0;
}

int odo_params_json_write(FILE *f, const odo_params_t *p)
{
    uint8_t block[ODO_PARAMS_SIZE];
    (void)odo_params_encode(p, block, sizeof block);
    return odo_params_json_write_stored(f, p, ODO_PARAMS_VERSION, odo_crc32(block, ODO_PARAMS_CRC_OFFSET));
}
