/// Firmware image formats. See image.h.
#include "image.h"
#include "odo_out.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAX_IMAGE_BYTES ((size_t)64 << 20)

const char *img_format_name(img_format_t f)
{
    switch (f) {
    case IMG_BIN: return "raw binary";
    case IMG_HEX: return "Intel HEX";
    case IMG_ELF: return "ELF";
    }
    return "?";
}

static uint64_t rd_le(const uint8_t *b, unsigned n)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < n; ++i) {
        v |= (uint64_t)b[i] << (8 * i);
    }
    return v;
}

/// "versions 1 (128 bytes) and 2 (256 bytes)": what this tool reads, for messages.
static const char *known_layouts(void) { return "versions 1 (128 bytes) and 2 (256 bytes)"; }

typedef enum { CAND_TRUNCATED, CAND_GOOD, CAND_BAD_CRC, CAND_OTHER_LAYOUT, CAND_NOISE } cand_t;

/// Classify an 'ODOP' at b with `avail` readable bytes: a block of a version this tool reads
/// (good, or with a bad CRC), cut off before its declared size, a block of another layout (its
/// declared length holds a good CRC-32 in its last 4 bytes), or just the magic in code/data.
static cand_t classify(const uint8_t *b, size_t avail)
{
    if (avail < ODO_PARAMS_HEADER_SIZE) {
        return CAND_TRUNCATED;
    }
    const size_t len = (size_t)rd_le(b + 6, 2);
    const size_t size = odo_params_version_size((uint16_t)rd_le(b + 4, 2));
    if (size != 0U && len == size) {
        if (avail < size) {
            return CAND_TRUNCATED;
        }
        odo_params_t p;
        const odo_params_status_t st = odo_params_parse(b, size, &p);
        return (st == ODO_PARAMS_OK || st == ODO_PARAMS_ERR_RANGE) ? CAND_GOOD : CAND_BAD_CRC;
    }
    if (len >= ODO_PARAMS_HEADER_SIZE + 4U && len <= avail &&
        odo_crc32(b, len - 4U) == (uint32_t)rd_le(b + len - 4U, 4)) {
        return CAND_OTHER_LAYOUT;
    }
    return CAND_NOISE;
}

/// Find the one good block among the magic's occurrences in buf (valid: NULL or a per-byte mask).
/// Returns 0 with *off, or -1 with a message naming offsets as base + offset.
static int locate(const uint8_t *buf, size_t len, const uint8_t *valid, uint64_t base, const char *what, size_t *off,
                  char *err, size_t errlen)
{
    size_t n_cand = 0, n_good = 0, good = 0, n_other = 0, other = 0, n_bad_crc = 0, bad_crc = 0;
    int truncated = 0;
    size_t trunc_at = 0;
    for (size_t i = 0; i + 4 <= len; ++i) {
        if (memcmp(buf + i, "ODOP", 4) != 0) {
            continue;
        }
        if (valid != NULL && !(valid[i] && valid[i + 1] && valid[i + 2] && valid[i + 3])) {
            continue;
        }
        n_cand++;
        size_t avail = len - i;
        if (valid != NULL) {
            size_t k = 0;
            while (k < avail && k <= 0xFFFFU && valid[i + k]) {
                k++;
            }
            avail = k;
        }
        switch (classify(buf + i, avail)) {
        case CAND_GOOD:
            if (n_good++ == 0) {
                good = i;
            }
            break;
        case CAND_BAD_CRC:
            if (n_bad_crc++ == 0) {
                bad_crc = i;
            }
            break;
        case CAND_OTHER_LAYOUT:
            if (n_other++ == 0) {
                other = i;
            }
            break;
        case CAND_TRUNCATED:
            truncated = 1;
            trunc_at = i;
            break;
        case CAND_NOISE: break;
        }
    }
    if (n_good == 1) {
        *off = good;
        return 0;
    }
    if (n_good > 1) {
        snprintf(err, errlen, "%s: %zu valid parameter blocks found: ambiguous, refusing to choose", what, n_good);
        return -1;
    }
    if (n_other > 0) {
        /* A block with a good CRC whose header this tool does not accept: another layout. */
        const uint8_t *b = buf + other;
        snprintf(err, errlen,
                 "%s: parameter block at 0x%llx has layout version %u, length %u; this tool "
                 "reads %s: refusing to touch it",
                 what, (unsigned long long)(base + other), (unsigned)rd_le(b + 4, 2), (unsigned)rd_le(b + 6, 2),
                 known_layouts());
        return -1;
    }
    if (truncated) {
        snprintf(err, errlen,
                 "%s: truncated: the parameter block starting at 0x%llx is cut off before its "
                 "declared length",
                 what, (unsigned long long)(base + trunc_at));
        return -1;
    }
    if (n_bad_crc == 1) {
        *off = bad_crc; /* the only block there is, damaged: the caller decides (write --force) */
        return 0;
    }
    snprintf(err, errlen,
             "%s: no parameter block found (%zu 'ODOP' candidates, none with a valid header and "
             "CRC-32)",
             what, n_cand);
    return -1;
}

