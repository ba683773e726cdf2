/// Parameter block: defaults, range checks and the explicit little-endian (de)serialisation of the
/// layout in odo/odo_params.h (the spec; this file only implements it). Pure functions, no state,
/// no heap; every routine is reentrant. Decode/encode/CRC are linear in the block size (128 bytes).
#include "odo/odo_params.h"

/* ---------------------------------------------------------------------------------------------
 * Layout offsets (odo_params.h, version 1). Named once here so encode and decode cannot disagree.
 * ------------------------------------------------------------------------------------------- */
#define OFF_MAGIC        0U
#define OFF_VERSION      4U
#define OFF_LENGTH       6U
#define HEADER_SIZE      8U  /* magic + version + length: enough to know what the block claims */
#define OFF_VEHICLE      8U
#define OFF_COUNTER_BITS 9U
#define OFF_HEADING_FORM 10U
#define OFF_IPEC_MODE    11U
#define OFF_TICK_US      12U
#define OFF_MAX_SPEED    16U
#define OFF_TRUCK0       20U
#define TRUCK_SIZE       28U
#define OFF_LINK         76U

/* Truck record, relative to its start. */
#define TR_WHEEL_DIAMETER 0U
#define TR_COUNTS_PER_REV 4U
#define TR_WHEELBASE      8U
#define TR_ED             12U
#define TR_EB             16U
#define TR_ES             20U
#define TR_FLAGS          24U
#define TR_RESERVED       25U
#define TR_RESERVED_SIZE  3U

/* Link record, absolute offsets. */
#define OFF_LINK_LENGTH       76U
#define OFF_HITCH_OFFSET      80U
#define OFF_LENGTH_BIAS       84U
#define OFF_LENGTH_ECC        88U
#define OFF_ALPHA_BIAS        92U
#define OFF_BETA_BIAS         96U
#define OFF_ROTARY_BITS       100U
#define OFF_RESERVED_A        101U
#define OFF_STALE_TICKS       102U
#define OFF_MAX_JUMP          104U
#define OFF_MAX_LENGTH_JUMP   108U
#define OFF_LENGTH_MIN        112U
#define OFF_LENGTH_MAX        116U
#define OFF_RESERVED_B        120U
#define RESERVED_B_SIZE       4U

/* A layout slip (a field moved without its neighbours) fails the build, not the field. */
typedef char odo_assert_truck_fits[(OFF_TRUCK0 + ODO_TRUCKS * TRUCK_SIZE == OFF_LINK) ? 1 : -1];
typedef char odo_assert_link_fits[(OFF_RESERVED_B + RESERVED_B_SIZE == ODO_PARAMS_CRC_OFFSET) ? 1 : -1];
typedef char odo_assert_crc_last[(ODO_PARAMS_CRC_OFFSET + 4U == ODO_PARAMS_SIZE) ? 1 : -1];

/* ---------------------------------------------------------------------------------------------
 * Units and limits. Ranges are inclusive, as documented beside each field in odo_params.h.
 * ------------------------------------------------------------------------------------------- */
#define NM_PER_MM 1000000UL
#define NM_PER_M  1000000000ULL
#define UM_PER_MM 1000UL
#define UM_PER_M  1000000UL

/* Degrees to BAM (2^32 per turn), rounded to nearest; exact for 90 deg. */
#define DEG_TO_BAM(deg) ((uint32_t)((((uint64_t)(deg) << 32) + 180U) / 360U))

/* Q30 ratios: 0.8 is not representable, 0.8 * 2^30 = 858993459.2 truncates to the nearest Q30
 * value; 1.25 is exact. */
#define RATIO_MIN_Q30 ((int32_t)(((int64_t)4 << 30) / 5))
#define RATIO_MAX_Q30 ((int32_t)(((int64_t)5 << 30) / 4))

#define TICK_MIN_US            1000UL     /* 1 ms */
#define TICK_MAX_US            1000000UL  /* 1 s */
#define WHEEL_SPEED_MIN_MM_S   100UL
#define WHEEL_SPEED_MAX_MM_S   20000UL

