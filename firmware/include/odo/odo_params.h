/// Parameter block: everything the firmware needs to know about its robot, stored in flash in its
/// own linker section (.odo_params) and patched by `odo-calib write`. This header is the single
/// source of truth for the layout: ODO_PARAMS_FIELDS below lists every field once (name, offset,
/// width, signedness, range, unit), and the codec, the range checks, the field names, the host
/// tools' JSON and the layout `odo-params layout` dumps for Python are all expanded from it.
///
/// Byte layout, version 2 (explicit little-endian serialisation, never a struct dump). Version 2
/// is version 1 with the CRC moved to the end and a tail appended: bytes [8, 124) mean the same in
/// both, so a version-1 block reads as version 2 with scrub_q30 = 0 (000 Eq. 2.4 unchanged).
///
///   off  size  type  field                        off  size  type  field
///     0     4  u32   magic 'ODOP' (0x504F444F)     76     4  u32   link.length_nm
///     4     2  u16   version (2)                   80     4  u32   link.hitch_offset_nm
///     6     2  u16   length (256, incl. CRC)       84     4  i32   link.length_bias_nm
///     8     1  u8    vehicle                       88     4  i32   link.length_ecc_nm
///     9     1  u8    counter_bits                  92     4  i32   link.alpha_bias_bam
///    10     1  u8    heading_form                  96     4  i32   link.beta_bias_bam
///    11     1  u8    ipec_mode                    100     1  u8    link.rotary_bits
///    12     4  u32   tick_us                      101     1        reserved (0)
///    16     4  u32   max_wheel_speed_mm_s         102     2  u16   link.stale_ticks
///    20    28        truck[0] (A), see below      104     4  u32   link.max_jump_bam
///    48    28        truck[1] (B)                 108     4  u32   link.max_length_jump_um
///                                                 112     4  u32   link.length_min_um
///   truck record (offsets from its start):        116     4  u32   link.length_max_um
///     0     4  u32   wheel_diameter_nm            120     4        reserved (0)
///     4     4  u32   counts_per_rev_milli         124     4  i32   truck[0].scrub_q30     (v2)
///     8     4  u32   wheelbase_nm                 128     4  i32   truck[1].scrub_q30     (v2)
///    12     4  i32   ed_q30                       132   120        reserved (0)           (v2)
///    16     4  i32   eb_q30                       252     4  u32   CRC-32 of bytes [0, 252)
///    20     4  i32   es_q30
///    24     1  u8    flags
///    25     3        reserved (0)
///
/// Version 1 (128 bytes, still read; never written): the same bytes [0, 124) with version 1 and
/// length 128, then the CRC-32 of bytes [0, 124) at 124. It has no scrub_q30 (read as 0).
///
/// CRC-32 is the IEEE 802.3 / zlib one (reflected polynomial 0xEDB88320, init and final xor
/// 0xFFFFFFFF), so `zlib.crc32(block[:252])` on the host agrees with the firmware.
///
/// Reserved bytes are every byte of [8, CRC offset) that no field of the block's version covers
/// (the table above; odo_params_reserved_offset finds them). Encoding writes them 0; parsing
/// refuses a block with any of them non-zero (ODO_PARAMS_ERR_RANGE, field "reserved"), because
/// a non-zero one means a writer that knows a field this firmware does not. That is how the block
/// grows without a new size: a later field takes reserved room, and its value 0 must mean "as
/// before", so older firmware accepts a block that leaves it at 0 and refuses one that uses it.
///
/// Boot rule: odo_params_load() accepts a block only if magic, version, length, CRC and every range
/// check pass; otherwise it fills the documented defaults (odo_params_defaults) and reports why, and
/// the application raises ODO_FAULT_PARAMS_DEFAULTED in every status frame.
#ifndef ODO_PARAMS_H
#define ODO_PARAMS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_PARAMS_MAGIC         0x504F444FUL ///< bytes 'O','D','O','P' in little-endian order
#define ODO_PARAMS_VERSION       2U           ///< the version odo_params_encode writes
#define ODO_PARAMS_SIZE          256U         ///< bytes of a version-2 block, CRC included
#define ODO_PARAMS_CRC_OFFSET    252U
#define ODO_PARAMS_V1_SIZE       128U ///< bytes of a version-1 block (read only)
#define ODO_PARAMS_V1_CRC_OFFSET 124U
#define ODO_PARAMS_HEADER_SIZE   8U ///< magic, version, length: what a block claims

