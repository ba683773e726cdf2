/// The parameter block as JSON: the shape `odo-params show` prints (odo/odo_params.h field names,
/// integer values in the block's own units), read and written by `odo-calib` and `odo-sim --params`.
/// Keys, order and types come from the header's field table (ODO_PARAMS_FIELDS); nothing here
/// names a field.
///
///   {"status": "ok", "magic": "ODOP", "version": 2, "length": 256, "crc32": "0x...",
///    "vehicle": 0, "counter_bits": 24, "heading_form": 0, "ipec_mode": 0, "tick_us": 40000,
///    "max_wheel_speed_mm_s": 3000,
///    "truck": [{"wheel_diameter_nm": ..., "counts_per_rev_milli": ..., "wheelbase_nm": ...,
///               "ed_q30": ..., "eb_q30": ..., "es_q30": ..., "scrub_q30": 0, "flags": 0}, {...}],
///    "link": {"length_nm": ..., "hitch_offset_nm": ..., "length_bias_nm": ..., "length_ecc_nm": ...,
///             "alpha_bias_bam": ..., "beta_bias_bam": ..., "rotary_bits": ..., "stale_ticks": ...,
///             "max_jump_bam": ..., "max_length_jump_um": ..., "length_min_um": ...,
///             "length_max_um": ...}}
///
/// Reading: "version" (1 or 2; absent means 2) says which fields the file carries: every field
/// of that layout version is required and must be an integer of its field's type, and a field
/// the version does not have is an error (a version-1 file, as tools before version 2 wrote it,
/// has no scrub_q30 and reads with scrub_q30 = 0). "file", "status" (must be "ok"), "magic" (must
/// be "ODOP"), "length" (must be that version's size), "crc32" (ignored: the CRC is recomputed on
/// encoding) and "comment" are optional; any other key is an error. The result is range-checked
/// with odo_params_validate. Errors read "<path>: <field>: <why>" (JSON syntax errors: line and
/// column). Writing always gives the current version.
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

/// Load a parameter file that is either this JSON or a raw block of any version the firmware reads
/// (decided by content: a block starts with the magic 'ODOP'; the file must be exactly the block).
/// Returns 0, or -1 with a message in err naming the offending field (params_diag.h).
int odo_params_file_load(const char *path, odo_params_t *p, char *err, size_t errlen);

/// The block's fields that layout `version` carries as JSON object members (from "vehicle" to the
/// "link" object, no braces and no trailing newline): the part `odo-params show` and the writers
/// share.
void odo_params_json_fields(FILE *f, const odo_params_t *p, unsigned version);

/// Write *p in the shape above as the current layout version (with "status", "magic", "version",
/// "length", and the "crc32" of its encoding). Returns 0, or -1 on an I/O error.
int odo_params_json_write(FILE *f, const odo_params_t *p);

/// The same for a block as stored in an image or file: its layout `version` (a version-1 block
/// shows without scrub_q30, so the text reads back as what it is) and its stored `crc`.
int odo_params_json_write_stored(FILE *f, const odo_params_t *p, unsigned version, uint32_t crc);

#endif