#define WHEEL_DIAMETER_MIN_NM  (10UL * NM_PER_MM)
#define WHEEL_DIAMETER_MAX_NM  (2UL * NM_PER_M)
#define COUNTS_MILLI_PER_COUNT 1000UL
#define COUNTS_PER_REV_MIN     (100UL * COUNTS_MILLI_PER_COUNT)
#define COUNTS_PER_REV_MAX     (4000000ULL * COUNTS_MILLI_PER_COUNT) /* 4e9: still fits uint32 */
#define WHEELBASE_MIN_NM       (50UL * NM_PER_MM)
#define WHEELBASE_MAX_NM       (3ULL * NM_PER_M)
#define TRUCK_FLAGS_KNOWN      (ODO_TRUCK_INVERT_LEFT | ODO_TRUCK_INVERT_RIGHT)

/* Lengths are uint32 nm (at most 4.29 m), so the documented limits stop at 4 m. */
#define LINK_LENGTH_MIN_NM     (100UL * NM_PER_MM)
#define LINK_LENGTH_MAX_NM     (4ULL * NM_PER_M)
#define HITCH_OFFSET_MAX_NM    (4ULL * NM_PER_M)
#define LENGTH_BIAS_MAX_NM     ((int64_t)(50UL * NM_PER_MM))
#define ROTARY_BIAS_MAX_BAM    ((int64_t)DEG_TO_BAM(10U))
#define ROTARY_BITS_MIN        8U
#define ROTARY_BITS_MAX        16U
#define STALE_TICKS_MIN        1U
#define STALE_TICKS_MAX        1000U
#define MAX_JUMP_MIN_BAM       1UL
#define MAX_JUMP_MAX_BAM       DEG_TO_BAM(90U)
#define MAX_LENGTH_JUMP_MIN_UM 1UL
#define MAX_LENGTH_JUMP_MAX_UM (1UL * UM_PER_M)
#define LENGTH_LIMIT_MIN_UM    (1UL * UM_PER_MM)
#define LENGTH_LIMIT_MAX_UM    (20UL * UM_PER_M)

/* ---------------------------------------------------------------------------------------------
 * Little-endian byte access. Shifts on unsigned values only; signed fields go through their
 * two's-complement bit pattern, which C99 fixed-width types guarantee.
 * ------------------------------------------------------------------------------------------- */
static void put_u16(uint8_t *b, uint16_t v)
{
    b[0] = (uint8_t)(v & 0xFFU);
    b[1] = (uint8_t)(v >> 8);
}

static void put_u32(uint8_t *b, uint32_t v)
{
    b[0] = (uint8_t)(v & 0xFFU);
    b[1] = (uint8_t)((v >> 8) & 0xFFU);
    b[2] = (uint8_t)((v >> 16) & 0xFFU);
    b[3] = (uint8_t)(v >> 24);
}

static void put_i32(uint8_t *b, int32_t v) { put_u32(b, (uint32_t)v); }

static uint16_t get_u16(const uint8_t *b) { return (uint16_t)((uint16_t)b[0] | ((uint16_t)b[1] << 8)); }

static uint32_t get_u32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static int32_t get_i32(const uint8_t *b)
{
    uint32_t u = get_u32(b);
    /* Portable two's-complement reinterpretation (no implementation-defined narrowing). */
    return (u <= (uint32_t)INT32_MAX) ? (int32_t)u : (int32_t)(u - 0x80000000UL) + INT32_MIN;
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
    p->tick_us = 40000UL;              /* 40 ms, 002 s. 4.1 */
    p->max_wheel_speed_mm_s = 3000UL;  /* 3 m/s */
    for (unsigned t = 0U; t < ODO_TRUCKS; t++) {
        odo_truck_params_t *tr = &p->truck[t];
        tr->wheel_diameter_nm = 150UL * NM_PER_MM;  /* R = 75 mm, 004 Table I */
        /* 500-line encoder, 4x decoding, 19.5:1 gear: 500 * 4 * 19.5 = 39000 counts per turn. */
        tr->counts_per_rev_milli = (500UL * 4UL * 195UL / 10UL) * COUNTS_MILLI_PER_COUNT;
        tr->wheelbase_nm = 340UL * NM_PER_MM;
        tr->ed_q30 = ODO_RATIO_Q30_ONE;
        tr->eb_q30 = ODO_RATIO_Q30_ONE;
        tr->es_q30 = ODO_RATIO_Q30_ONE;
        tr->flags = 0U;
    }
    p->link.length_nm = (uint32_t)NM_PER_M;  /* 1 m clapper link, 004 s. 2 */
    p->link.hitch_offset_nm = 0U;
    p->link.length_bias_nm = 0;
    p->link.length_ecc_nm = 0;
    p->link.alpha_bias_bam = 0;
    p->link.beta_bias_bam = 0;
    p->link.rotary_bits = 10U;  /* 004 */
    p->link.stale_ticks = 3U;
    p->link.max_jump_bam = DEG_TO_BAM(10U);
    p->link.max_length_jump_um = 20UL * UM_PER_MM;
    p->link.length_min_um = 900UL * UM_PER_MM;
    p->link.length_max_um = 1100UL * UM_PER_MM;
}

