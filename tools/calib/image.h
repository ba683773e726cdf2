/// Firmware images that carry a parameter block (odo/odo_params.h): raw binary, Intel HEX and ELF.
///
///   raw .bin  the block is found by its magic 'ODOP'. Every occurrence is a candidate (literal
///             pools hold the magic too); the one whose header and CRC-32 are good is the block.
///             Exactly one must be good.
///   Intel HEX records 00 (data), 01 (end of file, required), 02/04 (extended segment/linear
///             address), 03/05 (start address); checksums verified. The data is laid out by
///             address and searched like a .bin; patching rewrites the data bytes of the records
///             that hold the block and their checksums, every other line stays byte-identical.
///   ELF       32- or 64-bit little-endian; the block is the start of section `.odo_params`
///             (hal/cortexm/odo_cm4.ld puts it alone at 0x08004000).
///
/// Blocks of layout version 1 (128 bytes) and 2 (256 bytes) are found and read; a block is
/// written only over a version-2 block (the firmware in an image reads its own layout only, and
/// has room for its own size), so a version-1 image is refused, never half-upgraded. A block with
/// a good CRC but a version or length this tool does not know is refused as "another layout".
///
/// Host C; reentrant; the image lives in memory (files up to 64 MiB).
#ifndef CALIB_IMAGE_H
#define CALIB_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "odo/odo_params.h"
#include "odo_out.h"

typedef enum { IMG_BIN = 0, IMG_HEX = 1, IMG_ELF = 2 } img_format_t;

typedef struct {
    size_t line_start; ///< offset of the record's ':' in the file
    uint64_t addr;     ///< absolute address of its first data byte
    unsigned len;
} img_hex_rec_t;

typedef struct {
    img_format_t fmt;
    uint8_t *file; ///< the file's bytes
    size_t file_len;
    uint64_t block_addr;            ///< ELF/HEX: address; BIN: file offset
    size_t block_file_off;          ///< BIN/ELF: file offset of the block
    uint8_t block[ODO_PARAMS_SIZE]; ///< the block found: block_len bytes, zeros after
    size_t block_len;               ///< its declared size: ODO_PARAMS_V1_SIZE or ODO_PARAMS_SIZE
    unsigned version;               ///< its layout version (1 or 2)
    odo_params_status_t status;     ///< odo_params_decode of the block found
    unsigned mode;                  ///< the file's permission bits
    /* HEX only */
    img_hex_rec_t *rec;
    size_t n_rec;
} img_t;

/// Read and locate the block. Returns 0 with *img filled (img->status says whether the block
/// decodes: OK, or CRC/RANGE for a located but damaged or out-of-range block), or -1 with a
/// message: unreadable, no block, unknown layout or version, truncated, malformed HEX/ELF,
/// ambiguous. Free with img_free.
int img_load(const char *path, img_t *img, char *err, size_t errlen);

void img_free(img_t *img);

const char *img_format_name(img_format_t f);

/// Write the image with `block` (a current-version block, ODO_PARAMS_SIZE bytes) in place of the
/// old one to `out_path`: a temporary file in the same directory, flushed, read back and checked,
/// then renamed over out_path (keeping the source file's permission bits), by hostlib/odo_out.h's
/// rule: out_path must be absent or a regular file, and neither one of `ins` (may be NULL) nor
/// inside an input folder. Refused (-1) when the image holds a block of another size (a version-1
/// image). On any error nothing but the old state remains. Returns 0, or -1.
int img_write_patched(const img_t *img, const uint8_t block[ODO_PARAMS_SIZE], const char *out_path,
                      const odo_out_inputs_t *ins, char *err, size_t errlen);

#endif
