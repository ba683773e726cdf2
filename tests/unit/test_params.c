/// Parameter block (DESIGN s. 4, odo/odo_params.h): the boot rule says a block is used only if magic,
/// version, length, CRC and every range check pass, and otherwise the documented defaults are. These
/// tests show each clause of that rule, with the header as the only source of the layout and ranges.
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "odo/odo_params.h"
#include "test_support.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

/* ---------------------------------------------------------------------------------------------
 * Helpers
 * ------------------------------------------------------------------------------------------- */
#define SENTINEL 0xA5U

static void put_u16le(uint8_t *b, uint16_t v)
{
    b[0] = (uint8_t)v;
    b[1] = (uint8_t)(v >> 8);
}

static void put_u32le(uint8_t *b, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        b[i] = (uint8_t)(v >> (8 * i));
    }
}

/// Recompute the trailing CRC so a deliberately wrong field reaches the check under test.
static void recrc(uint8_t *block) { put_u32le(&block[ODO_PARAMS_CRC_OFFSET], odo_crc32(block, ODO_PARAMS_CRC_OFFSET)); }

static void default_block(uint8_t block[ODO_PARAMS_SIZE])
{
    odo_params_t p;
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, block, ODO_PARAMS_SIZE));
}

static void fill_sentinel(odo_params_t *p) { memset(p, SENTINEL, sizeof *p); }

static void assert_untouched(const odo_params_t *p, const char *msg)
{
    odo_params_t s;
    fill_sentinel(&s);
    TEST_ASSERT_EQUAL_MEMORY_MESSAGE(&s, p, sizeof s, msg);
}

static void assert_params_equal(const odo_params_t *e, const odo_params_t *a)
{
    TEST_ASSERT_EQUAL_UINT8(e->vehicle, a->vehicle);
    TEST_ASSERT_EQUAL_UINT8(e->counter_bits, a->counter_bits);
    TEST_ASSERT_EQUAL_UINT8(e->heading_form, a->heading_form);
    TEST_ASSERT_EQUAL_UINT8(e->ipec_mode, a->ipec_mode);
    TEST_ASSERT_EQUAL_UINT32(e->tick_us, a->tick_us);
    TEST_ASSERT_EQUAL_UINT32(e->max_wheel_speed_mm_s, a->max_wheel_speed_mm_s);
    for (unsigned t = 0; t < ODO_TRUCKS; t++) {
        const odo_truck_params_t *et = &e->truck[t];
        const odo_truck_params_t *at = &a->truck[t];
        TEST_ASSERT_EQUAL_UINT32(et->wheel_diameter_nm, at->wheel_diameter_nm);
        TEST_ASSERT_EQUAL_UINT32(et->counts_per_rev_milli, at->counts_per_rev_milli);
        TEST_ASSERT_EQUAL_UINT32(et->wheelbase_nm, at->wheelbase_nm);
        TEST_ASSERT_EQUAL_INT32(et->ed_q30, at->ed_q30);
        TEST_ASSERT_EQUAL_INT32(et->eb_q30, at->eb_q30);
        TEST_ASSERT_EQUAL_INT32(et->es_q30, at->es_q30);
        TEST_ASSERT_EQUAL_INT32(et->scrub_q30, at->scrub_q30);
        TEST_ASSERT_EQUAL_UINT8(et->flags, at->flags);
    }
    TEST_ASSERT_EQUAL_UINT32(e->link.length_nm, a->link.length_nm);
    TEST_ASSERT_EQUAL_UINT32(e->link.hitch_offset_nm, a->link.hitch_offset_nm);
    TEST_ASSERT_EQUAL_INT32(e->link.length_bias_nm, a->link.length_bias_nm);
    TEST_ASSERT_EQUAL_INT32(e->link.length_ecc_nm, a->link.length_ecc_nm);
    TEST_ASSERT_EQUAL_INT32(e->link.alpha_bias_bam, a->link.alpha_bias_bam);
    TEST_ASSERT_EQUAL_INT32(e->link.beta_bias_bam, a->link.beta_bias_bam);
    TEST_ASSERT_EQUAL_UINT8(e->link.rotary_bits, a->link.rotary_bits);
    TEST_ASSERT_EQUAL_UINT16(e->link.stale_ticks, a->link.stale_ticks);
    TEST_ASSERT_EQUAL_UINT32(e->link.max_jump_bam, a->link.max_jump_bam);
    TEST_ASSERT_EQUAL_UINT32(e->link.max_length_jump_um, a->link.max_length_jump_um);
    TEST_ASSERT_EQUAL_UINT32(e->link.length_min_um, a->link.length_min_um);
    TEST_ASSERT_EQUAL_UINT32(e->link.length_max_um, a->link.length_max_um);
}

/* ---------------------------------------------------------------------------------------------
 * The documented ranges, written out again from the header comments (independent of the C
 * implementation's constants). Inclusive bounds; a bound beyond the field's type is clipped.
 * ------------------------------------------------------------------------------------------- */
typedef enum { K_U8, K_U16, K_U32, K_I32 } kind_t;

typedef struct {
    const char *name;
    odo_param_field_t field;
    bool in_truck; ///< offset is into odo_truck_params_t rather than odo_params_t
    size_t offset;
    kind_t kind;
    int64_t lo, hi;
} range_case_t;

#define NM_PER_MM  1000000LL
#define NM_PER_M   1000000000LL
#define Q30_0_8    ((((int64_t)4) << 30) / 5) /* 0.8 * 2^30 = 858993459.2, truncated */
#define Q30_1_25   ((((int64_t)5) << 30) / 4)
#define Q30_0_25   (((int64_t)1) << 28)
#define BAM_DEG(d) (((((int64_t)(d)) << 32) + 180) / 360) /* rounded to nearest */

#define TR(f)  true, offsetof(odo_truck_params_t, f)
#define TOP(f) false, offsetof(odo_params_t, f)