static int load_elf(img_t *img, const char *path, char *err, size_t errlen)
{
    const uint8_t *b = img->file;
    const size_t n = img->file_len;
    if (n < 16 || (b[4] != 1 && b[4] != 2) || b[5] != 1) {
        snprintf(err, errlen, "%s: %s", path,
                 n < 16 ? "truncated ELF header" : "only little-endian ELF32/ELF64 is supported");
        return -1;
    }
    const int is64 = b[4] == 2;
    const size_t ehsize = is64 ? 64 : 52;
    if (n < ehsize) {
        snprintf(err, errlen, "%s: truncated ELF header", path);
        return -1;
    }
    const uint64_t shoff = is64 ? rd_le(b + 40, 8) : rd_le(b + 32, 4);
    const unsigned shentsize = (unsigned)rd_le(b + (is64 ? 58 : 46), 2);
    const unsigned shnum = (unsigned)rd_le(b + (is64 ? 60 : 48), 2);
    const unsigned shstrndx = (unsigned)rd_le(b + (is64 ? 62 : 50), 2);
    if (shentsize < (is64 ? 64U : 40U) || shnum == 0 || shstrndx >= shnum) {
        snprintf(err, errlen, "%s: ELF without a usable section header table", path);
        return -1;
    }
    if (shoff > n || (uint64_t)shentsize * shnum > n - shoff) {
        snprintf(err, errlen, "%s: truncated ELF: section headers end beyond the file (%zu bytes)", path, n);
        return -1;
    }
#define SH(i)      (b + shoff + (uint64_t)(i)*shentsize)
#define SH_OFF(s)  (is64 ? rd_le((s) + 24, 8) : rd_le((s) + 16, 4))
#define SH_SIZE(s) (is64 ? rd_le((s) + 32, 8) : rd_le((s) + 20, 4))
#define SH_ADDR(s) (is64 ? rd_le((s) + 16, 8) : rd_le((s) + 12, 4))
    const uint8_t *strsh = SH(shstrndx);
    const uint64_t stroff = SH_OFF(strsh), strsize = SH_SIZE(strsh);
    if (stroff > n || strsize > n - stroff) {
        snprintf(err, errlen, "%s: truncated ELF: section names beyond the file", path);
        return -1;
    }
    for (unsigned i = 0; i < shnum; ++i) {
        const uint8_t *s = SH(i);
        const uint64_t name = rd_le(s, 4);
        if (name >= strsize) {
            continue;
        }
        const char *nm = (const char *)b + stroff + name;
        const size_t maxlen = (size_t)(strsize - name);
        if (strnlen(nm, maxlen) == maxlen || strcmp(nm, ".odo_params") != 0) {
            continue;
        }
        const uint64_t off = SH_OFF(s), size = SH_SIZE(s);
        if (rd_le(s + 4, 4) == 8U /* SHT_NOBITS */) {
            snprintf(err, errlen, "%s: section .odo_params has no file content (NOBITS)", path);
            return -1;
        }
        if (size < ODO_PARAMS_HEADER_SIZE) {
            snprintf(err, errlen, "%s: section .odo_params is %llu bytes, too small for a parameter block", path,
                     (unsigned long long)size);
            return -1;
        }
        if (off > n || ODO_PARAMS_HEADER_SIZE > n - off) {
            snprintf(err, errlen,
                     "%s: truncated ELF: section .odo_params (offset %llu) lies beyond the end of "
                     "the file (%zu bytes)",
                     path, (unsigned long long)off, n);
            return -1;
        }
        img->block_file_off = (size_t)off;
        img->block_addr = SH_ADDR(s);
        const uint8_t *blk = b + off;
        if (memcmp(blk, "ODOP", 4) != 0) {
            snprintf(err, errlen, "%s: section .odo_params does not start with the magic 'ODOP'", path);
            return -1;
        }
        const size_t want = odo_params_version_size((uint16_t)rd_le(blk + 4, 2));
        if (want == 0U || rd_le(blk + 6, 2) != want) {
            snprintf(err, errlen, "%s: .odo_params holds layout version %u, length %u; this tool reads %s", path,
                     (unsigned)rd_le(blk + 4, 2), (unsigned)rd_le(blk + 6, 2), known_layouts());
            return -1;
        }
        if (size < want) {
            snprintf(err, errlen, "%s: section .odo_params is %llu bytes, its version-%u block needs %zu", path,
                     (unsigned long long)size, (unsigned)rd_le(blk + 4, 2), want);
            return -1;
        }
        if (want > n - off) {
            snprintf(err, errlen,
                     "%s: truncated ELF: section .odo_params (offset %llu) lies beyond the end of "
                     "the file (%zu bytes)",
                     path, (unsigned long long)off, n);
            return -1;
        }
        img->block_len = want;
        return 0;
    }
#undef SH
#undef SH_OFF
#undef SH_SIZE
#undef SH_ADDR
    snprintf(err, errlen, "%s: ELF has no .odo_params section", path);
    return -1;
}