/// Q30 representation of a dimensionless ratio: 1.0 == 2^30.
#define ODO_RATIO_Q30_ONE ((int32_t)1 << 30)

typedef enum {
    ODO_VEHICLE_SINGLE = 0,  ///< one differential-drive truck (labmate)
    ODO_VEHICLE_CLAPPER = 1, ///< two trucks on a compliant linkage (004 section 2)
    ODO_VEHICLE_SET = 2      ///< one truck towing a passive encoder trailer (000 section 4.6)
} odo_vehicle_t;

typedef enum {
    ODO_HEADING_MIDPOINT = 0, ///< position advanced along theta_{i-1} + dtheta/2 (default)
    ODO_HEADING_PAPER = 1     ///< position advanced along the new theta_i (000 Eq. 2.6)
} odo_heading_form_t;

typedef enum {
    ODO_IPEC_OFF = 0,
    ODO_IPEC_PAPER = 1,    ///< the per-tick correction of 002 Eqs. 9-16
    ODO_IPEC_ESTIMATOR = 2 ///< per-tick correction plus the sub-resolution estimator
} odo_ipec_mode_t;

#define ODO_TRUCK_INVERT_LEFT  0x01U ///< left counter counts down when the wheel rolls forward
#define ODO_TRUCK_INVERT_RIGHT 0x02U

/// One truck's geometry and calibration. Ranges (inclusive) are those of ODO_PARAMS_FIELDS;
/// odo_params_validate enforces them.
typedef struct {
    uint32_t wheel_diameter_nm;    ///< nominal wheel diameter Dn (000 Eq. 2.1); [10 mm, 2 m]
    uint32_t counts_per_rev_milli; ///< decoded counts per wheel turn (n * Ce, after 4x) x 1000;
                                   ///< [100 counts, 4e6 counts]
    uint32_t wheelbase_nm;         ///< nominal wheelbase b (000 Eq. 2.4); [50 mm, 3 m]
    int32_t ed_q30;                ///< Ed = DR/DL (000 Eq. 2.7, found by Eq. 6.24); [0.8, 1.25]
    int32_t eb_q30;                ///< Eb = b_actual/b_nominal on spot turns (000 Eq. 2.8, 6.28);
                                   ///< [0.8, 1.25]
    int32_t es_q30;                ///< Es = L_calc/L_actual (000 Eq. B.1); [0.8, 1.25]
    int32_t scrub_q30;             ///< k of the tyre-scrub term (effect `scrub`, odo_odometry.h):
                                   ///< on an arc of spin fraction s the effective wheelbase is
                                   ///< b Eb / (1 - k (1 - s)); [-0.25, 0.25], 0 = off (version 1)
    uint8_t flags;                 ///< ODO_TRUCK_INVERT_*; other bits must be 0
} odo_truck_params_t;

/// Linkage (clapper) or trailer joint (set) geometry and IPEC gating limits.
typedef struct {
    uint32_t length_nm;          ///< nominal link length l (clapper, 004 s. 2: 1 m) or the joint to
                                 ///< trailer-axle distance (set); [100 mm, 4 m]
    uint32_t hitch_offset_nm;    ///< set: robot centre to joint, behind the robot; [0, 4 m]
    int32_t length_bias_nm;      ///< linear-encoder bias, subtracted (002 s. 5.2); |.| <= 50 mm
    int32_t length_ecc_nm;       ///< eccentric part of the bias (see ipec); |.| <= 50 mm
    int32_t alpha_bias_bam;      ///< rotary encoder A zero offset, subtracted; |.| <= 10 deg
    int32_t beta_bias_bam;       ///< rotary encoder B zero offset, subtracted; |.| <= 10 deg
    uint8_t rotary_bits;         ///< absolute rotary encoder resolution (004: 10); [8, 16]
    uint16_t stale_ticks;        ///< linkage data older than this gates IPEC off; [1, 1000]
    uint32_t max_jump_bam;       ///< largest believable per-tick change of alpha/beta; [1, 90 deg]
    uint32_t max_length_jump_um; ///< largest believable per-tick change of l; [1 um, 1 m]
    uint32_t length_min_um;      ///< physical range of l; min < max, both within [1 mm, 20 m]
    uint32_t length_max_um;
} odo_link_params_t;