static const range_case_t k_ranges[] = {
    {"vehicle", ODO_PF_VEHICLE, TOP(vehicle), K_U8, 0, 2},
    {"counter_bits", ODO_PF_COUNTER_BITS, TOP(counter_bits), K_U8, 8, 32},
    {"heading_form", ODO_PF_HEADING_FORM, TOP(heading_form), K_U8, 0, 1},
    {"ipec_mode", ODO_PF_IPEC_MODE, TOP(ipec_mode), K_U8, 0, 2},
    {"tick_us", ODO_PF_TICK_US, TOP(tick_us), K_U32, 1000, 1000000},
    {"max_wheel_speed_mm_s", ODO_PF_MAX_WHEEL_SPEED, TOP(max_wheel_speed_mm_s), K_U32, 100, 20000},
    {"wheel_diameter_nm", ODO_PF_WHEEL_DIAMETER, TR(wheel_diameter_nm), K_U32, 10 * NM_PER_MM, 2 * NM_PER_M},
    {"counts_per_rev_milli", ODO_PF_COUNTS_PER_REV, TR(counts_per_rev_milli), K_U32, 100 * 1000, 4000000LL * 1000},
    {"wheelbase_nm", ODO_PF_WHEELBASE, TR(wheelbase_nm), K_U32, 50 * NM_PER_MM, 3 * NM_PER_M},
    {"ed_q30", ODO_PF_ED, TR(ed_q30), K_I32, Q30_0_8, Q30_1_25},
    {"eb_q30", ODO_PF_EB, TR(eb_q30), K_I32, Q30_0_8, Q30_1_25},
    {"es_q30", ODO_PF_ES, TR(es_q30), K_I32, Q30_0_8, Q30_1_25},
    {"scrub_q30", ODO_PF_SCRUB, TR(scrub_q30), K_I32, -Q30_0_25, Q30_0_25},
    {"link.length_nm", ODO_PF_LINK_LENGTH, TOP(link.length_nm), K_U32, 100 * NM_PER_MM, 4 * NM_PER_M},
    {"link.hitch_offset_nm", ODO_PF_HITCH_OFFSET, TOP(link.hitch_offset_nm), K_U32, 0, 4 * NM_PER_M},
    {"link.length_bias_nm", ODO_PF_LENGTH_BIAS, TOP(link.length_bias_nm), K_I32, -50 * NM_PER_MM, 50 * NM_PER_MM},
    {"link.length_ecc_nm", ODO_PF_LENGTH_ECC, TOP(link.length_ecc_nm), K_I32, -50 * NM_PER_MM, 50 * NM_PER_MM},
    {"link.alpha_bias_bam", ODO_PF_ALPHA_BIAS, TOP(link.alpha_bias_bam), K_I32, -BAM_DEG(10), BAM_DEG(10)},
    {"link.beta_bias_bam", ODO_PF_BETA_BIAS, TOP(link.beta_bias_bam), K_I32, -BAM_DEG(10), BAM_DEG(10)},
    {"link.rotary_bits", ODO_PF_ROTARY_BITS, TOP(link.rotary_bits), K_U8, 8, 16},
    {"link.stale_ticks", ODO_PF_STALE_TICKS, TOP(link.stale_ticks), K_U16, 1, 1000},
    {"link.max_jump_bam", ODO_PF_MAX_JUMP, TOP(link.max_jump_bam), K_U32, 1, BAM_DEG(90)},
    {"link.max_length_jump_um", ODO_PF_MAX_LENGTH_JUMP, TOP(link.max_length_jump_um), K_U32, 1, 1000000},
};
#define N_RANGES (sizeof k_ranges / sizeof k_ranges[0])

static int64_t type_min(kind_t k) { return k == K_I32 ? INT32_MIN : 0; }

static int64_t type_max(kind_t k)
{
    switch (k) {
    case K_U8: return UINT8_MAX;
    case K_U16: return UINT16_MAX;
    case K_U32: return UINT32_MAX;
    case K_I32: return INT32_MAX;
    }
    return 0;
}

static void set_field(odo_params_t *p, const range_case_t *c, unsigned truck, int64_t v)
{
    uint8_t *base = c->in_truck ? (uint8_t *)&p->truck[truck] : (uint8_t *)p;
    uint8_t *dst = base + c->offset;
    switch (c->kind) {
    case K_U8: {
        uint8_t x = (uint8_t)v;
        memcpy(dst, &x, sizeof x);
        break;
    }
    case K_U16: {
        uint16_t x = (uint16_t)v;
        memcpy(dst, &x, sizeof x);
        break;
    }
    case K_U32: {
        uint32_t x = (uint32_t)v;
        memcpy(dst, &x, sizeof x);
        break;
    }
    case K_I32: {
        int32_t x = (int32_t)v;
        memcpy(dst, &x, sizeof x);
        break;
    }
    }
}

/// Encode p (correct CRC), decode it, and check the status; on rejection also check that
/// odo_params_validate names `field` in `truck` and that decode left *out alone.
static void expect_block(const odo_params_t *p, odo_params_status_t want, odo_param_field_t field, uint8_t truck,
                         const char *what)
{
    uint8_t block[ODO_PARAMS_SIZE];
    odo_params_t out;
    odo_param_field_t got_field = ODO_PF_NONE;
    uint8_t got_truck = 0xFFU;

    TEST_ASSERT_EQUAL_size_t_MESSAGE(ODO_PARAMS_SIZE, odo_params_encode(p, block, sizeof block), what);
    fill_sentinel(&out);
    TEST_ASSERT_EQUAL_INT_MESSAGE(want, odo_params_decode(block, sizeof block, &out), what);
    TEST_ASSERT_EQUAL_INT_MESSAGE(want, odo_params_validate(p, &got_field, &got_truck), what);
    if (want == ODO_PARAMS_OK) {
        assert_params_equal(p, &out);
        TEST_ASSERT_EQUAL_INT_MESSAGE(ODO_PF_NONE, got_field, what);
    } else {
        assert_untouched(&out, what);
        TEST_ASSERT_EQUAL_INT_MESSAGE(field, got_field, what);
        TEST_ASSERT_EQUAL_UINT8_MESSAGE(truck, got_truck, what);
    }
}

static void random_valid(ts_rng_t *r, odo_params_t *p)
{
    odo_params_defaults(p);
    for (size_t i = 0; i < N_RANGES; i++) {
        const range_case_t *c = &k_ranges[i];
        int64_t hi = c->hi < type_max(c->kind) ? c->hi : type_max(c->kind);
        for (unsigned t = 0; t < (c->in_truck ? ODO_TRUCKS : 1U); t++) {
            set_field(p, c, t, ts_rng_range(r, c->lo, hi));
        }
    }
    for (unsigned t = 0; t < ODO_TRUCKS; t++) {
        p->truck[t].flags = (uint8_t)ts_rng_range(r, 0, ODO_TRUCK_INVERT_LEFT | ODO_TRUCK_INVERT_RIGHT);
    }
    p->link.length_min_um = (uint32_t)ts_rng_range(r, 1000, 20000000 - 1);
    p->link.length_max_um = (uint32_t)ts_rng_range(r, p->link.length_min_um + 1, 20000000);
}

/* ---------------------------------------------------------------------------------------------
 * Tests
 * ------------------------------------------------------------------------------------------- */

