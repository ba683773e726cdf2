/// The parameter block as JSON: the shape `odo-params show` prints (odo/odo_params.h field names,
/// integer values in the block's own units), read and written by `odo-calib` and `odo-sim --params`.
///
///   {"status": "ok", "magic": "ODOP", "version": 1, "length": 128, "crc32": "0x...",
///    "vehicle": 0, "counter_bits": 24, "heading_form": 0, "ipec_mode": 0, "tick_us": 40000,
///    "max_wheel_speed_mm_s": 3000,
///    "truck": [{"wheel_diameter_nm": ..., "counts_per_rev_milli": ..., "wheelbase_nm": ...,
///               "ed_q30": ..., "eb_q30": ..., "es_q30": ..., "flags": 0}, {...}],
///    "link": {"length_nm": ..., "hitch_offset_nm": ..., "length_bias_nm": ..., "length_ecc_nm": ...,
///             "alpha_bias_bam": ..., "beta_bias_bam": ..., "rotary_bits": ..., "stale_ticks": ...,
///             "max_jump_bam": ..., "max_length_jump_um": ..., "length_min_um": ...,
///             "length_max_um": ...}}
///
/// Reading: every layout field is required and must be an integer of its field's type; "file",
/// "status" (must be "ok"), "magic" (must be "ODOP"), "version" (must be ODO_PARAMS_VERSION),
/// "length" (must be ODO_PARAMS_SIZE), "crc32" (ignored: the CRC is recomputed on encoding) and
/// "comment" are optional; any other key is an error. The result is range-checked with
/// odo_params_validate. Errors read "<path>: <field>: <why>" (JSON syntax errors: line and column).
///
/// Host C99 + jansson; reentrant.
#ifndef ODO_PARAMS_JSON_H
#define ODO_PARAMS_JSON_H

#include <stddef.h>
#include <stdio.h>

#include "odo/odo_params.h"

/// Parse a file. Returns 0 with *p filled, or -1 with a message in err (*p untouched).
int odo_params_json_load(const char *path, odo_params_t *p, char *err, size_t errlen);

/// Parse text; `origin` names it in messages.
int odo_params_json_parse(const char *text, const char *origin, odo_params_t *p, char *err, size_t errlen);

/// Load a parameter file that is either this JSON or a raw 128-byte block (decided by content: a
/// block starts with the magic 'ODOP'). Returns 0, or -1 with a message in err.
int odo_params_file_load(const char *path, odo_params_t *p, char *err, size_t errlen);

/// Write *p in the shape above (with "status", "magic", "version", "length", and the "crc32" of
/// its encoding). Returns 0, or -1 on an I/O error.
/// The block's fields as JSON object members (from "vehicle" to the "link" object, no braces and
/// no trailing newline): the part `odo-params show` and odo_params_json_write share.
void odo_params_json_fields(FILE *f, const odo_params_t *p);

int odo_params_json_write(FILE *f, const odo_params_t *p);

#endif
