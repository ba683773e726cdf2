/// Why a parameter block is refused, in words a user can act on: shared by `odo-params show`,
/// `odo-calib read/verify/write` and the raw-block reader of params_json.h, so every tool names
/// the same field the same way. Host C99; reentrant.
#ifndef ODO_PARAMS_DIAG_H
#define ODO_PARAMS_DIAG_H

#include <stddef.h>
#include <stdint.h>

#include "odo/odo_params.h"

/// The field as a user finds it in the JSON: "truck[1].scrub_q30", "link.rotary_bits", "tick_us".
void odo_params_qualified_name(odo_param_field_t f, uint8_t truck, char *out, size_t cap);

/// Explain status `st` of odo_params_decode on the n bytes at b: `field` gets what is wrong
/// ("magic", "version", "length", "crc32", a qualified field name, "reserved"; empty for SHORT),
/// `detail` the specifics with the offending value ("version 3, this tool reads 1 and 2",
/// "field truck[1].scrub_q30 = 300000000 is outside [-268435456, 268435456]", "reserved byte at
/// offset 140 is 0x01, must be 0"). Both empty for ODO_PARAMS_OK.
void odo_params_explain(odo_params_status_t st, const uint8_t *b, size_t n, char *field, size_t fcap, char *detail,
                        size_t dcap);

#endif