/// odo_params.h defaults: the labmate of 004 Table I / 002 s. 4.1, as the header documents them.
static void test_defaults_are_the_documented_labmate_and_validate(void)
{
    odo_params_t p;
    odo_param_field_t f = ODO_PF_TRUCK_FLAGS;
    uint8_t t = 7U;
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_validate(&p, &f, &t));
    TEST_ASSERT_EQUAL_INT(ODO_PF_NONE, f);
    TEST_ASSERT_EQUAL_UINT8(ODO_VEHICLE_SINGLE, p.vehicle);
    TEST_ASSERT_EQUAL_UINT8(24, p.counter_bits);
    TEST_ASSERT_EQUAL_UINT8(ODO_HEADING_MIDPOINT, p.heading_form);
    TEST_ASSERT_EQUAL_UINT8(ODO_IPEC_OFF, p.ipec_mode);
    TEST_ASSERT_EQUAL_UINT32(40000, p.tick_us);
    TEST_ASSERT_EQUAL_UINT32(3000, p.max_wheel_speed_mm_s);
    for (unsigned i = 0; i < ODO_TRUCKS; i++) {
        TEST_ASSERT_EQUAL_UINT32(150000000UL, p.truck[i].wheel_diameter_nm);
        TEST_ASSERT_EQUAL_UINT32(500UL * 4UL * 39UL / 2UL * 1000UL, p.truck[i].counts_per_rev_milli);
        TEST_ASSERT_EQUAL_UINT32(340000000UL, p.truck[i].wheelbase_nm);
        TEST_ASSERT_EQUAL_INT32(ODO_RATIO_Q30_ONE, p.truck[i].ed_q30);
        TEST_ASSERT_EQUAL_INT32(ODO_RATIO_Q30_ONE, p.truck[i].eb_q30);
        TEST_ASSERT_EQUAL_INT32(ODO_RATIO_Q30_ONE, p.truck[i].es_q30);
        TEST_ASSERT_EQUAL_UINT8(0, p.truck[i].flags);
    }
    TEST_ASSERT_EQUAL_UINT32(1000000000UL, p.link.length_nm);
    TEST_ASSERT_EQUAL_UINT32(0, p.link.hitch_offset_nm);
    TEST_ASSERT_EQUAL_INT32(0, p.link.length_bias_nm);
    TEST_ASSERT_EQUAL_INT32(0, p.link.length_ecc_nm);
    TEST_ASSERT_EQUAL_INT32(0, p.link.alpha_bias_bam);
    TEST_ASSERT_EQUAL_INT32(0, p.link.beta_bias_bam);
    TEST_ASSERT_EQUAL_UINT8(10, p.link.rotary_bits);
    TEST_ASSERT_EQUAL_UINT16(3, p.link.stale_ticks);
    TEST_ASSERT_EQUAL_UINT32(119304647UL, p.link.max_jump_bam); /* round(10/360 * 2^32) */
    TEST_ASSERT_EQUAL_UINT32((uint32_t)BAM_DEG(10), p.link.max_jump_bam);
    TEST_ASSERT_EQUAL_UINT32(20000, p.link.max_length_jump_um);
    TEST_ASSERT_EQUAL_UINT32(900000, p.link.length_min_um);
    TEST_ASSERT_EQUAL_UINT32(1100000, p.link.length_max_um);
}

/// CRC-32 as zlib: the catalogue check value of "123456789" (IEEE 802.3, reflected, xorout ~0).
static void test_crc32_of_123456789_is_the_standard_check_value(void)
{
    const uint8_t msg[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926UL, odo_crc32(msg, sizeof msg));
    TEST_ASSERT_EQUAL_HEX32(0x00000000UL, odo_crc32(msg, 0));
    TEST_ASSERT_EQUAL_HEX32(0x00000000UL, odo_crc32(NULL, 0));
    const uint8_t a = 'a';
    TEST_ASSERT_EQUAL_HEX32(0xE8B7BE43UL, odo_crc32(&a, 1));
}

/// Header layout: magic 'ODOP', version 2, length 256, CRC of [0, 252) little-endian at 252.
static void test_encoded_header_and_crc_sit_where_the_layout_table_says(void)
{
    uint8_t b[ODO_PARAMS_SIZE];
    odo_params_t p;
    odo_params_defaults(&p);
    p.truck[1].scrub_q30 = -0x01020304;
    TEST_ASSERT_EQUAL_size_t(256, odo_params_encode(&p, b, sizeof b));
    TEST_ASSERT_EQUAL_MEMORY("ODOP", b, 4);
    TEST_ASSERT_EQUAL_HEX8(2, b[4]);
    TEST_ASSERT_EQUAL_HEX8(0, b[5]);
    TEST_ASSERT_EQUAL_HEX8(0, b[6]); /* 256 = 0x0100 */
    TEST_ASSERT_EQUAL_HEX8(1, b[7]);
    uint32_t crc = odo_crc32(b, 252);
    TEST_ASSERT_EQUAL_HEX8((uint8_t)crc, b[252]);
    TEST_ASSERT_EQUAL_HEX8((uint8_t)(crc >> 8), b[253]);
    TEST_ASSERT_EQUAL_HEX8((uint8_t)(crc >> 16), b[254]);
    TEST_ASSERT_EQUAL_HEX8((uint8_t)(crc >> 24), b[255]);
    /* A sample of little-endian fields: tick_us at 12, link.stale_ticks at 102, truck B Ed at 60,
     * truck B's scrub at 128 (two's complement of 0x01020304 = 0xFEFDFCFC). */
    TEST_ASSERT_EQUAL_HEX8(0x40, b[12]); /* 40000 = 0x9C40 */
    TEST_ASSERT_EQUAL_HEX8(0x9C, b[13]);
    TEST_ASSERT_EQUAL_HEX8(3, b[102]);
    TEST_ASSERT_EQUAL_HEX8(0x40, b[48 + 12 + 3]); /* 2^30 = 0x40000000 */
    TEST_ASSERT_EQUAL_HEX8(0xFC, b[128]);
    TEST_ASSERT_EQUAL_HEX8(0xFC, b[129]);
    TEST_ASSERT_EQUAL_HEX8(0xFD, b[130]);
    TEST_ASSERT_EQUAL_HEX8(0xFE, b[131]);
    TEST_ASSERT_EQUAL_HEX32(0, (uint32_t)b[124] | b[125] | b[126] | b[127]); /* truck A's scrub: 0 */
}

/// Round trip, defaults: decode(encode(p)) == p field for field.
static void test_round_trip_of_defaults_is_field_for_field_equal(void)
{
    odo_params_t p, out;
    uint8_t b[ODO_PARAMS_SIZE];
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, b, sizeof b));
    fill_sentinel(&out);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_decode(b, sizeof b, &out));
    assert_params_equal(&p, &out);
}

/// Round trip, randomised valid blocks: every field anywhere in its range survives, sign included.
static void test_round_trip_of_random_valid_blocks_is_field_for_field_equal(void)
{
    ts_rng_t r;
    ts_rng_seed(&r, 0x0D0A5EEDULL);
    for (int i = 0; i < 2000; i++) {
        odo_params_t p, out;
        uint8_t b[ODO_PARAMS_SIZE];
        random_valid(&r, &p);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_validate(&p, NULL, NULL));
        TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, b, sizeof b));
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_decode(b, sizeof b, &out));
        assert_params_equal(&p, &out);
    }
}

/// A flash region larger than the block: only the declared 128 bytes are read.
static void test_trailing_bytes_after_the_declared_length_are_ignored(void)
{
    uint8_t b[ODO_PARAMS_SIZE + 64];
    odo_params_t p, out;
    memset(b, 0xFF, sizeof b); /* erased flash */
    default_block(b);
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_decode(b, sizeof b, &out));
    assert_params_equal(&p, &out);
}