static int hexval(int c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    return -1;
}

static int hexbyte(const uint8_t *p)
{
    const int h = hexval(p[0]), l = hexval(p[1]);
    return h < 0 || l < 0 ? -1 : h * 16 + l;
}

static int load_hex(img_t *img, const char *path, uint8_t **flat_out, uint8_t **valid_out, uint64_t *base_out,
                    size_t *len_out, char *err, size_t errlen)
{
    const uint8_t *b = img->file;
    const size_t n = img->file_len;
    size_t cap = 64;
    img->rec = malloc(cap * sizeof *img->rec);
    if (img->rec == NULL) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    uint64_t upper = 0, lo = UINT64_MAX, hi = 0;
    int eof = 0;
    unsigned lineno = 0;
    size_t i = 0;
    while (i < n) {
        size_t e = i;
        while (e < n && b[e] != '\n') {
            e++;
        }
        size_t end = e;
        while (end > i && (b[end - 1] == '\r' || b[end - 1] == ' ' || b[end - 1] == '\t')) {
            end--;
        }
        lineno++;
        if (end > i) {
            if (eof) {
                snprintf(err, errlen, "%s:%u: data after the end-of-file record", path, lineno);
                return -1;
            }
            if (b[i] != ':' || (end - i) < 11 || ((end - i - 1) % 2) != 0) {
                snprintf(err, errlen, "%s:%u: not an Intel HEX record", path, lineno);
                return -1;
            }
            uint8_t rec[262];
            const size_t nb = (end - i - 1) / 2;
            if (nb > sizeof rec) {
                snprintf(err, errlen, "%s:%u: record too long", path, lineno);
                return -1;
            }
            unsigned sum = 0;
            for (size_t k = 0; k < nb; ++k) {
                const int v = hexbyte(b + i + 1 + 2 * k);
                if (v < 0) {
                    snprintf(err, errlen, "%s:%u: not a hex digit", path, lineno);
                    return -1;
                }
                rec[k] = (uint8_t)v;
                sum += (unsigned)v;
            }
            const unsigned ll = rec[0], type = rec[3];
            if (nb != ll + 5U) {
                snprintf(err, errlen, "%s:%u: record length %u does not match its %zu data bytes (truncated?)", path,
                         lineno, ll, nb >= 5 ? nb - 5 : 0);
                return -1;
            }
            if ((sum & 0xFFU) != 0U) {
                snprintf(err, errlen, "%s:%u: checksum error", path, lineno);
                return -1;
            }
            const uint64_t a16 = ((uint64_t)rec[1] << 8) | rec[2];
            switch (type) {
            case 0x00: {
                if (img->n_rec == cap) {
                    cap *= 2;
                    img_hex_rec_t *nr = realloc(img->rec, cap * sizeof *nr);
                    if (nr == NULL) {
                        snprintf(err, errlen, "out of memory");
                        return -1;
                    }
                    img->rec = nr;
                }
                img_hex_rec_t *r = &img->rec[img->n_rec++];
                r->line_start = i;
                r->addr = upper + a16;
                r->len = ll;
                if (ll > 0) {
                    lo = r->addr < lo ? r->addr : lo;
                    hi = r->addr + ll > hi ? r->addr + ll : hi;
                }
                break;
            }
            case 0x01: eof = 1; break;
            case 0x02: upper = (((uint64_t)rec[4] << 8) | rec[5]) << 4; break;
            case 0x04: upper = (((uint64_t)rec[4] << 8) | rec[5]) << 16; break;
            case 0x03:
            case 0x05: break;
            default: snprintf(err, errlen, "%s:%u: unknown record type %02X", path, lineno, type); return -1;
            }
        }
        i = e + 1;
    }
    if (!eof) {
        snprintf(err, errlen, "%s: truncated Intel HEX: no end-of-file record", path);
        return -1;
    }
    if (lo == UINT64_MAX) {
        snprintf(err, errlen, "%s: Intel HEX without data", path);
        return -1;
    }
    if (hi - lo > MAX_IMAGE_BYTES) {
        snprintf(err, errlen, "%s: Intel HEX spans %llu bytes, more than this tool handles", path,
                 (unsigned long long)(hi - lo));
        return -1;
    }
    const size_t span = (size_t)(hi - lo);
    uint8_t *flat = calloc(span, 1), *valid = calloc(span, 1);
    if (flat == NULL || valid == NULL) {
        free(flat);
        free(valid);
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    for (size_t k = 0; k < img->n_rec; ++k) {
        const img_hex_rec_t *r = &img->rec[k];
        for (unsigned j = 0; j < r->len; ++j) {
            const size_t at = (size_t)(r->addr - lo) + j;
            flat[at] = (uint8_t)hexbyte(b + r->line_start + 9 + 2 * j);
            valid[at] = 1;
        }
    }
    *flat_out = flat;
    *valid_out = valid;
    *base_out = lo;
    *len_out = span;
    return 0;
}

int img_load(const char *path, img_t *img, char *err, size_t errlen)
{
    memset(img, 0, sizeof *img);
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    struct stat sb;
    if (fstat(fileno(f), &sb) != 0 || !S_ISREG(sb.st_mode)) {
        fclose(f);
        snprintf(err, errlen, "%s: not a regular file", path);
        return -1;
    }
    img->mode = (unsigned)(sb.st_mode & 07777);
    /* As large as the file says it is (+1 to see it grew), not the 64 MiB cap every time: the
     * fuzz campaign ran at 5 loads a second with the cap allocated under ASan. */
    const size_t cap =
        (sb.st_size < 0 || (uint64_t)sb.st_size >= MAX_IMAGE_BYTES) ? MAX_IMAGE_BYTES + 1 : (size_t)sb.st_size + 1U;
    img->file = malloc(cap);
    if (img->file == NULL) {
        fclose(f);
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    img->file_len = fread(img->file, 1, cap, f);
    const int bad = ferror(f) || (img->file_len == cap && cap <= MAX_IMAGE_BYTES); /* grew while read */
    fclose(f);
    if (bad || img->file_len > MAX_IMAGE_BYTES) {
        snprintf(err, errlen, bad ? "%s: read error" : "%s: larger than 64 MiB", path);
        img_free(img);
        return -1;
    }
    const uint8_t *b = img->file;
    size_t k = 0;
    while (k < img->file_len && (b[k] == ' ' || b[k] == '\t' || b[k] == '\r' || b[k] == '\n')) {
        k++;
    }
    int rc;
    if (img->file_len >= 4 && memcmp(b,
                                     "\x7f"
                                     "ELF",
                                     4) == 0) {
        img->fmt = IMG_ELF;
        rc = load_elf(img, path, err, errlen);
        if (rc == 0) {
            memcpy(img->block, b + img->block_file_off, img->block_len);
        }
    } else if (k < img->file_len && b[k] == ':') {
        img->fmt = IMG_HEX;
        uint8_t *flat = NULL, *valid = NULL;
        uint64_t base = 0;
        size_t span = 0, off = 0;
        rc = load_hex(img, path, &flat, &valid, &base, &span, err, errlen);
        if (rc == 0) {
            rc = locate(flat, span, valid, base, path, &off, err, errlen);
        }
        if (rc == 0) {
            img->block_addr = base + off;
            img->block_len = odo_params_version_size((uint16_t)rd_le(flat + off + 4, 2));
            memcpy(img->block, flat + off, img->block_len);
        }
        free(flat);
        free(valid);
    } else {
        img->fmt = IMG_BIN;
        size_t off = 0;
        rc = locate(b, img->file_len, NULL, 0, path, &off, err, errlen);
        if (rc == 0) {
            img->block_file_off = off;
            img->block_addr = off;
            img->block_len = odo_params_version_size((uint16_t)rd_le(b + off + 4, 2));
            memcpy(img->block, b + off, img->block_len);
        }
    }
    if (rc != 0) {
        img_free(img);
        return -1;
    }
    img->version = (unsigned)rd_le(img->block + 4, 2);
    odo_params_t p;
    img->status = odo_params_decode(img->block, img->block_len, &p);
    return 0;
}

void img_free(img_t *img)
{
    free(img->file);
    free(img->rec);
    memset(img, 0, sizeof *img);
}

static void put_hex(uint8_t *p, unsigned v)
{
    static const char d[] = "0123456789ABCDEF";
    p[0] = (uint8_t)d[(v >> 4) & 0xF];
    p[1] = (uint8_t)d[v & 0xF];
}

int img_write_patched(const img_t *img, const uint8_t block[ODO_PARAMS_SIZE], const char *out_path,
                      const odo_out_inputs_t *ins, char *err, size_t errlen)
{
    if (img->block_len != ODO_PARAMS_SIZE) {
        /* The firmware in the image reads its own layout only, and has room for that many bytes. */
        snprintf(err, errlen,
                 "the image holds a version-%u parameter block (%zu bytes): its firmware reads that "
                 "layout only, and this tool writes version %u (%u bytes); rebuild the image with a "
                 "firmware that reads version %u, or write it with the odo-calib of its own release",
                 img->version, img->block_len, ODO_PARAMS_VERSION, ODO_PARAMS_SIZE, ODO_PARAMS_VERSION);
        return -1;
    }
    uint8_t *out = malloc(img->file_len ? img->file_len : 1);
    if (out == NULL) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    memcpy(out, img->file, img->file_len);
    if (img->fmt == IMG_HEX) {
        for (size_t k = 0; k < img->n_rec; ++k) {
            const img_hex_rec_t *r = &img->rec[k];
            if (r->addr + r->len <= img->block_addr || r->addr >= img->block_addr + ODO_PARAMS_SIZE) {
                continue;
            }
            for (unsigned j = 0; j < r->len; ++j) {
                const uint64_t a = r->addr + j;
                if (a >= img->block_addr && a < img->block_addr + ODO_PARAMS_SIZE) {
                    put_hex(out + r->line_start + 9 + 2 * j, block[a - img->block_addr]);
                }
            }
            unsigned sum = 0;
            for (unsigned j = 0; j < 4U + r->len; ++j) {
                sum += (unsigned)hexbyte(out + r->line_start + 1 + 2 * j);
            }
            put_hex(out + r->line_start + 9 + 2 * r->len, (0x100U - (sum & 0xFFU)) & 0xFFU);
        }
    } else {
        memcpy(out + img->block_file_off, block, ODO_PARAMS_SIZE);
    }

    /* hostlib/odo_out.h: a fresh temp beside out_path (O_EXCL|O_NOFOLLOW), never a special file. */
    int rc = -1;
    odo_out_file_t o;
    if (odo_out_file_begin(&o, out_path, ins, err, errlen) != 0) {
        goto done;
    }
    if (fwrite(out, 1, img->file_len, o.f) != img->file_len || fflush(o.f) != 0 ||
        fchmod(fileno(o.f), (mode_t)(img->mode ? img->mode : 0644)) != 0) {
        snprintf(err, errlen, "cannot write %s: %s", out_path, strerror(errno));
        odo_out_file_abort(&o);
        goto done;
    }
    /* Read it back the way a user would, before it replaces anything. */
    img_t back;
    char berr[256];
    if (img_load(o.tmp, &back, berr, sizeof berr) != 0 || back.status != ODO_PARAMS_OK ||
        memcmp(back.block, block, ODO_PARAMS_SIZE) != 0) {
        snprintf(err, errlen, "internal error: the patched image does not read back (%s)",
                 back.file == NULL ? berr : "block differs");
        if (back.file != NULL) {
            img_free(&back);
        }
        odo_out_file_abort(&o);
        goto done;
    }
    img_free(&back);
    if (odo_out_file_commit(&o, err, errlen) != 0) {
        goto done;
    }
    rc = 0;
done:
    free(out);
    return rc;
}