typedef struct {
    uint8_t vehicle;               ///< odo_vehicle_t
    uint8_t counter_bits;          ///< wheel decoder counter width, any of 8..32 bits
    uint8_t heading_form;          ///< odo_heading_form_t
    uint8_t ipec_mode;             ///< odo_ipec_mode_t
    uint32_t tick_us;              ///< application step period; [1 ms, 1 s]; 40 ms (002 s. 4.1)
    uint32_t max_wheel_speed_mm_s; ///< faster wheel motion is a counter fault; [100, 20000]
    odo_truck_params_t truck[ODO_TRUCKS];
    odo_link_params_t link;
} odo_params_t;

/* ---------------------------------------------------------------------------------------------
 * The field table.
 * ------------------------------------------------------------------------------------------- */

/// Units of the limits below (nm, um, BAM: 2^32 per turn, rounded to nearest).
#define ODO_NM_PER_MM     INT64_C(1000000)
#define ODO_UM_PER_MM     INT64_C(1000)
#define ODO_DEG_TO_BAM(d) (((((int64_t)(d)) << 32) + 180) / 360)
/// Q30 ratio limits: 0.8 is not representable (0.8 * 2^30 = 858993459.2, truncated); 1.25 is.
#define ODO_RATIO_MIN_Q30 ((((int64_t)4) << 30) / 5)
#define ODO_RATIO_MAX_Q30 ((((int64_t)5) << 30) / 4)
/// |scrub| <= 0.25 in Q30: beyond, the wheelbase factor 1/(1 - k (1 - s)) leaves [0.8, 1.34].
#define ODO_SCRUB_MAX_Q30 (((int64_t)1) << 28)