static bool in_u(uint64_t v, uint64_t lo, uint64_t hi) { return (v >= lo) && (v <= hi); }

static bool in_abs(int64_t v, int64_t max_abs) { return (v >= -max_abs) && (v <= max_abs); }

static odo_param_field_t check_truck(const odo_truck_params_t *tr)
{
    if (!in_u(tr->wheel_diameter_nm, WHEEL_DIAMETER_MIN_NM, WHEEL_DIAMETER_MAX_NM)) {
        return ODO_PF_WHEEL_DIAMETER;
    }
    if (!in_u(tr->counts_per_rev_milli, COUNTS_PER_REV_MIN, COUNTS_PER_REV_MAX)) {
        return ODO_PF_COUNTS_PER_REV;
    }
    if (!in_u(tr->wheelbase_nm, WHEELBASE_MIN_NM, WHEELBASE_MAX_NM)) {
        return ODO_PF_WHEELBASE;
    }
    if ((tr->ed_q30 < RATIO_MIN_Q30) || (tr->ed_q30 > RATIO_MAX_Q30)) {
        return ODO_PF_ED;
    }
    if ((tr->eb_q30 < RATIO_MIN_Q30) || (tr->eb_q30 > RATIO_MAX_Q30)) {
        return ODO_PF_EB;
    }
    if ((tr->es_q30 < RATIO_MIN_Q30) || (tr->es_q30 > RATIO_MAX_Q30)) {
        return ODO_PF_ES;
    }
    if ((tr->flags & (uint8_t)~TRUCK_FLAGS_KNOWN) != 0U) {
        return ODO_PF_TRUCK_FLAGS;
    }
    return ODO_PF_NONE;
}

static odo_param_field_t check_link(const odo_link_params_t *l)
{
    if (!in_u(l->length_nm, LINK_LENGTH_MIN_NM, LINK_LENGTH_MAX_NM)) {
        return ODO_PF_LINK_LENGTH;
    }
    if (!in_u(l->hitch_offset_nm, 0U, HITCH_OFFSET_MAX_NM)) {
        return ODO_PF_HITCH_OFFSET;
    }
    if (!in_abs(l->length_bias_nm, LENGTH_BIAS_MAX_NM)) {
        return ODO_PF_LENGTH_BIAS;
    }
    if (!in_abs(l->length_ecc_nm, LENGTH_BIAS_MAX_NM)) {
        return ODO_PF_LENGTH_ECC;
    }
    if (!in_abs(l->alpha_bias_bam, ROTARY_BIAS_MAX_BAM)) {
        return ODO_PF_ALPHA_BIAS;
    }
    if (!in_abs(l->beta_bias_bam, ROTARY_BIAS_MAX_BAM)) {
        return ODO_PF_BETA_BIAS;
    }
    if (!in_u(l->rotary_bits, ROTARY_BITS_MIN, ROTARY_BITS_MAX)) {
        return ODO_PF_ROTARY_BITS;
    }
    if (!in_u(l->stale_ticks, STALE_TICKS_MIN, STALE_TICKS_MAX)) {
        return ODO_PF_STALE_TICKS;
    }
    if (!in_u(l->max_jump_bam, MAX_JUMP_MIN_BAM, MAX_JUMP_MAX_BAM)) {
        return ODO_PF_MAX_JUMP;
    }
    if (!in_u(l->max_length_jump_um, MAX_LENGTH_JUMP_MIN_UM, MAX_LENGTH_JUMP_MAX_UM)) {
        return ODO_PF_MAX_LENGTH_JUMP;
    }
    if (!in_u(l->length_min_um, LENGTH_LIMIT_MIN_UM, LENGTH_LIMIT_MAX_UM) ||
        !in_u(l->length_max_um, LENGTH_LIMIT_MIN_UM, LENGTH_LIMIT_MAX_UM) ||
        (l->length_min_um >= l->length_max_um)) {
        return ODO_PF_LENGTH_RANGE;
    }
    return ODO_PF_NONE;
}