/// CRC-32 detects every single-bit error: each of the 2048 flips is rejected, by the header check
/// that sees it first or by the CRC, and *out is never written.
static void test_every_single_bit_flip_is_rejected_and_out_is_untouched(void)
{
    uint8_t good[ODO_PARAMS_SIZE];
    default_block(good);
    for (unsigned i = 0; i < ODO_PARAMS_SIZE; i++) {
        for (unsigned bit = 0; bit < 8; bit++) {
            uint8_t b[ODO_PARAMS_SIZE];
            odo_params_t out;
            char msg[48];
            odo_params_status_t want = i < 4   ? ODO_PARAMS_ERR_MAGIC
                                       : i < 6 ? ODO_PARAMS_ERR_VERSION
                                       : i < 8 ? ODO_PARAMS_ERR_LENGTH
                                               : ODO_PARAMS_ERR_CRC;
            memcpy(b, good, sizeof b);
            b[i] ^= (uint8_t)(1U << bit);
            snprintf(msg, sizeof msg, "byte %u bit %u", i, bit);
            fill_sentinel(&out);
            TEST_ASSERT_EQUAL_INT_MESSAGE(want, odo_params_decode(b, sizeof b, &out), msg);
            assert_untouched(&out, msg);
        }
    }
}

/// ERR_SHORT for every length below the block, from an empty read up to one byte missing.
static void test_truncated_blocks_of_every_length_are_short(void)
{
    uint8_t b[ODO_PARAMS_SIZE];
    default_block(b);
    for (size_t len = 0; len < ODO_PARAMS_SIZE; len++) {
        odo_params_t out;
        char msg[32];
        snprintf(msg, sizeof msg, "len %u", (unsigned)len);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT_MESSAGE(ODO_PARAMS_ERR_SHORT, odo_params_decode(b, len, &out), msg);
        assert_untouched(&out, msg);
    }
}

static void test_wrong_magic_is_not_a_parameter_block(void)
{
    static const char *const magics[] = {"PODO", "odop", "ODOQ", "\0\0\0\0", "\xFF\xFF\xFF\xFF"};
    for (size_t m = 0; m < sizeof magics / sizeof magics[0]; m++) {
        uint8_t b[ODO_PARAMS_SIZE];
        odo_params_t out;
        default_block(b);
        memcpy(b, magics[m], 4);
        recrc(b);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_MAGIC, odo_params_decode(b, sizeof b, &out));
        assert_untouched(&out, "magic");
    }
}

/// A block from another firmware generation is refused even though its CRC is right.
static void test_unknown_version_is_refused_even_with_a_correct_crc(void)
{
    static const uint16_t versions[] = {0U, 3U, 0xFFFFU};
    for (size_t v = 0; v < sizeof versions / sizeof versions[0]; v++) {
        uint8_t b[ODO_PARAMS_SIZE];
        odo_params_t out;
        default_block(b);
        put_u16le(&b[4], versions[v]);
        recrc(b);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_VERSION, odo_params_decode(b, sizeof b, &out));
        assert_untouched(&out, "version");
    }
}

static void test_wrong_length_field_is_refused_even_with_a_correct_crc(void)
{
    static const uint16_t lengths[] = {0U, 8U, 128U, 252U, 255U, 257U, 512U, 0xFFFFU};
    for (size_t l = 0; l < sizeof lengths / sizeof lengths[0]; l++) {
        uint8_t b[ODO_PARAMS_SIZE];
        odo_params_t out;
        default_block(b);
        put_u16le(&b[6], lengths[l]);
        recrc(b);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_LENGTH, odo_params_decode(b, sizeof b, &out));
        assert_untouched(&out, "length");
    }
}

/// Every documented range, both ends: one step outside is ERR_RANGE naming the field (and the
/// truck, for both records), the bound itself is accepted. A bound beyond what the field's type can
/// hold cannot be crossed; there the type's limit is checked as accepted.
static void test_each_range_rejects_just_outside_and_accepts_just_inside(void)
{
    for (size_t i = 0; i < N_RANGES; i++) {
        const range_case_t *c = &k_ranges[i];
        for (unsigned t = 0; t < (c->in_truck ? ODO_TRUCKS : 1U); t++) {
            const int64_t ends[2] = {c->lo, c->hi};
            const int64_t steps[2] = {-1, +1};
            for (int e = 0; e < 2; e++) {
                odo_params_t p;
                char msg[96];
                int64_t inside = ends[e];
                int64_t outside = ends[e] + steps[e];
                if (inside > type_max(c->kind)) {
                    inside = type_max(c->kind);
                }
                odo_params_defaults(&p);
                set_field(&p, c, t, inside);
                snprintf(msg, sizeof msg, "%s truck %u = %lld (inside)", c->name, t, (long long)inside);
                expect_block(&p, ODO_PARAMS_OK, ODO_PF_NONE, 0, msg);
                if (outside < type_min(c->kind) || outside > type_max(c->kind)) {
                    continue;
                }
                odo_params_defaults(&p);
                set_field(&p, c, t, outside);
                snprintf(msg, sizeof msg, "%s truck %u = %lld (outside)", c->name, t, (long long)outside);
                expect_block(&p, ODO_PARAMS_ERR_RANGE, c->field, c->in_truck ? (uint8_t)t : 0U, msg);
            }
        }
    }
}

/// Signed ranges are symmetric: the most negative int32 must not slip through an abs() overflow.
static void test_int32_min_is_out_of_every_signed_range(void)
{
    for (size_t i = 0; i < N_RANGES; i++) {
        const range_case_t *c = &k_ranges[i];
        if (c->kind != K_I32) {
            continue;
        }
        odo_params_t p;
        odo_params_defaults(&p);
        set_field(&p, c, 0, INT32_MIN);
        expect_block(&p, ODO_PARAMS_ERR_RANGE, c->field, 0, c->name);
        odo_params_defaults(&p);
        set_field(&p, c, 0, INT32_MAX);
        expect_block(&p, ODO_PARAMS_ERR_RANGE, c->field, 0, c->name);
    }
}

/// counter_bits: any width a real decoder has, 8 to 32 bits (the OptiOdom robot's is 12).
static void test_counter_bits_accepts_every_width_from_8_to_32(void)
{
    for (unsigned v = 0; v <= 255; v++) {
        odo_params_t p;
        char msg[32];
        odo_params_defaults(&p);
        p.counter_bits = (uint8_t)v;
        snprintf(msg, sizeof msg, "counter_bits %u", v);
        if (v >= 8 && v <= 32) {
            expect_block(&p, ODO_PARAMS_OK, ODO_PF_NONE, 0, msg);
        } else {
            expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_COUNTER_BITS, 0, msg);
        }
    }
}

