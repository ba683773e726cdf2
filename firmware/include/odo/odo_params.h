/// Parameter block: everything the firmware needs to know about its robot, stored in flash in its
/// own linker section (.odo_params) and patched by `odo-calib write`. This header is the single
/// source of truth for the layout; host tools and tests are checked against it.
///
/// Byte layout, version 1 (explicit little-endian serialisation, never a struct dump):
///
///   off  size  field                                   off  size  field
///     0    4   magic 'O''D''O''P' (0x504F444F LE)       76    4   link.length_nm
///     4    2   version (1)                              80    4   link.hitch_offset_nm
///     6    2   length (128, whole block incl. CRC)      84    4   link.length_bias_nm   (int32)
///     8    1   vehicle                                  88    4   link.length_ecc_nm    (int32)
///     9    1   counter_bits                             92    4   link.alpha_bias_bam   (int32)
///    10    1   heading_form                             96    4   link.beta_bias_bam    (int32)
///    11    1   ipec_mode                               100    1   link.rotary_bits
///    12    4   tick_us                                 101    1   reserved (0)
///    16    4   max_wheel_speed_mm_s                    102    2   link.stale_ticks
///    20   28   truck[0] (A), see below                 104    4   link.max_jump_bam
///    48   28   truck[1] (B)                            108    4   link.max_length_jump_um
///                                                      112    4   link.length_min_um
///   truck record (offsets relative to its start):      116    4   link.length_max_um
///     0 u32 wheel_diameter_nm   16 i32 eb_q30          120    4   reserved (0)
///     4 u32 counts_per_rev_milli 20 i32 es_q30         124    4   CRC-32 of bytes [0, 124)
///     8 u32 wheelbase_nm        24 u8  flags
///    12 i32 ed_q30              25..27 reserved (0)
///
/// CRC-32 is the IEEE 802.3 / zlib one (reflected polynomial 0xEDB88320, init and final xor
/// 0xFFFFFFFF), so `zlib.crc32(block[:124])` on the host agrees with the firmware.
///
/// Boot rule: odo_params_load() accepts a block only if magic, version, length, CRC and every range
/// check pass; otherwise it fills the documented defaults (odo_params_defaults) and reports why, and
/// the application raises ODO_FAULT_PARAMS_DEFAULTED in every status frame.
#ifndef ODO_PARAMS_H
#define ODO_PARAMS_H

#include <stddef.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_PARAMS_MAGIC     0x504F444FUL ///< bytes 'O','D','O','P' in little-endian order
#define ODO_PARAMS_VERSION   1U
#define ODO_PARAMS_SIZE      128U
#define ODO_PARAMS_CRC_OFFSET 124U

/// Q30 representation of a dimensionless ratio: 1.0 == 2^30.
#define ODO_RATIO_Q30_ONE ((int32_t)1 << 30)

typedef enum {
    ODO_VEHICLE_SINGLE  = 0, ///< one differential-drive truck (labmate)
    ODO_VEHICLE_CLAPPER = 1, ///< two trucks on a compliant linkage (004 section 2)
    ODO_VEHICLE_SET     = 2  ///< one truck towing a passive encoder trailer (000 section 4.6)
} odo_vehicle_t;

typedef enum {
    ODO_HEADING_MIDPOINT = 0, ///< position advanced along theta_{i-1} + dtheta/2 (default)
    ODO_HEADING_PAPER    = 1  ///< position advanced along the new theta_i (000 Eq. 2.6)
} odo_heading_form_t;

typedef enum {
    ODO_IPEC_OFF       = 0,
    ODO_IPEC_PAPER     = 1, ///< the per-tick correction of 002 Eqs. 9-16
    ODO_IPEC_ESTIMATOR = 2  ///< per-tick correction plus the sub-resolution estimator
} odo_ipec_mode_t;

#define ODO_TRUCK_INVERT_LEFT  0x01U ///< left counter counts down when the wheel rolls forward
#define ODO_TRUCK_INVERT_RIGHT 0x02U

/// One truck's geometry and calibration. Ranges are inclusive; odo_params_validate enforces them.
typedef struct {
    uint32_t wheel_diameter_nm;    ///< nominal wheel diameter Dn (000 Eq. 2.1); [10 mm, 2 m]
    uint32_t counts_per_rev_milli; ///< decoded counts per wheel turn (n * Ce, after 4x) x 1000;
                                   ///< [100 counts, 4e6 counts]
    uint32_t wheelbase_nm;         ///< nominal wheelbase b (000 Eq. 2.4); [50 mm, 3 m]
    int32_t  ed_q30;               ///< Ed = DR/DL (000 Eq. 2.7, found by Eq. 6.24); [0.8, 1.25]
    int32_t  eb_q30;               ///< Eb = b_actual/b_nominal (000 Eq. 2.8, 6.28); [0.8, 1.25]
    int32_t  es_q30;               ///< Es = L_calc/L_actual (000 Eq. B.1); [0.8, 1.25]
    uint8_t  flags;                ///< ODO_TRUCK_INVERT_*; other bits must be 0
} odo_truck_params_t;