odo_params_status_t odo_params_validate(const odo_params_t *p, odo_param_field_t *bad_field,
                                        uint8_t *bad_truck)
{
    odo_param_field_t field = ODO_PF_NONE;
    uint8_t truck = 0U;

    if (p == NULL) {
        return ODO_PARAMS_ERR_ARG;
    }
    if (p->vehicle > (uint8_t)ODO_VEHICLE_SET) {
        field = ODO_PF_VEHICLE;
    } else if ((p->counter_bits < 8U) || (p->counter_bits > 32U)) {
        field = ODO_PF_COUNTER_BITS;
    } else if (p->heading_form > (uint8_t)ODO_HEADING_PAPER) {
        field = ODO_PF_HEADING_FORM;
    } else if (p->ipec_mode > (uint8_t)ODO_IPEC_ESTIMATOR) {
        field = ODO_PF_IPEC_MODE;
    } else if (!in_u(p->tick_us, TICK_MIN_US, TICK_MAX_US)) {
        field = ODO_PF_TICK_US;
    } else if (!in_u(p->max_wheel_speed_mm_s, WHEEL_SPEED_MIN_MM_S, WHEEL_SPEED_MAX_MM_S)) {
        field = ODO_PF_MAX_WHEEL_SPEED;
    } else {
        /* Both records, even for a single truck: an unused record must still hold sane values. */
        for (uint8_t t = 0U; (t < ODO_TRUCKS) && (field == ODO_PF_NONE); t++) {
            field = check_truck(&p->truck[t]);
            truck = t;
        }
        if (field == ODO_PF_NONE) {
            truck = 0U;
            field = check_link(&p->link);
        }
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
    memset(buf, 0, ODO_PARAMS_SIZE);  /* reserved bytes are 0 */
    put_u32(&buf[OFF_MAGIC], (uint32_t)ODO_PARAMS_MAGIC);
    put_u16(&buf[OFF_VERSION], (uint16_t)ODO_PARAMS_VERSION);
    put_u16(&buf[OFF_LENGTH], (uint16_t)ODO_PARAMS_SIZE);
    buf[OFF_VEHICLE] = p->vehicle;
    buf[OFF_COUNTER_BITS] = p->counter_bits;
    buf[OFF_HEADING_FORM] = p->heading_form;
    buf[OFF_IPEC_MODE] = p->ipec_mode;
    put_u32(&buf[OFF_TICK_US], p->tick_us);
    put_u32(&buf[OFF_MAX_SPEED], p->max_wheel_speed_mm_s);
    for (unsigned t = 0U; t < ODO_TRUCKS; t++) {
        const odo_truck_params_t *tr = &p->truck[t];
        uint8_t *r = &buf[OFF_TRUCK0 + t * TRUCK_SIZE];
        put_u32(&r[TR_WHEEL_DIAMETER], tr->wheel_diameter_nm);
        put_u32(&r[TR_COUNTS_PER_REV], tr->counts_per_rev_milli);
        put_u32(&r[TR_WHEELBASE], tr->wheelbase_nm);
        put_i32(&r[TR_ED], tr->ed_q30);
        put_i32(&r[TR_EB], tr->eb_q30);
        put_i32(&r[TR_ES], tr->es_q30);
        r[TR_FLAGS] = tr->flags;
    }
    put_u32(&buf[OFF_LINK_LENGTH], p->link.length_nm);
    put_u32(&buf[OFF_HITCH_OFFSET], p->link.hitch_offset_nm);
    put_i32(&buf[OFF_LENGTH_BIAS], p->link.length_bias_nm);
    put_i32(&buf[OFF_LENGTH_ECC], p->link.length_ecc_nm);
    put_i32(&buf[OFF_ALPHA_BIAS], p->link.alpha_bias_bam);
    put_i32(&buf[OFF_BETA_BIAS], p->link.beta_bias_bam);
    buf[OFF_ROTARY_BITS] = p->link.rotary_bits;
    put_u16(&buf[OFF_STALE_TICKS], p->link.stale_ticks);
    put_u32(&buf[OFF_MAX_JUMP], p->link.max_jump_bam);
    put_u32(&buf[OFF_MAX_LENGTH_JUMP], p->link.max_length_jump_um);
    put_u32(&buf[OFF_LENGTH_MIN], p->link.length_min_um);
    put_u32(&buf[OFF_LENGTH_MAX], p->link.length_max_um);
    put_u32(&buf[ODO_PARAMS_CRC_OFFSET], odo_crc32(buf, ODO_PARAMS_CRC_OFFSET));
    return ODO_PARAMS_SIZE;
}

static bool all_zero(const uint8_t *b, size_t n)
{
    uint8_t acc = 0U;
    for (size_t i = 0U; i < n; i++) {
        acc |= b[i];
    }
    return acc == 0U;
}

odo_params_status_t odo_params_parse(const uint8_t *buf, size_t len, odo_params_t *out)
{
    odo_params_t p;

    if ((buf == NULL) || (out == NULL)) {
        return ODO_PARAMS_ERR_ARG;
    }
    if (len < HEADER_SIZE) {
        return ODO_PARAMS_ERR_SHORT;
    }
    if (get_u32(&buf[OFF_MAGIC]) != (uint32_t)ODO_PARAMS_MAGIC) {
        return ODO_PARAMS_ERR_MAGIC;
    }
    if (get_u16(&buf[OFF_VERSION]) != (uint16_t)ODO_PARAMS_VERSION) {
        return ODO_PARAMS_ERR_VERSION;
    }
    if (get_u16(&buf[OFF_LENGTH]) != (uint16_t)ODO_PARAMS_SIZE) {
        return ODO_PARAMS_ERR_LENGTH;
    }
    /* A flash region may be larger than the block; only the declared length is read. */
    if (len < ODO_PARAMS_SIZE) {
        return ODO_PARAMS_ERR_SHORT;
    }
    if (get_u32(&buf[ODO_PARAMS_CRC_OFFSET]) != odo_crc32(buf, ODO_PARAMS_CRC_OFFSET)) {
        return ODO_PARAMS_ERR_CRC;
    }

    memset(&p, 0, sizeof p);
    p.vehicle = buf[OFF_VEHICLE];
    p.counter_bits = buf[OFF_COUNTER_BITS];
    p.heading_form = buf[OFF_HEADING_FORM];
    p.ipec_mode = buf[OFF_IPEC_MODE];
    p.tick_us = get_u32(&buf[OFF_TICK_US]);
    p.max_wheel_speed_mm_s = get_u32(&buf[OFF_MAX_SPEED]);
    bool reserved_ok = all_zero(&buf[OFF_RESERVED_A], 1U) &&
                       all_zero(&buf[OFF_RESERVED_B], RESERVED_B_SIZE);
    for (unsigned t = 0U; t < ODO_TRUCKS; t++) {
        odo_truck_params_t *tr = &p.truck[t];
        const uint8_t *r = &buf[OFF_TRUCK0 + t * TRUCK_SIZE];
        tr->wheel_diameter_nm = get_u32(&r[TR_WHEEL_DIAMETER]);
        tr->counts_per_rev_milli = get_u32(&r[TR_COUNTS_PER_REV]);
        tr->wheelbase_nm = get_u32(&r[TR_WHEELBASE]);
        tr->ed_q30 = get_i32(&r[TR_ED]);
        tr->eb_q30 = get_i32(&r[TR_EB]);
        tr->es_q30 = get_i32(&r[TR_ES]);
        tr->flags = r[TR_FLAGS];
        reserved_ok = reserved_ok && all_zero(&r[TR_RESERVED], TR_RESERVED_SIZE);
    }
    p.link.length_nm = get_u32(&buf[OFF_LINK_LENGTH]);
    p.link.hitch_offset_nm = get_u32(&buf[OFF_HITCH_OFFSET]);
    p.link.length_bias_nm = get_i32(&buf[OFF_LENGTH_BIAS]);
    p.link.length_ecc_nm = get_i32(&buf[OFF_LENGTH_ECC]);
    p.link.alpha_bias_bam = get_i32(&buf[OFF_ALPHA_BIAS]);
    p.link.beta_bias_bam = get_i32(&buf[OFF_BETA_BIAS]);
    p.link.rotary_bits = buf[OFF_ROTARY_BITS];
    p.link.stale_ticks = get_u16(&buf[OFF_STALE_TICKS]);
    p.link.max_jump_bam = get_u32(&buf[OFF_MAX_JUMP]);
    p.link.max_length_jump_um = get_u32(&buf[OFF_MAX_LENGTH_JUMP]);
    p.link.length_min_um = get_u32(&buf[OFF_LENGTH_MIN]);
    p.link.length_max_um = get_u32(&buf[OFF_LENGTH_MAX]);

    *out = p;
    /* Non-zero reserved bytes mean a writer that knows a layout we do not: refuse, never guess. */
    return reserved_ok ? ODO_PARAMS_OK : ODO_PARAMS_ERR_RANGE;
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
    case ODO_PARAMS_OK:
        return "ok";
    case ODO_PARAMS_ERR_SHORT:
        return "block too short (fewer bytes than the header or the declared length)";
    case ODO_PARAMS_ERR_MAGIC:
        return "bad magic (not a parameter block)";
    case ODO_PARAMS_ERR_VERSION:
        return "unknown parameter block version";
    case ODO_PARAMS_ERR_LENGTH:
        return "declared length differs from this version's size";
    case ODO_PARAMS_ERR_CRC:
        return "CRC mismatch (corrupted in flash or in transit)";
    case ODO_PARAMS_ERR_RANGE:
        return "field out of range (or reserved byte non-zero)";
    case ODO_PARAMS_ERR_ARG:
        return "invalid argument (NULL pointer or buffer too small)";
    default:
        break;
    }
    return "unknown status";
}