/// Truck flags: only the two invert bits are defined; any other bit is refused, in either record.
static void test_truck_flags_accept_only_the_invert_bits(void)
{
    for (unsigned t = 0; t < ODO_TRUCKS; t++) {
        for (unsigned v = 0; v <= 255; v++) {
            odo_params_t p;
            char msg[32];
            odo_params_defaults(&p);
            p.truck[t].flags = (uint8_t)v;
            snprintf(msg, sizeof msg, "truck %u flags 0x%02X", t, v);
            if ((v & ~(ODO_TRUCK_INVERT_LEFT | ODO_TRUCK_INVERT_RIGHT)) == 0U) {
                expect_block(&p, ODO_PARAMS_OK, ODO_PF_NONE, 0, msg);
            } else {
                expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_TRUCK_FLAGS, (uint8_t)t, msg);
            }
        }
    }
}

/// Linkage length limits: min < max, both within [1 mm, 20 m]; a bound outside names its own
/// field, an inverted or empty pair names the pair.
static void test_length_limits_must_be_ordered_and_within_1mm_to_20m(void)
{
    static const struct {
        uint32_t min_um, max_um;
        odo_param_field_t bad;
    } cases[] = {
        {1000, 20000000, ODO_PF_NONE},
        {999, 20000000, ODO_PF_LENGTH_MIN},
        {1000, 20000001, ODO_PF_LENGTH_MAX},
        {1000, 1001, ODO_PF_NONE},
        {1000, 1000, ODO_PF_LENGTH_RANGE},
        {1100000, 900000, ODO_PF_LENGTH_RANGE},
        {19999999, 20000000, ODO_PF_NONE},
        {20000000, 20000000, ODO_PF_LENGTH_RANGE},
        {0, 1000, ODO_PF_LENGTH_MIN},
        {999, 1000, ODO_PF_LENGTH_MIN},
        {20000001, 20000000, ODO_PF_LENGTH_MIN},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        odo_params_t p;
        char msg[64];
        odo_params_defaults(&p);
        p.link.length_min_um = cases[i].min_um;
        p.link.length_max_um = cases[i].max_um;
        snprintf(msg, sizeof msg, "min %lu max %lu", (unsigned long)cases[i].min_um, (unsigned long)cases[i].max_um);
        expect_block(&p, cases[i].bad == ODO_PF_NONE ? ODO_PARAMS_OK : ODO_PARAMS_ERR_RANGE, cases[i].bad, 0, msg);
    }
}

/// The unused truck B record of a single-truck vehicle is still checked, and named as truck 1.
static void test_unused_truck_record_must_still_be_sane(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL_UINT8(ODO_VEHICLE_SINGLE, p.vehicle);
    p.truck[1].wheelbase_nm = 0U;
    expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_WHEELBASE, 1, "truck B wheelbase 0");
    memset(&p.truck[1], 0, sizeof p.truck[1]);
    expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_WHEEL_DIAMETER, 1, "truck B all zero");
}

/// With several bad fields, validate names the first in layout order.
static void test_validate_names_the_first_offending_field(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.link.rotary_bits = 0U;
    p.truck[1].es_q30 = 0;
    p.truck[0].flags = 0x80U;
    expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_TRUCK_FLAGS, 0, "truck A flags first");
    p.truck[0].flags = 0U;
    expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_ES, 1, "then truck B Es");
    p.truck[1].es_q30 = ODO_RATIO_Q30_ONE;
    expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_ROTARY_BITS, 0, "then the link");
    p.tick_us = 0U;
    expect_block(&p, ODO_PARAMS_ERR_RANGE, ODO_PF_TICK_US, 0, "header fields before records");
}

/// The reserved bytes of the header's table (25..27 of each truck record, 101, 120..123, and
/// version 2's tail 132..251), written out again here.
static bool is_reserved_v2(unsigned i)
{
    return (i >= 20 + 25 && i <= 20 + 27) || (i >= 48 + 25 && i <= 48 + 27) || i == 101 || (i >= 120 && i <= 123) ||
           (i >= 132 && i <= 251);
}

/// Reserved bytes must be 0: a non-zero one means a writer that knows a layout this firmware does
/// not. Each is refused, and odo_params_reserved_offset names it; no other byte is reserved.
static void test_nonzero_reserved_bytes_are_out_of_range(void)
{
    unsigned n_reserved = 0;
    for (unsigned i = 0; i < ODO_PARAMS_CRC_OFFSET; i++) {
        static const uint8_t vals[] = {0x01U, 0x80U, 0xFFU};
        for (size_t v = 0; v < sizeof vals; v++) {
            uint8_t b[ODO_PARAMS_SIZE];
            odo_params_t out;
            char msg[48];
            default_block(b);
            b[i] ^= vals[v];
            recrc(b);
            snprintf(msg, sizeof msg, "byte %u ^= 0x%02X", i, vals[v]);
            fill_sentinel(&out);
            const odo_params_status_t st = odo_params_decode(b, sizeof b, &out);
            if (is_reserved_v2(i)) {
                TEST_ASSERT_EQUAL_INT_MESSAGE(ODO_PARAMS_ERR_RANGE, st, msg);
                TEST_ASSERT_EQUAL_size_t_MESSAGE(i, odo_params_reserved_offset(b, sizeof b), msg);
                assert_untouched(&out, msg);
            } else {
                TEST_ASSERT_EQUAL_size_t_MESSAGE(0, odo_params_reserved_offset(b, sizeof b), msg);
            }
        }
        n_reserved += is_reserved_v2(i) ? 1U : 0U;
    }
    TEST_ASSERT_EQUAL_UINT(6 + 1 + 4 + 120, n_reserved);
    uint8_t b[ODO_PARAMS_SIZE];
    default_block(b);
    TEST_ASSERT_EQUAL_size_t(0, odo_params_reserved_offset(b, sizeof b));
    TEST_ASSERT_EQUAL_size_t(0, odo_params_reserved_offset(b, sizeof b - 1)); /* short: not judged */
    TEST_ASSERT_EQUAL_size_t(0, odo_params_reserved_offset(NULL, sizeof b));
}

