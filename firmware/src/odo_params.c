/// Parameter block: defaults, range checks and the explicit little-endian (de)serialisation of the
/// layout in odo/odo_params.h (the spec; this file only walks its field table). Pure functions, no
/// state, no heap; every routine is reentrant. Encode, parse, validate and CRC are linear in the
/// block size (256 bytes) and the number of fields.
#include "odo/odo_params.h"

/* ---------------------------------------------------------------------------------------------
 * The field table, expanded from ODO_PARAMS_FIELDS: the only place offsets, widths and ranges
 * enter the code.
 * ------------------------------------------------------------------------------------------- */
#define OFF_MAGIC   0U
#define OFF_VERSION 4U
#define OFF_LENGTH  6U

#define WIDTH_U8  1U
#define WIDTH_U16 2U
#define WIDTH_U32 4U
#define WIDTH_I32 4U

#define MEMBER_OFF_TOP(m)    offsetof(odo_params_t, m)
#define MEMBER_OFF_LINK(m)   offsetof(odo_params_t, m)
#define MEMBER_OFF_TRUCK(m)  offsetof(odo_truck_params_t, m)
#define MEMBER_SIZE_TOP(m)   sizeof(((const odo_params_t *)0)->m)
#define MEMBER_SIZE_LINK(m)  sizeof(((const odo_params_t *)0)->m)
#define MEMBER_SIZE_TRUCK(m) sizeof(((const odo_truck_params_t *)0)->m)

#define FIELD_ROW(id, scope, member, json, since, off, stride, type, lo, hi, unit) \
    {(int64_t)(lo),                                                                \
     (int64_t)(hi),                                                                \
     json,                                                                         \
     (uint16_t)(off),                                                              \
     (uint16_t)(stride),                                                           \
     (uint16_t)MEMBER_OFF_##scope(member),                                         \
     (uint8_t)ODO_PF_##id,                                                         \
     (uint8_t)ODO_PSCOPE_##scope,                                                  \
     (uint8_t)ODO_PTYPE_##type,                                                    \
     (uint8_t)WIDTH_##type,                                                        \
     (uint8_t)(since)},

static const odo_param_field_info_t k_fields[] = {ODO_PARAMS_FIELDS(FIELD_ROW)};
#define N_FIELDS (sizeof k_fields / sizeof k_fields[0])

/* A slip in the table fails the build: a width that is not the member's, a field that ends past
 * the CRC of the first version that carries it, or a range the field's type cannot hold. */