/// Every field of the block, once, in validation order:
///   X(id, scope, member, json, since, offset, stride, type, min, max, unit)
///   id      odo_param_field_t is ODO_PF_<id>
///   scope   TOP (odo_params_t), TRUCK (odo_truck_params_t, one per truck), LINK (p->link)
///   member  the struct member (TRUCK: of odo_truck_params_t, otherwise of odo_params_t)
///   json    the name as the JSON tools spell it (truck fields without "truck[i].")
///   since   the first layout version that carries the field
///   offset  byte offset in the block (truck fields: truck A's); stride: truck B's minus A's
///   type    U8, U16, U32 (unsigned) or I32 (two's complement), little-endian
///   min/max inclusive range odo_params_validate enforces; unit: scale and unit, for people
/// Checks beyond one field's range: link.length_min_um < link.length_max_um (ODO_PF_LENGTH_RANGE).
/// flags' range [0, 3] is exactly "no bit but the two ODO_TRUCK_INVERT_* bits".
#define ODO_PARAMS_FIELDS(X)                                                                                          \
    X(VEHICLE, TOP, vehicle, "vehicle", 1, 8, 0, U8, 0, 2, "odo_vehicle_t")                                           \
    X(COUNTER_BITS, TOP, counter_bits, "counter_bits", 1, 9, 0, U8, 8, 32, "bits")                                    \
    X(HEADING_FORM, TOP, heading_form, "heading_form", 1, 10, 0, U8, 0, 1, "odo_heading_form_t")                      \
    X(IPEC_MODE, TOP, ipec_mode, "ipec_mode", 1, 11, 0, U8, 0, 2, "odo_ipec_mode_t")                                  \
    X(TICK_US, TOP, tick_us, "tick_us", 1, 12, 0, U32, 1000, 1000000, "us")                                           \
    X(MAX_WHEEL_SPEED, TOP, max_wheel_speed_mm_s, "max_wheel_speed_mm_s", 1, 16, 0, U32, 100, 20000, "mm/s")          \
    X(WHEEL_DIAMETER, TRUCK, wheel_diameter_nm, "wheel_diameter_nm", 1, 20, 28, U32, 10 * ODO_NM_PER_MM,              \
      2000 * ODO_NM_PER_MM, "nm")                                                                                     \
    X(COUNTS_PER_REV, TRUCK, counts_per_rev_milli, "counts_per_rev_milli", 1, 24, 28, U32, INT64_C(100000),           \
      INT64_C(4000000000), "counts per wheel turn x 1000")                                                            \
    X(WHEELBASE, TRUCK, wheelbase_nm, "wheelbase_nm", 1, 28, 28, U32, 50 * ODO_NM_PER_MM, 3000 * ODO_NM_PER_MM, "nm") \
    X(ED, TRUCK, ed_q30, "ed_q30", 1, 32, 28, I32, ODO_RATIO_MIN_Q30, ODO_RATIO_MAX_Q30, "Q30")                       \
    X(EB, TRUCK, eb_q30, "eb_q30", 1, 36, 28, I32, ODO_RATIO_MIN_Q30, ODO_RATIO_MAX_Q30, "Q30")                       \
    X(ES, TRUCK, es_q30, "es_q30", 1, 40, 28, I32, ODO_RATIO_MIN_Q30, ODO_RATIO_MAX_Q30, "Q30")                       \
    X(SCRUB, TRUCK, scrub_q30, "scrub_q30", 2, 124, 4, I32, -ODO_SCRUB_MAX_Q30, ODO_SCRUB_MAX_Q30, "Q30")             \
    X(TRUCK_FLAGS, TRUCK, flags, "flags", 1, 44, 28, U8, 0, 3, "ODO_TRUCK_INVERT_* bits")                             \
    X(LINK_LENGTH, LINK, link.length_nm, "link.length_nm", 1, 76, 0, U32, 100 * ODO_NM_PER_MM, 4000 * ODO_NM_PER_MM,  \
      "nm")                                                                                                           \
    X(HITCH_OFFSET, LINK, link.hitch_offset_nm, "link.hitch_offset_nm", 1, 80, 0, U32, 0, 4000 * ODO_NM_PER_MM, "nm") \
    X(LENGTH_BIAS, LINK, link.length_bias_nm, "link.length_bias_nm", 1, 84, 0, I32, -50 * ODO_NM_PER_MM,              \
      50 * ODO_NM_PER_MM, "nm")                                                                                       \
    X(LENGTH_ECC, LINK, link.length_ecc_nm, "link.length_ecc_nm", 1, 88, 0, I32, -50 * ODO_NM_PER_MM,                 \
      50 * ODO_NM_PER_MM, "nm")                                                                                       \
    X(ALPHA_BIAS, LINK, link.alpha_bias_bam, "link.alpha_bias_bam", 1, 92, 0, I32, -ODO_DEG_TO_BAM(10),               \
      ODO_DEG_TO_BAM(10), "BAM")                                                                                      \
    X(BETA_BIAS, LINK, link.beta_bias_bam, "link.beta_bias_bam", 1, 96, 0, I32, -ODO_DEG_TO_BAM(10),                  \
      ODO_DEG_TO_BAM(10), "BAM")                                                                                      \
    X(ROTARY_BITS, LINK, link.rotary_bits, "link.rotary_bits", 1, 100, 0, U8, 8, 16, "bits")                          \
    X(STALE_TICKS, LINK, link.stale_ticks, "link.stale_ticks", 1, 102, 0, U16, 1, 1000, "ticks")                      \
    X(MAX_JUMP, LINK, link.max_jump_bam, "link.max_jump_bam", 1, 104, 0, U32, 1, ODO_DEG_TO_BAM(90), "BAM")           \
    X(MAX_LENGTH_JUMP, LINK, link.max_length_jump_um, "link.max_length_jump_um", 1, 108, 0, U32, 1,                   \
      1000 * ODO_UM_PER_MM, "um")                                                                                     \
    X(LENGTH_MIN, LINK, link.length_min_um, "link.length_min_um", 1, 112, 0, U32, ODO_UM_PER_MM,                      \
      20000 * ODO_UM_PER_MM, "um")                                                                                    \
    X(LENGTH_MAX, LINK, link.length_max_um, "link.length_max_um", 1, 116, 0, U32, ODO_UM_PER_MM,                      \
      20000 * ODO_UM_PER_MM, "um")