/// Boot rule: any rejected block gives exactly the defaults, and load reports why.
static void test_load_falls_back_to_exactly_the_defaults_and_reports_why(void)
{
    odo_params_t defaults, out;
    uint8_t good[ODO_PARAMS_SIZE];
    odo_params_defaults(&defaults);
    {
        /* A valid, non-default block is taken as it is. */
        odo_params_t p = defaults;
        p.vehicle = ODO_VEHICLE_CLAPPER;
        p.truck[0].ed_q30 = ODO_RATIO_Q30_ONE + 12345;
        TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, good, sizeof good));
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_load(good, sizeof good, &out));
        assert_params_equal(&p, &out);
    }
    struct {
        const char *what;
        unsigned off; /* byte to change, or ~0 for none */
        uint8_t xor_;
        bool fix_crc;
        size_t len;
        odo_params_status_t want;
    } cases[] = {
        {"erased flash", ~0U, 0, false, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_MAGIC},
        {"short", ~0U, 0, false, 64, ODO_PARAMS_ERR_SHORT},
        {"magic", 0, 0x01, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_MAGIC},
        {"version", 4, 0x01, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_VERSION},
        {"length", 6, 0x01, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_LENGTH},
        {"crc", 40, 0x10, false, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_CRC},
        {"range", 9, 0x30, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_RANGE},
        {"reserved", 101, 0x01, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_RANGE},
        {"reserved tail", 200, 0x01, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_RANGE},
        {"scrub out of range", 127, 0x40, true, ODO_PARAMS_SIZE, ODO_PARAMS_ERR_RANGE},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        uint8_t b[ODO_PARAMS_SIZE];
        memcpy(b, good, sizeof b);
        if (i == 0) {
            memset(b, 0xFF, sizeof b);
        } else if (cases[i].off != ~0U) {
            b[cases[i].off] ^= cases[i].xor_;
        }
        if (cases[i].fix_crc) {
            recrc(b);
        }
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT_MESSAGE(cases[i].want, odo_params_load(b, cases[i].len, &out), cases[i].what);
        assert_params_equal(&defaults, &out);
    }
    fill_sentinel(&out);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_ARG, odo_params_load(NULL, ODO_PARAMS_SIZE, &out));
    assert_params_equal(&defaults, &out);
}

static void test_null_arguments_are_err_arg_never_a_crash(void)
{
    uint8_t b[ODO_PARAMS_SIZE];
    odo_params_t p;
    default_block(b);
    odo_params_defaults(&p);
    odo_params_defaults(NULL);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_ARG, odo_params_decode(NULL, ODO_PARAMS_SIZE, &p));
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_ARG, odo_params_decode(b, sizeof b, NULL));
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_ARG, odo_params_decode(NULL, 0, NULL));
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_ARG, odo_params_load(b, sizeof b, NULL));
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_ARG, odo_params_validate(NULL, NULL, NULL));
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_validate(&p, NULL, NULL));
    TEST_ASSERT_EQUAL_size_t(0, odo_params_encode(NULL, b, sizeof b));
    TEST_ASSERT_EQUAL_size_t(0, odo_params_encode(&p, NULL, ODO_PARAMS_SIZE));
}

/// Encode never writes past cap: too small a buffer returns 0 and is left alone.
static void test_encode_into_too_small_a_buffer_returns_0_and_writes_nothing(void)
{
    odo_params_t p;
    uint8_t b[ODO_PARAMS_SIZE + 8];
    odo_params_defaults(&p);
    for (size_t cap = 0; cap < ODO_PARAMS_SIZE; cap++) {
        memset(b, SENTINEL, sizeof b);
        TEST_ASSERT_EQUAL_size_t(0, odo_params_encode(&p, b, cap));
        for (size_t i = 0; i < sizeof b; i++) {
            TEST_ASSERT_EQUAL_HEX8(SENTINEL, b[i]);
        }
    }
    memset(b, SENTINEL, sizeof b);
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, b, sizeof b));
    for (size_t i = ODO_PARAMS_SIZE; i < sizeof b; i++) {
        TEST_ASSERT_EQUAL_HEX8(SENTINEL, b[i]);
    }
}

static void test_every_status_has_distinct_text_and_crc_names_the_crc(void)
{
    static const odo_params_status_t all[] = {ODO_PARAMS_OK,          ODO_PARAMS_ERR_SHORT,  ODO_PARAMS_ERR_MAGIC,
                                              ODO_PARAMS_ERR_VERSION, ODO_PARAMS_ERR_LENGTH, ODO_PARAMS_ERR_CRC,
                                              ODO_PARAMS_ERR_RANGE,   ODO_PARAMS_ERR_ARG};
    const size_t n = sizeof all / sizeof all[0];
    for (size_t i = 0; i < n; i++) {
        TEST_ASSERT_NOT_NULL(odo_params_status_str(all[i]));
        for (size_t j = 0; j < i; j++) {
            TEST_ASSERT_TRUE(strcmp(odo_params_status_str(all[i]), odo_params_status_str(all[j])) != 0);
        }
    }
    TEST_ASSERT_NOT_NULL(strstr(odo_params_status_str(ODO_PARAMS_ERR_CRC), "CRC"));
    TEST_ASSERT_NOT_NULL(odo_params_status_str((odo_params_status_t)99));
}

/// odo_params_parse reads a block whose header and CRC are good without judging its ranges, so a
/// tool can name the bad field; decode is parse + validate and writes nothing on failure.
static void parse_reads_out_of_range_fields_that_decode_refuses(void)
{
    odo_params_t p, got, untouched;
    odo_params_defaults(&p);
    p.truck[1].wheelbase_nm = 1U; /* below 50 mm */
    uint8_t block[ODO_PARAMS_SIZE];
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, block, sizeof block));
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_params_parse(block, sizeof block, &got));
    TEST_ASSERT_EQUAL_UINT32(1U, got.truck[1].wheelbase_nm);
    odo_param_field_t f = ODO_PF_NONE;
    uint8_t t = 0U;
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_RANGE, odo_params_validate(&got, &f, &t));
    TEST_ASSERT_EQUAL(ODO_PF_WHEELBASE, f);
    TEST_ASSERT_EQUAL_UINT8(1U, t);
    memset(&untouched, 0xA5, sizeof untouched);
    got = untouched;
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_RANGE, odo_params_decode(block, sizeof block, &got));
    TEST_ASSERT_EQUAL_MEMORY(&untouched, &got, sizeof got);

    /* A non-zero reserved byte: parse reports it but still hands back the fields. */
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, block, sizeof block));
    block[101] = 0x01U;
    const uint32_t crc = odo_crc32(block, ODO_PARAMS_CRC_OFFSET);
    for (unsigned i = 0U; i < 4U; ++i) {
        block[ODO_PARAMS_CRC_OFFSET + i] = (uint8_t)(crc >> (8U * i));
    }
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_RANGE, odo_params_parse(block, sizeof block, &got));
    TEST_ASSERT_EQUAL_UINT32(p.truck[0].wheelbase_nm, got.truck[0].wheelbase_nm);
    /* header errors leave the output alone */
    got = untouched;
    block[0] = 'X';
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_MAGIC, odo_params_parse(block, sizeof block, &got));
    TEST_ASSERT_EQUAL_MEMORY(&untouched, &got, sizeof got);
}

/* ---------------------------------------------------------------------------------------------
 * Version 1 (128 bytes): still read, with scrub_q30 = 0.
 * ------------------------------------------------------------------------------------------- */

/// A version-1 block as firmware before version 2 wrote it: the header's statement that bytes
/// [8, 124) mean the same in both versions, applied by hand (version 1, length 128, CRC-32 of
/// [0, 124) at 124).
static void v1_block_of(const odo_params_t *p, uint8_t b[ODO_PARAMS_V1_SIZE])
{
    uint8_t v2[ODO_PARAMS_SIZE];
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(p, v2, sizeof v2));
    memcpy(b, v2, 124);
    put_u16le(&b[4], 1U);
    put_u16le(&b[6], 128U);
    put_u32le(&b[124], odo_crc32(b, 124));
}