const char *odo_params_field_name(odo_param_field_t f)
{
    switch (f) {
    case ODO_PF_NONE: return "none";
    case ODO_PF_VEHICLE: return "vehicle";
    case ODO_PF_COUNTER_BITS: return "counter_bits";
    case ODO_PF_HEADING_FORM: return "heading_form";
    case ODO_PF_IPEC_MODE: return "ipec_mode";
    case ODO_PF_TICK_US: return "tick_us";
    case ODO_PF_MAX_WHEEL_SPEED: return "max_wheel_speed_mm_s";
    case ODO_PF_WHEEL_DIAMETER: return "wheel_diameter_nm";
    case ODO_PF_COUNTS_PER_REV: return "counts_per_rev_milli";
    case ODO_PF_WHEELBASE: return "wheelbase_nm";
    case ODO_PF_ED: return "ed_q30";
    case ODO_PF_EB: return "eb_q30";
    case ODO_PF_ES: return "es_q30";
    case ODO_PF_TRUCK_FLAGS: return "flags";
    case ODO_PF_LINK_LENGTH: return "link.length_nm";
    case ODO_PF_HITCH_OFFSET: return "link.hitch_offset_nm";
    case ODO_PF_LENGTH_BIAS: return "link.length_bias_nm";
    case ODO_PF_LENGTH_ECC: return "link.length_ecc_nm";
    case ODO_PF_ALPHA_BIAS: return "link.alpha_bias_bam";
    case ODO_PF_BETA_BIAS: return "link.beta_bias_bam";
    case ODO_PF_ROTARY_BITS: return "link.rotary_bits";
    case ODO_PF_STALE_TICKS: return "link.stale_ticks";
    case ODO_PF_MAX_JUMP: return "link.max_jump_bam";
    case ODO_PF_MAX_LENGTH_JUMP: return "link.max_length_jump_um";
    case ODO_PF_LENGTH_RANGE: return "link.length_min_um/link.length_max_um";
    case ODO_PF_RESERVED: return "reserved";
    }
    return "unknown";
}