/// Field identifiers: one per ODO_PARAMS_FIELDS entry, in table order, then the two that are not
/// a single field. odo_params_validate reports them so tools can name the offending field.
typedef enum {
    ODO_PF_NONE = 0,
#define ODO_PF_ENUM_(id, ...) ODO_PF_##id,
    ODO_PARAMS_FIELDS(ODO_PF_ENUM_)
#undef ODO_PF_ENUM_
        ODO_PF_LENGTH_RANGE, ///< link.length_min_um >= link.length_max_um
    ODO_PF_RESERVED          ///< a reserved byte is non-zero (odo_params_reserved_offset says which)
} odo_param_field_t;

typedef enum { ODO_PSCOPE_TOP = 0, ODO_PSCOPE_TRUCK = 1, ODO_PSCOPE_LINK = 2 } odo_param_scope_t;
typedef enum { ODO_PTYPE_U8 = 0, ODO_PTYPE_U16 = 1, ODO_PTYPE_U32 = 2, ODO_PTYPE_I32 = 3 } odo_param_type_t;

/// One row of ODO_PARAMS_FIELDS as data, for code that walks the fields (codec, JSON, tools).
typedef struct {
    int64_t min; ///< inclusive range
    int64_t max;
    const char *name; ///< `json`: odo_params_field_name of this field
    uint16_t offset;  ///< byte offset in the block (truck fields: truck A's)
    uint16_t stride;  ///< truck fields: truck B's offset minus truck A's; otherwise 0
    uint16_t member;  ///< offsetof the member in odo_truck_params_t (TRUCK) or odo_params_t
    uint8_t id;       ///< odo_param_field_t
    uint8_t scope;    ///< odo_param_scope_t
    uint8_t type;     ///< odo_param_type_t
    uint8_t width;    ///< bytes: 1, 2 or 4
    uint8_t since;    ///< first layout version carrying the field
} odo_param_field_info_t;

/// Number of ODO_PARAMS_FIELDS entries; odo_params_field_at(i) is entry i (id i + 1), or NULL iff
/// i >= that number. Constant time; the rows live in flash.
size_t odo_params_field_count(void);
const odo_param_field_info_t *odo_params_field_at(size_t i);

/// The row of a field id; NULL for ODO_PF_NONE, ODO_PF_LENGTH_RANGE, ODO_PF_RESERVED and unknown ids.
const odo_param_field_info_t *odo_params_field_info(odo_param_field_t f);

/// True iff f is a per-truck field (reported with a truck index).
bool odo_params_field_is_truck(odo_param_field_t f);

/// Field f of *p (of truck `truck` for truck fields) as a signed 64-bit value; 0 if f is not a
/// field or truck >= ODO_TRUCKS.
int64_t odo_params_get(const odo_params_t *p, odo_param_field_t f, uint8_t truck);

/// Store v into field f of *p (truck `truck`), converted to the field's type modulo its width
/// (no range check: tests write bad values on purpose). Returns false iff f is not a field or
/// truck >= ODO_TRUCKS (nothing is written then).
bool odo_params_set(odo_params_t *p, odo_param_field_t f, uint8_t truck, int64_t v);

/* ---------------------------------------------------------------------------------------------
 * Codec.
 * ------------------------------------------------------------------------------------------- */