/// Every path the boot rule takes reads a version-1 block, field for field, with no scrub term.
static void version_1_block_loads_with_scrub_0(void)
{
    ts_rng_t r;
    ts_rng_seed(&r, 0x0001B10CULL);
    for (int i = 0; i < 200; i++) {
        odo_params_t p, out;
        uint8_t b[ODO_PARAMS_V1_SIZE];
        random_valid(&r, &p);
        p.truck[0].scrub_q30 = 0;
        p.truck[1].scrub_q30 = 0;
        v1_block_of(&p, b);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_parse(b, sizeof b, &out));
        assert_params_equal(&p, &out);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_decode(b, sizeof b, &out));
        assert_params_equal(&p, &out);
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_load(b, sizeof b, &out));
        assert_params_equal(&p, &out);
        /* re-encoding upgrades it: the same fields as a version-2 block */
        uint8_t v2[ODO_PARAMS_SIZE];
        TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&out, v2, sizeof v2));
        TEST_ASSERT_EQUAL_MEMORY(&b[8], &v2[8], 124 - 8);
        TEST_ASSERT_EQUAL_HEX8(2, v2[4]);
    }
    /* in a larger flash region (erased after it), only its own 128 bytes are read */
    odo_params_t p, out;
    uint8_t region[ODO_PARAMS_SIZE + 16];
    memset(region, 0xFF, sizeof region);
    odo_params_defaults(&p);
    p.truck[0].ed_q30 = ODO_RATIO_Q30_ONE + 777;
    v1_block_of(&p, region);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_decode(region, sizeof region, &out));
    assert_params_equal(&p, &out);
    TEST_ASSERT_EQUAL_INT32(0, out.truck[0].scrub_q30);
}

/// Version 1's own refusals: its length must be 128, all 128 bytes must be there, its CRC sits at
/// 124 (where version 2 keeps truck A's scrub), and its reserved bytes are still reserved.
static void version_1_block_refusals(void)
{
    odo_params_t p, out;
    uint8_t good[ODO_PARAMS_V1_SIZE], b[ODO_PARAMS_V1_SIZE];
    odo_params_defaults(&p);
    v1_block_of(&p, good);

    memcpy(b, good, sizeof b);
    put_u16le(&b[6], 256U); /* a version-1 header claiming version 2's size */
    put_u32le(&b[124], odo_crc32(b, 124));
    fill_sentinel(&out);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_LENGTH, odo_params_decode(b, sizeof b, &out));
    assert_untouched(&out, "v1 length 256");

    for (size_t len = 8; len < ODO_PARAMS_V1_SIZE; len++) {
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_SHORT, odo_params_decode(good, len, &out));
    }

    memcpy(b, good, sizeof b);
    b[124] ^= 0x01U; /* the CRC, not a field */
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_CRC, odo_params_decode(b, sizeof b, &out));

    for (unsigned i = 120; i < 124; i++) {
        memcpy(b, good, sizeof b);
        b[i] = 0x5AU;
        put_u32le(&b[124], odo_crc32(b, 124));
        fill_sentinel(&out);
        TEST_ASSERT_EQUAL_INT(ODO_PARAMS_ERR_RANGE, odo_params_decode(b, sizeof b, &out));
        TEST_ASSERT_EQUAL_size_t(i, odo_params_reserved_offset(b, sizeof b));
        assert_untouched(&out, "v1 reserved");
    }

    /* A version-2 block relabelled as version 1 (length and CRC adjusted) is judged as
     * version 1: bytes 124..127 are its CRC. */
    uint8_t v2[ODO_PARAMS_SIZE];
    default_block(v2);
    put_u16le(&v2[4], 1U);
    put_u16le(&v2[6], 128U);
    put_u32le(&v2[124], odo_crc32(v2, 124));
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_decode(v2, sizeof v2, &out));

    TEST_ASSERT_EQUAL_size_t(128, odo_params_version_size(1));
    TEST_ASSERT_EQUAL_size_t(256, odo_params_version_size(2));
    TEST_ASSERT_EQUAL_size_t(0, odo_params_version_size(0));
    TEST_ASSERT_EQUAL_size_t(0, odo_params_version_size(3));
}

/* ---------------------------------------------------------------------------------------------
 * The field table (ODO_PARAMS_FIELDS) and what is expanded from it.
 * ------------------------------------------------------------------------------------------- */

/// Every field sits inside the block of the first version that carries it, no two fields (or a
/// field and the header or CRC) share a byte, ids run in table order, and names are unique and are
/// what odo_params_field_name says.
static void field_table_is_a_partition_of_the_block(void)
{
    uint8_t owner[ODO_PARAMS_SIZE];
    memset(owner, 0, sizeof owner);
    memset(owner, 0xFF, 8);                         /* header */
    memset(&owner[ODO_PARAMS_CRC_OFFSET], 0xFF, 4); /* CRC */
    const size_t n = odo_params_field_count();
    TEST_ASSERT_TRUE(n > 20 && n < 0xFF);
    TEST_ASSERT_NULL(odo_params_field_at(n));
    TEST_ASSERT_NULL(odo_params_field_info(ODO_PF_NONE));
    TEST_ASSERT_NULL(odo_params_field_info(ODO_PF_LENGTH_RANGE));
    TEST_ASSERT_NULL(odo_params_field_info(ODO_PF_RESERVED));
    for (size_t i = 0; i < n; i++) {
        const odo_param_field_info_t *f = odo_params_field_at(i);
        TEST_ASSERT_NOT_NULL(f);
        TEST_ASSERT_EQUAL_UINT(i + 1, f->id);
        TEST_ASSERT_EQUAL_PTR(f, odo_params_field_info((odo_param_field_t)f->id));
        TEST_ASSERT_EQUAL_STRING(f->name, odo_params_field_name((odo_param_field_t)f->id));
        TEST_ASSERT_EQUAL_UINT(f->type == ODO_PTYPE_U8 ? 1 : f->type == ODO_PTYPE_U16 ? 2 : 4, f->width);
        TEST_ASSERT_EQUAL(f->scope == ODO_PSCOPE_TRUCK, odo_params_field_is_truck((odo_param_field_t)f->id));
        TEST_ASSERT_EQUAL(f->scope == ODO_PSCOPE_LINK, strncmp(f->name, "link.", 5) == 0);
        const unsigned end = f->since == 1 ? 124U : 252U;
        for (unsigned t = 0; t < (f->scope == ODO_PSCOPE_TRUCK ? ODO_TRUCKS : 1U); t++) {
            for (unsigned k = 0; k < f->width; k++) {
                const unsigned at = f->offset + t * f->stride + k;
                TEST_ASSERT_TRUE_MESSAGE(at >= 8 && at < end, f->name);
                TEST_ASSERT_EQUAL_HEX8_MESSAGE(0, owner[at], f->name);
                owner[at] = (uint8_t)f->id;
            }
        }
        for (size_t j = 0; j < i; j++) {
            TEST_ASSERT_TRUE(strcmp(odo_params_field_at(j)->name, f->name) != 0);
        }
    }
    /* what no field owns is exactly what the header calls reserved */
    for (unsigned i = 8; i < ODO_PARAMS_CRC_OFFSET; i++) {
        TEST_ASSERT_EQUAL_MESSAGE(is_reserved_v2(i), owner[i] == 0, "byte owned iff not reserved");
    }
    TEST_ASSERT_EQUAL_STRING("scrub_q30", odo_params_field_name(ODO_PF_SCRUB));
    TEST_ASSERT_EQUAL_STRING("link.length_min_um/link.length_max_um", odo_params_field_name(ODO_PF_LENGTH_RANGE));
    TEST_ASSERT_EQUAL_STRING("reserved", odo_params_field_name(ODO_PF_RESERVED));
    TEST_ASSERT_EQUAL_STRING("none", odo_params_field_name(ODO_PF_NONE));
    TEST_ASSERT_EQUAL_STRING("unknown", odo_params_field_name((odo_param_field_t)200));
}