#define FIELD_CHECKS(id, scope, member, json, since, off, stride, type, lo, hi, unit)                            \
    typedef char odo_assert_width_##id[(MEMBER_SIZE_##scope(member) == WIDTH_##type) ? 1 : -1];                  \
    typedef char odo_assert_fits_##id[((off) + (stride) + WIDTH_##type <=                                        \
                                       ((since) == 1 ? ODO_PARAMS_V1_CRC_OFFSET : ODO_PARAMS_CRC_OFFSET))        \
                                          ? 1                                                                    \
                                          : -1];                                                                 \
    typedef char                                                                                                 \
        odo_assert_range_##id[((lo) <= (hi) && ((ODO_PTYPE_##type == ODO_PTYPE_I32)                              \
                                                    ? ((lo) >= INT32_MIN && (hi) <= INT32_MAX)                   \
                                                    : ((lo) >= 0 && (hi) < ((int64_t)1 << (8 * WIDTH_##type))))) \
                                  ? 1                                                                            \
                                  : -1];
ODO_PARAMS_FIELDS(FIELD_CHECKS)
typedef char odo_assert_crc_last[(ODO_PARAMS_CRC_OFFSET + 4U == ODO_PARAMS_SIZE) ? 1 : -1];
typedef char odo_assert_v1_crc_last[(ODO_PARAMS_V1_CRC_OFFSET + 4U == ODO_PARAMS_V1_SIZE) ? 1 : -1];

size_t odo_params_field_count(void) { return N_FIELDS; }

const odo_param_field_info_t *odo_params_field_at(size_t i) { return i < N_FIELDS ? &k_fields[i] : NULL; }

const odo_param_field_info_t *odo_params_field_info(odo_param_field_t f)
{
    /* The enum lists the table's ids first, in table order, right after ODO_PF_NONE. */
    const size_t i = (size_t)f;
    return (i >= 1U && i <= N_FIELDS) ? &k_fields[i - 1U] : NULL;
}

bool odo_params_field_is_truck(odo_param_field_t f)
{
    const odo_param_field_info_t *fi = odo_params_field_info(f);
    return fi != NULL && fi->scope == (uint8_t)ODO_PSCOPE_TRUCK;
}

/// How many instances a field has in the block: one per truck, or one.
static unsigned instances(const odo_param_field_info_t *f)
{
    return f->scope == (uint8_t)ODO_PSCOPE_TRUCK ? (unsigned)ODO_TRUCKS : 1U;
}

/* ---------------------------------------------------------------------------------------------
 * Member access as 32-bit patterns. Signed fields go through their two's-complement bit pattern,
 * which C99 fixed-width types guarantee; no implementation-defined narrowing.
 * ------------------------------------------------------------------------------------------- */
static int32_t as_i32(uint32_t u)
{
    return (u <= (uint32_t)INT32_MAX) ? (int32_t)u : (int32_t)(u - 0x80000000UL) + INT32_MIN;
}

static const uint8_t *member_c(const odo_params_t *p, const odo_param_field_info_t *f, unsigned t)
{
    const uint8_t *base = f->scope == (uint8_t)ODO_PSCOPE_TRUCK ? (const uint8_t *)&p->truck[t] : (const uint8_t *)p;
    return base + f->member;
}

static uint8_t *member_w(odo_params_t *p, const odo_param_field_info_t *f, unsigned t)
{
    uint8_t *base = f->scope == (uint8_t)ODO_PSCOPE_TRUCK ? (uint8_t *)&p->truck[t] : (uint8_t *)p;
    return base + f->member;
}

static uint32_t load_bits(const odo_params_t *p, const odo_param_field_info_t *f, unsigned t)
{
    const uint8_t *m = member_c(p, f, t);
    uint32_t u32 = 0U;
    uint16_t u16 = 0U;
    int32_t i32 = 0;
    switch ((odo_param_type_t)f->type) {
    case ODO_PTYPE_U8: return m[0];
    case ODO_PTYPE_U16: memcpy(&u16, m, sizeof u16); return u16;
    case ODO_PTYPE_U32: memcpy(&u32, m, sizeof u32); return u32;
    case ODO_PTYPE_I32: memcpy(&i32, m, sizeof i32); return (uint32_t)i32;
    }
    return 0U;
}

static void store_bits(odo_params_t *p, const odo_param_field_info_t *f, unsigned t, uint32_t v)
{
    uint8_t *m = member_w(p, f, t);
    const uint16_t u16 = (uint16_t)(v & 0xFFFFU);
    const int32_t i32 = as_i32(v);
    switch ((odo_param_type_t)f->type) {
    case ODO_PTYPE_U8: m[0] = (uint8_t)(v & 0xFFU); break;
    case ODO_PTYPE_U16: memcpy(m, &u16, sizeof u16); break;
    case ODO_PTYPE_U32: memcpy(m, &v, sizeof v); break;
    case ODO_PTYPE_I32: memcpy(m, &i32, sizeof i32); break;
    }
}

/// The member's value: unsigned fields as they are, I32 sign-extended.
static int64_t load_value(const odo_params_t *p, const odo_param_field_info_t *f, unsigned t)
{
    const uint32_t bits = load_bits(p, f, t);
    return f->type == (uint8_t)ODO_PTYPE_I32 ? (int64_t)as_i32(bits) : (int64_t)bits;
}

int64_t odo_params_get(const odo_params_t *p, odo_param_field_t f, uint8_t truck)
{
    const odo_param_field_info_t *fi = odo_params_field_info(f);
    if (p == NULL || fi == NULL || truck >= ODO_TRUCKS) {
        return 0;
    }
    return load_value(p, fi, fi->scope == (uint8_t)ODO_PSCOPE_TRUCK ? truck : 0U);
}

bool odo_params_set(odo_params_t *p, odo_param_field_t f, uint8_t truck, int64_t v)
{
    const odo_param_field_info_t *fi = odo_params_field_info(f);
    if (p == NULL || fi == NULL || truck >= ODO_TRUCKS) {
        return false;
    }
    /* Modulo 2^32 first (well defined on the unsigned pattern), then the store narrows further. */
    store_bits(p, fi, fi->scope == (uint8_t)ODO_PSCOPE_TRUCK ? truck : 0U, (uint32_t)((uint64_t)v & 0xFFFFFFFFU));
    return true;
}

/* ---------------------------------------------------------------------------------------------
 * Little-endian byte access.
 * ------------------------------------------------------------------------------------------- */
static void put_le(uint8_t *b, uint32_t v, unsigned width)
{
    for (unsigned i = 0U; i < width; i++) {
        b[i] = (uint8_t)((v >> (8U * i)) & 0xFFU);
    }
}

static uint32_t get_le(const uint8_t *b, unsigned width)
{
    uint32_t v = 0U;
    for (unsigned i = width; i > 0U; i--) {
        v = (v << 8) | b[i - 1U];
    }
    return v;
}

/* ---------------------------------------------------------------------------------------------
 * CRC-32 (IEEE 802.3 / zlib), bitwise: 8 shift/xor steps per byte, no table (saves 1 KiB flash;
 * the block is checked once at boot).
 * ------------------------------------------------------------------------------------------- */
uint32_t odo_crc32(const uint8_t *data, size_t len)
{
    uint32_t crc = 0xFFFFFFFFUL;
    if (data == NULL) {
        len = 0U;
    }
    for (size_t i = 0U; i < len; i++) {
        crc ^= data[i];
        for (unsigned bit = 0U; bit < 8U; bit++) {
            uint32_t mask = (uint32_t)0U - (crc & 1U);
            crc = (crc >> 1) ^ (0xEDB88320UL & mask);
        }
    }
    return crc ^ 0xFFFFFFFFUL;
}

size_t odo_params_version_size(uint16_t version)
{
    switch (version) {
    case 1U: return ODO_PARAMS_V1_SIZE;
    case 2U: return ODO_PARAMS_SIZE;
    default: break;
    }
    return 0U;
}

/* ---------------------------------------------------------------------------------------------
 * Defaults and range checks.
 * ------------------------------------------------------------------------------------------- */
void odo_params_defaults(odo_params_t *p)
{
    if (p == NULL) {
        return;
    }
    memset(p, 0, sizeof *p);
    p->vehicle = (uint8_t)ODO_VEHICLE_SINGLE;
    p->counter_bits = 24U;
    p->heading_form = (uint8_t)ODO_HEADING_MIDPOINT;
    p->ipec_mode = (uint8_t)ODO_IPEC_OFF;
    p->tick_us = 40000UL;             /* 40 ms, 002 s. 4.1 */
    p->max_wheel_speed_mm_s = 3000UL; /* 3 m/s */
    for (unsigned t = 0U; t < ODO_TRUCKS; t++) {
        odo_truck_params_t *tr = &p->truck[t];
        tr->wheel_diameter_nm = 150UL * (uint32_t)ODO_NM_PER_MM; /* R = 75 mm, 004 Table I */
        /* 500-line encoder, 4x decoding, 19.5:1 gear: 500 * 4 * 19.5 = 39000 counts per turn. */
        tr->counts_per_rev_milli = (500UL * 4UL * 195UL / 10UL) * 1000UL;
        tr->wheelbase_nm = 340UL * (uint32_t)ODO_NM_PER_MM;
        tr->ed_q30 = ODO_RATIO_Q30_ONE;
        tr->eb_q30 = ODO_RATIO_Q30_ONE;
        tr->es_q30 = ODO_RATIO_Q30_ONE;
        tr->scrub_q30 = 0; /* no tyre-scrub term: 000 Eq. 2.4 as it stands */
        tr->flags = 0U;
    }
    p->link.length_nm = 1000UL * (uint32_t)ODO_NM_PER_MM; /* 1 m clapper link, 004 s. 2 */
    p->link.hitch_offset_nm = 0U;
    p->link.length_bias_nm = 0;
    p->link.length_ecc_nm = 0;
    p->link.alpha_bias_bam = 0;
    p->link.beta_bias_bam = 0;
    p->link.rotary_bits = 10U; /* 004 */
    p->link.stale_ticks = 3U;
    p->link.max_jump_bam = (uint32_t)ODO_DEG_TO_BAM(10);
    p->link.max_length_jump_um = 20UL * (uint32_t)ODO_UM_PER_MM;
    p->link.length_min_um = 900UL * (uint32_t)ODO_UM_PER_MM;
    p->link.length_max_um = 1100UL * (uint32_t)ODO_UM_PER_MM;
}

/// The first field of `scope` (instance t) outside its range, in table order; ODO_PF_NONE if none.
static odo_param_field_t check_scope(const odo_params_t *p, odo_param_scope_t scope, unsigned t)
{
    for (size_t i = 0U; i < N_FIELDS; i++) {
        const odo_param_field_info_t *f = &k_fields[i];
        if (f->scope != (uint8_t)scope) {
            continue;
        }
        const int64_t v = load_value(p, f, t);
        if ((v < f->min) || (v > f->max)) {
            return (odo_param_field_t)f->id;
        }
    }
    return ODO_PF_NONE;
}

odo_params_status_t odo_params_validate(const odo_params_t *p, odo_param_field_t *bad_field, uint8_t *bad_truck)
{
    uint8_t truck = 0U;

    if (p == NULL) {
        return ODO_PARAMS_ERR_ARG;
    }
    odo_param_field_t field = check_scope(p, ODO_PSCOPE_TOP, 0U);
    /* Both records, even for a single truck: an unused record must still hold sane values. */
    for (uint8_t t = 0U; (t < ODO_TRUCKS) && (field == ODO_PF_NONE); t++) {
        field = check_scope(p, ODO_PSCOPE_TRUCK, t);
        truck = t;
    }
    if (field == ODO_PF_NONE) {
        truck = 0U;
        field = check_scope(p, ODO_PSCOPE_LINK, 0U);
    }
    if ((field == ODO_PF_NONE) && (p->link.length_min_um >= p->link.length_max_um)) {
        field = ODO_PF_LENGTH_RANGE;
    }

    if (bad_field != NULL) {
        *bad_field = field;
    }
    if (bad_truck != NULL) {
        *bad_truck = (field == ODO_PF_NONE) ? 0U : truck;
    }
    return (field == ODO_PF_NONE) ? ODO_PARAMS_OK : ODO_PARAMS_ERR_RANGE;
}

/* ---------------------------------------------------------------------------------------------
 * Serialisation.
 * ------------------------------------------------------------------------------------------- */
size_t odo_params_encode(const odo_params_t *p, uint8_t *buf, size_t cap)
{
    if ((p == NULL) || (buf == NULL) || (cap < ODO_PARAMS_SIZE)) {
        return 0U;
    }
    memset(buf, 0, ODO_PARAMS_SIZE); /* reserved bytes are 0 */
    put_le(&buf[OFF_MAGIC], (uint32_t)ODO_PARAMS_MAGIC, 4U);
    put_le(&buf[OFF_VERSION], ODO_PARAMS_VERSION, 2U);
    put_le(&buf[OFF_LENGTH], ODO_PARAMS_SIZE, 2U);
    for (size_t i = 0U; i < N_FIELDS; i++) {
        const odo_param_field_info_t *f = &k_fields[i];
        for (unsigned t = 0U; t < instances(f); t++) {
            put_le(&buf[f->offset + t * f->stride], load_bits(p, f, t), f->width);
        }
    }
    put_le(&buf[ODO_PARAMS_CRC_OFFSET], odo_crc32(buf, ODO_PARAMS_CRC_OFFSET), 4U);
    return ODO_PARAMS_SIZE;
}

/// Offset of the first non-zero byte in [header, crc_off) that no field of `version` covers, or 0.
static size_t first_reserved(const uint8_t *buf, uint16_t version, size_t crc_off)
{
    uint8_t used[ODO_PARAMS_SIZE / 8U];
    memset(used, 0, sizeof used);
    for (size_t i = 0U; i < N_FIELDS; i++) {
        const odo_param_field_info_t *f = &k_fields[i];
        if (f->since > version) {
            continue;
        }
        for (unsigned t = 0U; t < instances(f); t++) {
            for (unsigned k = 0U; k < f->width; k++) {
                const unsigned at = f->offset + t * f->stride + k;
                used[at / 8U] = (uint8_t)(used[at / 8U] | (1U << (at % 8U)));
            }
        }
    }
    for (size_t at = ODO_PARAMS_HEADER_SIZE; at < crc_off; at++) {
        if ((((unsigned)used[at / 8U] >> (at % 8U)) & 1U) == 0U && buf[at] != 0U) {
            return at;
        }
    }
    return 0U;
}

size_t odo_params_reserved_offset(const uint8_t *buf, size_t len)
{
    if ((buf == NULL) || (len < ODO_PARAMS_HEADER_SIZE) ||
        (get_le(&buf[OFF_MAGIC], 4U) != (uint32_t)ODO_PARAMS_MAGIC)) {
        return 0U;
    }
    const uint16_t version = (uint16_t)get_le(&buf[OFF_VERSION], 2U);
    const size_t size = odo_params_version_size(version);
    if ((size == 0U) || (get_le(&buf[OFF_LENGTH], 2U) != size) || (len < size)) {
        return 0U;
    }
    return first_reserved(buf, version, size - 4U);
}

odo_params_status_t odo_params_parse(const uint8_t *buf, size_t len, odo_params_t *out)
{
    if ((buf == NULL) || (out == NULL)) {
        return ODO_PARAMS_ERR_ARG;
    }
    if (len < ODO_PARAMS_HEADER_SIZE) {
        return ODO_PARAMS_ERR_SHORT;
    }
    if (get_le(&buf[OFF_MAGIC], 4U) != (uint32_t)ODO_PARAMS_MAGIC) {
        return ODO_PARAMS_ERR_MAGIC;
    }
    const uint16_t version = (uint16_t)get_le(&buf[OFF_VERSION], 2U);
    const size_t size = odo_params_version_size(version);
    if (size == 0U) {
        return ODO_PARAMS_ERR_VERSION;
    }
    if (get_le(&buf[OFF_LENGTH], 2U) != size) {
        return ODO_PARAMS_ERR_LENGTH;
    }
    /* A flash region may be larger than the block; only the declared length is read. */
    if (len < size) {
        return ODO_PARAMS_ERR_SHORT;
    }
    const size_t crc_off = size - 4U;
    if (get_le(&buf[crc_off], 4U) != odo_crc32(buf, crc_off)) {
        return ODO_PARAMS_ERR_CRC;
    }

    /* Every check that leaves *out untouched is above: from here on the fields go straight into
     * *out (no local copy: the boot path's stack is part of the RAM budget). */
    memset(out, 0, sizeof *out); /* fields a version-1 block does not carry read as 0 */
    for (size_t i = 0U; i < N_FIELDS; i++) {
        const odo_param_field_info_t *f = &k_fields[i];
        if (f->since > version) {
            continue;
        }
        for (unsigned t = 0U; t < instances(f); t++) {
            store_bits(out, f, t, get_le(&buf[f->offset + t * f->stride], f->width));
        }
    }

    /* Non-zero reserved bytes mean a writer that knows a layout we do not: refuse, never guess. */
    return (first_reserved(buf, version, crc_off) == 0U) ? ODO_PARAMS_OK : ODO_PARAMS_ERR_RANGE;
}

odo_params_status_t odo_params_decode(const uint8_t *buf, size_t len, odo_params_t *out)
{
    odo_params_t p;
    if (out == NULL) {
        return ODO_PARAMS_ERR_ARG;
    }
    odo_params_status_t st = odo_params_parse(buf, len, &p);
    if (st == ODO_PARAMS_OK) {
        st = odo_params_validate(&p, NULL, NULL);
    }
    if (st == ODO_PARAMS_OK) {
        *out = p;
    }
    return st;
}

odo_params_status_t odo_params_load(const uint8_t *buf, size_t len, odo_params_t *out)
{
    if (out == NULL) {
        return ODO_PARAMS_ERR_ARG;
    }
    odo_params_status_t st = odo_params_decode(buf, len, out);
    if (st != ODO_PARAMS_OK) {
        odo_params_defaults(out);
    }
    return st;
}

const char *odo_params_status_str(odo_params_status_t s)
{
    switch (s) {
    case ODO_PARAMS_OK: return "ok";
    case ODO_PARAMS_ERR_SHORT: return "block too short (fewer bytes than the header or the declared length)";
    case ODO_PARAMS_ERR_MAGIC: return "bad magic (not a parameter block)";
    case ODO_PARAMS_ERR_VERSION: return "unknown parameter block version";
    case ODO_PARAMS_ERR_LENGTH: return "declared length differs from this version's size";
    case ODO_PARAMS_ERR_CRC: return "CRC mismatch (corrupted in flash or in transit)";
    case ODO_PARAMS_ERR_RANGE: return "field out of range (or reserved byte non-zero)";
    case ODO_PARAMS_ERR_ARG: return "invalid argument (NULL pointer or buffer too small)";
    default: break;
    }
    return "unknown status";
}

const char *odo_params_field_name(odo_param_field_t f)
{
    const odo_param_field_info_t *fi = odo_params_field_info(f);
    if (fi != NULL) {
        return fi->name;
    }
    if (f == ODO_PF_NONE) {
        return "none";
    }
    if (f == ODO_PF_LENGTH_RANGE) {
        return "link.length_min_um/link.length_max_um";
    }
    return (f == ODO_PF_RESERVED) ? "reserved" : "unknown";
}