typedef enum {
    ODO_PARAMS_OK = 0,
    ODO_PARAMS_ERR_SHORT,   ///< fewer bytes than the header or the declared length
    ODO_PARAMS_ERR_MAGIC,   ///< not a parameter block
    ODO_PARAMS_ERR_VERSION, ///< a version this firmware does not know
    ODO_PARAMS_ERR_LENGTH,  ///< declared length differs from this version's size
    ODO_PARAMS_ERR_CRC,     ///< CRC mismatch: corrupted in flash or in transit
    ODO_PARAMS_ERR_RANGE,   ///< a field outside its documented range (or a reserved byte non-zero)
    ODO_PARAMS_ERR_ARG      ///< NULL pointer or too small an output buffer
} odo_params_status_t;

/// Size in bytes of a block of layout `version` (128 for 1, 256 for 2), or 0 for a version this
/// firmware does not know.
size_t odo_params_version_size(uint16_t version);

/// The documented defaults (a labmate: one truck, Dn 150 mm, 39000 counts/turn, b 340 mm, no
/// calibration, no scrub term, 24-bit counters, midpoint heading, IPEC off, 40 ms tick, 3 m/s
/// limit; linkage fields describe the clapper's 1 m link with 10-bit rotary encoders). Never fails.
void odo_params_defaults(odo_params_t *p);

/// Range-check every field (table order: the top fields, then truck A's, truck B's, the link's,
/// then the length pair). Returns ODO_PARAMS_OK or ODO_PARAMS_ERR_RANGE; on error *bad_field (if
/// not NULL) names the first offending field and *bad_truck (if not NULL) its truck index.
/// Linear in the number of fields; no loops otherwise.
odo_params_status_t odo_params_validate(const odo_params_t *p, odo_param_field_t *bad_field, uint8_t *bad_truck);

/// Serialise to exactly ODO_PARAMS_SIZE bytes of layout version ODO_PARAMS_VERSION with header
/// and CRC. Returns the byte count, or 0 iff cap < ODO_PARAMS_SIZE or an argument is NULL. Does
/// not validate (tests need to write bad blocks).
size_t odo_params_encode(const odo_params_t *p, uint8_t *buf, size_t cap);

/// Check header, length and CRC of a version-1 or version-2 block and read every field as
/// stored, without range checks, so tools can name an offending field with odo_params_validate.
/// Fields a version-1 block does not carry read as 0. Returns ODO_PARAMS_OK with *out filled;
/// ODO_PARAMS_ERR_RANGE with *out filled iff a reserved byte is non-zero; any other error with
/// *out untouched. Reads only the declared length of a larger region.
odo_params_status_t odo_params_parse(const uint8_t *buf, size_t len, odo_params_t *out);

/// odo_params_parse, then odo_params_validate. *out is written only on ODO_PARAMS_OK.
odo_params_status_t odo_params_decode(const uint8_t *buf, size_t len, odo_params_t *out);

/// Boot-time load: decode; on any failure fill *out with the defaults. Returns the decode status, so
/// the caller raises ODO_FAULT_PARAMS_DEFAULTED iff the result is not ODO_PARAMS_OK.
odo_params_status_t odo_params_load(const uint8_t *buf, size_t len, odo_params_t *out);

/// The offset of the first non-zero reserved byte of a block whose header is that of a known
/// version (CRC not checked), or 0 if there is none, the header is not a known one, or fewer
/// than the declared length of bytes are given (offset 0 is the magic, never reserved).
size_t odo_params_reserved_offset(const uint8_t *buf, size_t len);

/// CRC-32 (IEEE 802.3 / zlib). Bitwise, 8 iterations per byte; no table.
uint32_t odo_crc32(const uint8_t *data, size_t len);

/// Static English text for a status, for host tools' messages.
const char *odo_params_status_str(odo_params_status_t s);

/// The field's name as the JSON tools spell it ("link.rotary_bits", "ed_q30"; truck fields without
/// their truck index); "none", "reserved" and "link.length_min_um/link.length_max_um" for the
/// identifiers that are not a single field; "unknown" otherwise.
const char *odo_params_field_name(odo_param_field_t f);

#ifdef __cplusplus
}
#endif
#endif