/// The encoder puts each field where the table says: a distinct value per field and truck, read
/// back little-endian from the table's offset, and odo_params_get/set agree with the members.
static void encoder_puts_every_field_at_its_table_offset(void)
{
    odo_params_t p;
    memset(&p, 0, sizeof p);
    for (size_t i = 0; i < odo_params_field_count(); i++) {
        const odo_param_field_info_t *f = odo_params_field_at(i);
        for (uint8_t t = 0; t < ODO_TRUCKS; t++) {
            const int64_t v = (int64_t)(0x11 * (i + 1) + t) * (f->type == ODO_PTYPE_I32 ? -1 : 1);
            TEST_ASSERT_TRUE(odo_params_set(&p, (odo_param_field_t)f->id, t, v));
        }
    }
    TEST_ASSERT_FALSE(odo_params_set(&p, ODO_PF_NONE, 0, 1));
    TEST_ASSERT_FALSE(odo_params_set(&p, ODO_PF_SCRUB, ODO_TRUCKS, 1));
    TEST_ASSERT_EQUAL_INT64(0, odo_params_get(&p, ODO_PF_RESERVED, 0));
    /* a sample through the members themselves */
    TEST_ASSERT_EQUAL_INT32(-(0x11 * (ODO_PF_SCRUB) + 1), p.truck[1].scrub_q30);
    TEST_ASSERT_EQUAL_UINT8(0x11 * ODO_PF_VEHICLE + 1, p.vehicle); /* top fields: last write wins */
    TEST_ASSERT_EQUAL_UINT16(0x11 * ODO_PF_STALE_TICKS + 1, p.link.stale_ticks);

    uint8_t b[ODO_PARAMS_SIZE];
    TEST_ASSERT_EQUAL_size_t(ODO_PARAMS_SIZE, odo_params_encode(&p, b, sizeof b));
    for (size_t i = 0; i < odo_params_field_count(); i++) {
        const odo_param_field_info_t *f = odo_params_field_at(i);
        for (uint8_t t = 0; t < (f->scope == ODO_PSCOPE_TRUCK ? ODO_TRUCKS : 1U); t++) {
            uint32_t raw = 0;
            for (unsigned k = f->width; k > 0; k--) {
                raw = (raw << 8) | b[f->offset + (size_t)t * f->stride + k - 1U];
            }
            const int64_t want = odo_params_get(&p, (odo_param_field_t)f->id, t);
            const int64_t got = f->type == ODO_PTYPE_I32 ? (int64_t)(int32_t)raw : (int64_t)raw;
            TEST_ASSERT_EQUAL_INT64_MESSAGE(want, got, f->name);
        }
    }
}

/// The scrub term's range, both trucks: |k| <= 0.25 in Q30 (the header), as a decoded block shows.
static void scrub_outside_a_quarter_is_refused_naming_the_truck(void)
{
    static const int64_t cases[][2] = {
        {Q30_0_25, 1}, {-Q30_0_25, 1}, {Q30_0_25 + 1, 0}, {-Q30_0_25 - 1, 0}, {INT32_MAX, 0}, {INT32_MIN, 0}, {0, 1}};
    for (uint8_t t = 0; t < ODO_TRUCKS; t++) {
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            odo_params_t p;
            odo_params_defaults(&p);
            p.truck[t].scrub_q30 = (int32_t)cases[i][0];
            expect_block(&p, cases[i][1] ? ODO_PARAMS_OK : ODO_PARAMS_ERR_RANGE,
                         cases[i][1] ? ODO_PF_NONE : ODO_PF_SCRUB, cases[i][1] ? 0U : t, "scrub");
        }
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_defaults_are_the_documented_labmate_and_validate);
    RUN_TEST(test_crc32_of_123456789_is_the_standard_check_value);
    RUN_TEST(test_encoded_header_and_crc_sit_where_the_layout_table_says);
    RUN_TEST(test_round_trip_of_defaults_is_field_for_field_equal);
    RUN_TEST(test_round_trip_of_random_valid_blocks_is_field_for_field_equal);
    RUN_TEST(test_trailing_bytes_after_the_declared_length_are_ignored);
    RUN_TEST(test_every_single_bit_flip_is_rejected_and_out_is_untouched);
    RUN_TEST(test_truncated_blocks_of_every_length_are_short);
    RUN_TEST(test_wrong_magic_is_not_a_parameter_block);
    RUN_TEST(test_unknown_version_is_refused_even_with_a_correct_crc);
    RUN_TEST(test_wrong_length_field_is_refused_even_with_a_correct_crc);
    RUN_TEST(test_each_range_rejects_just_outside_and_accepts_just_inside);
    RUN_TEST(test_int32_min_is_out_of_every_signed_range);
    RUN_TEST(test_counter_bits_accepts_every_width_from_8_to_32);
    RUN_TEST(test_truck_flags_accept_only_the_invert_bits);
    RUN_TEST(test_length_limits_must_be_ordered_and_within_1mm_to_20m);
    RUN_TEST(test_unused_truck_record_must_still_be_sane);
    RUN_TEST(test_validate_names_the_first_offending_field);
    RUN_TEST(test_nonzero_reserved_bytes_are_out_of_range);
    RUN_TEST(test_load_falls_back_to_exactly_the_defaults_and_reports_why);
    RUN_TEST(test_null_arguments_are_err_arg_never_a_crash);
    RUN_TEST(test_encode_into_too_small_a_buffer_returns_0_and_writes_nothing);
    RUN_TEST(test_every_status_has_distinct_text_and_crc_names_the_crc);
    RUN_TEST(parse_reads_out_of_range_fields_that_decode_refuses);
    RUN_TEST(version_1_block_loads_with_scrub_0);
    RUN_TEST(version_1_block_refusals);
    RUN_TEST(field_table_is_a_partition_of_the_block);
    RUN_TEST(encoder_puts_every_field_at_its_table_offset);
    RUN_TEST(scrub_outside_a_quarter_is_refused_naming_the_truck);
    return UNITY_END();
}