/// Linkage (clapper) or trailer joint (set) geometry and IPEC gating limits.
typedef struct {
    uint32_t length_nm;          ///< nominal link length l (clapper, 004 s. 2: 1 m) or the joint to
                                 ///< trailer-axle distance (set); [100 mm, 4 m]
    uint32_t hitch_offset_nm;    ///< set: robot centre to joint, behind the robot; [0, 4 m]
    int32_t  length_bias_nm;     ///< linear-encoder bias, subtracted (002 s. 5.2); |.| <= 50 mm
    int32_t  length_ecc_nm;      ///< eccentric part of the bias (see ipec); |.| <= 50 mm
    int32_t  alpha_bias_bam;     ///< rotary encoder A zero offset, subtracted; |.| <= 10 deg
    int32_t  beta_bias_bam;      ///< rotary encoder B zero offset, subtracted; |.| <= 10 deg
    uint8_t  rotary_bits;        ///< absolute rotary encoder resolution (004: 10); [8, 16]
    uint16_t stale_ticks;        ///< linkage data older than this gates IPEC off; [1, 1000]
    uint32_t max_jump_bam;       ///< largest believable per-tick change of alpha/beta; [1, 90 deg]
    uint32_t max_length_jump_um; ///< largest believable per-tick change of l; [1 um, 1 m]
    uint32_t length_min_um;      ///< physical range of l; min < max, both within [1 mm, 20 m]
    uint32_t length_max_um;
} odo_link_params_t;

typedef struct {
    uint8_t  vehicle;              ///< odo_vehicle_t
    uint8_t  counter_bits;         ///< wheel decoder counter width: [8, 32] (real decoders: 8-32)
    uint8_t  heading_form;         ///< odo_heading_form_t
    uint8_t  ipec_mode;            ///< odo_ipec_mode_t
    uint32_t tick_us;              ///< application step period; [1 ms, 1 s]; 40 ms (002 s. 4.1)
    uint32_t max_wheel_speed_mm_s; ///< faster wheel motion is a counter fault; [100, 20000]
    odo_truck_params_t truck[ODO_TRUCKS];
    odo_link_params_t  link;
} odo_params_t;

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

/// Field identifiers reported by odo_params_validate, so tools can name the offending field.
typedef enum {
    ODO_PF_NONE = 0, ODO_PF_VEHICLE, ODO_PF_COUNTER_BITS, ODO_PF_HEADING_FORM, ODO_PF_IPEC_MODE,
    ODO_PF_TICK_US, ODO_PF_MAX_WHEEL_SPEED,
    ODO_PF_WHEEL_DIAMETER, ODO_PF_COUNTS_PER_REV, ODO_PF_WHEELBASE, ODO_PF_ED, ODO_PF_EB, ODO_PF_ES,
    ODO_PF_TRUCK_FLAGS,
    ODO_PF_LINK_LENGTH, ODO_PF_HITCH_OFFSET, ODO_PF_LENGTH_BIAS, ODO_PF_LENGTH_ECC, ODO_PF_ALPHA_BIAS,
    ODO_PF_BETA_BIAS, ODO_PF_ROTARY_BITS, ODO_PF_STALE_TICKS, ODO_PF_MAX_JUMP, ODO_PF_MAX_LENGTH_JUMP,
    ODO_PF_LENGTH_RANGE, ODO_PF_RESERVED
} odo_param_field_t;

/// The documented defaults (a labmate: one truck, Dn 150 mm, 39000 counts/turn, b 340 mm, no
/// calibration, 24-bit counters, midpoint heading, IPEC off, 40 ms tick, 3 m/s limit; linkage
/// fields describe the clapper's 1 m link with 10-bit rotary encoders). Never fails.
void odo_params_defaults(odo_params_t *p);

/// Range-check every field. Returns ODO_PARAMS_OK or ODO_PARAMS_ERR_RANGE; on error *bad_field
/// (if not NULL) names the first offending field and *bad_truck (if not NULL) its truck index.
odo_params_status_t odo_params_validate(const odo_params_t *p, odo_param_field_t *bad_field,
                                        uint8_t *bad_truck);

/// Serialise to exactly ODO_PARAMS_SIZE bytes with header and CRC. Returns the byte count, or 0 iff
/// cap < ODO_PARAMS_SIZE or an argument is NULL. Does not validate (tests need to write bad blocks).
size_t odo_params_encode(const odo_params_t *p, uint8_t *buf, size_t cap);

/// Check header, length and CRC and read every field as stored, without range checks, so tools
/// can name an offending field with odo_params_validate. Returns ODO_PARAMS_OK with *out filled;
/// ODO_PARAMS_ERR_RANGE with *out filled iff a reserved byte is non-zero; any other error with
/// *out untouched. Reads only the first ODO_PARAMS_SIZE bytes of a larger region.
odo_params_status_t odo_params_parse(const uint8_t *buf, size_t len, odo_params_t *out);

/// odo_params_parse, then odo_params_validate. *out is written only on ODO_PARAMS_OK.
odo_params_status_t odo_params_decode(const uint8_t *buf, size_t len, odo_params_t *out);

/// Boot-time load: decode; on any failure fill *out with the defaults. Returns the decode status, so
/// the caller raises ODO_FAULT_PARAMS_DEFAULTED iff the result is not ODO_PARAMS_OK.
odo_params_status_t odo_params_load(const uint8_t *buf, size_t len, odo_params_t *out);

/// CRC-32 (IEEE 802.3 / zlib). Bitwise, 8 iterations per byte; no table.
uint32_t odo_crc32(const uint8_t *data, size_t len);

/// Static English text for a status, for host tools' messages.
const char *odo_params_status_str(odo_params_status_t s);

/// The field's name as the JSON tools spell it ("link.rotary_bits", "ed_q30"; truck fields without
/// their truck index); "none" and "reserved" for those two values.
const char *odo_params_field_name(odo_param_field_t f);

#ifdef __cplusplus
}
#endif
#endif
