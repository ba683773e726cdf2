/// Firmware image formats (tools/calib/image.h): a block found by magic in a raw image among
/// decoys, an Intel HEX whose records straddle the block, and every refusal the issue lists
/// (wrong layout or version, truncated, malformed, a version-1 image), with the original left
/// untouched.
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check_support.h"
#include "image.h"

static char g_dir[] = "/tmp/odo_calib_img_XXXXXX";

static void path_in(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", g_dir, name); }

static void put(const char *path, const void *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    ck_assert_ptr_nonnull(f);
    ck_assert_uint_eq(fwrite(b, 1, n, f), n);
    fclose(f);
}

static size_t get(const char *path, uint8_t *b, size_t cap)
{
    FILE *f = fopen(path, "rb");
    ck_assert_ptr_nonnull(f);
    const size_t n = fread(b, 1, cap, f);
    fclose(f);
    return n;
}

static void block_with(uint8_t b[ODO_PARAMS_SIZE], int32_t ed_q30)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.truck[0].ed_q30 = ed_q30;
    ck_assert_uint_eq(odo_params_encode(&p, b, ODO_PARAMS_SIZE), ODO_PARAMS_SIZE);
}

/// A raw image: code with the magic in a literal pool (a decoy), then the block at 0x4000.
START_TEST(raw_image_block_is_found_among_decoys_and_patched_in_place)
{
    static uint8_t img[0x5000], back[0x5000];
    for (size_t i = 0; i < sizeof img; ++i) {
        img[i] = (uint8_t)(i * 7U);
    }
    memcpy(img + 0x100, "ODOP\x02\x00", 6); /* decoy */
    block_with(img + 0x4000, 1 << 30);
    char path[256], out[256], err[512];
    path_in(path, sizeof path, "fw.bin");
    path_in(out, sizeof out, "fw-new.bin");
    put(path, img, sizeof img);
    img_t m;
    ck_assert_msg(img_load(path, &m, err, sizeof err) == 0, "%s", err);
    ck_assert_uint_eq(m.block_addr, 0x4000);
    ck_assert_int_eq(m.status, ODO_PARAMS_OK);
    uint8_t nb[ODO_PARAMS_SIZE];
    block_with(nb, (int32_t)(1.001 * (1 << 30)));
    ck_assert_msg(img_write_patched(&m, nb, out, NULL, err, sizeof err) == 0, "%s", err);
    img_free(&m);
    ck_assert_uint_eq(get(out, back, sizeof back), sizeof img);
    ck_assert_mem_eq(back, img, 0x4000);
    ck_assert_mem_eq(back + 0x4000, nb, ODO_PARAMS_SIZE);
    ck_assert_mem_eq(back + 0x4000 + ODO_PARAMS_SIZE, img + 0x4000 + ODO_PARAMS_SIZE,
                     sizeof img - 0x4000 - ODO_PARAMS_SIZE);
    ck_assert_uint_eq(get(path, back, sizeof back), sizeof img); /* original untouched */
    ck_assert_mem_eq(back, img, sizeof img);
}
END_TEST

/// Refusals: another layout version (with a good CRC), a truncated block, no block at all, two
/// valid blocks; and a read-only destination leaves nothing behind.
START_TEST(raw_image_refusals_name_the_problem)
{
    static uint8_t img[0x300];
    memset(img, 0xFF, sizeof img);
    block_with(img + 0x100, 1 << 30);
    char path[256], err[512];
    path_in(path, sizeof path, "bad.bin");
    img_t m;

    img[0x104] = 3; /* version 3, CRC recomputed: another layout */
    const uint32_t crc = odo_crc32(img + 0x100, ODO_PARAMS_CRC_OFFSET);
    for (unsigned k = 0; k < 4U; ++k) {
        img[0x100 + ODO_PARAMS_CRC_OFFSET + k] = (uint8_t)(crc >> (8U * k));
    }
    put(path, img, sizeof img);
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "version 3") != NULL && strstr(err, "versions 1 (128 bytes) and 2") != NULL, "%s", err);

    block_with(img + 0x100, 1 << 30);
    put(path, img, 0x100 + 60); /* truncated in the middle of the block */
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "truncated") != NULL, "%s", err);

    put(path, img, 0x100); /* no block */
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "no parameter block") != NULL, "%s", err);

    block_with(img, 1 << 30); /* two valid blocks */
    put(path, img, sizeof img);
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "ambiguous") != NULL, "%s", err);

    memset(img, 0xFF, 0x100);
    put(path, img, sizeof img);
    ck_assert_msg(img_load(path, &m, err, sizeof err) == 0, "%s", err);
    uint8_t nb[ODO_PARAMS_SIZE];
    block_with(nb, 1 << 30);
    ck_assert_int_eq(img_write_patched(&m, nb, "/proc/odo-calib-readonly.bin", NULL, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "cannot create") != NULL, "%s", err);
    img_free(&m);
}
END_TEST

static void hex_rec(FILE *f, unsigned type, unsigned addr16, const uint8_t *d, unsigned n)
{
    unsigned sum = n + (addr16 >> 8) + (addr16 & 0xFF) + type;
    fprintf(f, ":%02X%04X%02X", n, addr16, type);
    for (unsigned i = 0; i < n; ++i) {
        fprintf(f, "%02X", d[i]);
        sum += d[i];
    }
    fprintf(f, "%02X\r\n", (0x100 - (sum & 0xFF)) & 0xFF);
}

/// Intel HEX: the block at 0x08004000 spread over records of 24 bytes that straddle both its
/// ends; after patching, every record's checksum is valid and the lines not holding the block are
/// byte-identical.
START_TEST(intel_hex_records_straddling_the_block_are_patched_with_new_checksums)
{
    static uint8_t flat[512];
    memset(flat, 0xA5, sizeof flat);
    block_with(flat + 200, 1 << 30); /* 0x08004000 = base + 200 */
    const unsigned base16 = 0x4000 - 200;
    char path[256], out[256], err[512];
    path_in(path, sizeof path, "fw.hex");
    path_in(out, sizeof out, "fw-new.hex");
    FILE *f = fopen(path, "wb");
    const uint8_t ela[2] = {0x08, 0x00};
    hex_rec(f, 4, 0, ela, 2);
    for (unsigned off = 0; off < sizeof flat; off += 24) {
        const unsigned n = sizeof flat - off < 24 ? (unsigned)(sizeof flat - off) : 24;
        hex_rec(f, 0, base16 + off, flat + off, n);
    }
    const uint8_t start[4] = {0x08, 0x00, 0x80, 0x01};
    hex_rec(f, 5, 0, start, 4);
    hex_rec(f, 1, 0, NULL, 0);
    fclose(f);
    img_t m;
    ck_assert_msg(img_load(path, &m, err, sizeof err) == 0, "%s", err);
    ck_assert_uint_eq(m.fmt, IMG_HEX);
    ck_assert_uint_eq(m.block_addr, 0x08004000);
    uint8_t nb[ODO_PARAMS_SIZE];
    block_with(nb, (int32_t)(0.999 * (1 << 30)));
    ck_assert_msg(img_write_patched(&m, nb, out, NULL, err, sizeof err) == 0, "%s", err);
    img_free(&m);
    img_t m2;
    ck_assert_msg(img_load(out, &m2, err, sizeof err) == 0, "%s", err); /* checksums verified on load */
    ck_assert_mem_eq(m2.block, nb, ODO_PARAMS_SIZE);
    ck_assert_uint_eq(m2.file_len, m2.file_len);
    img_free(&m2);
    static uint8_t a[8192], b[8192];
    const size_t na = get(path, a, sizeof a), nb2 = get(out, b, sizeof b);
    ck_assert_uint_eq(na, nb2);
    ck_assert_mem_eq(a, b, 40); /* the first lines (before the block) are unchanged */

    /* Truncated HEX (no end-of-file record) and a checksum error. */
    put(path, a, na - 13);
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "truncated") != NULL || strstr(err, "length") != NULL, "%s", err);
    a[20] = a[20] == '0' ? '1' : '0';
    put(path, a, na);
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "checksum") != NULL, "%s", err);
}
END_TEST

/// A version-1 block (128 bytes) as firmware before version 2 carried it: bytes [0, 124) of a
/// version-2 block, relabelled, with its CRC at 124 (odo_params.h).
static void v1_block_with(uint8_t b[ODO_PARAMS_V1_SIZE], int32_t ed_q30)
{
    uint8_t v2[ODO_PARAMS_SIZE];
    block_with(v2, ed_q30);
    memcpy(b, v2, 124);
    b[4] = 1;
    b[6] = 128;
    b[7] = 0;
    const uint32_t crc = odo_crc32(b, 124);
    for (int k = 0; k < 4; ++k) {
        b[124 + k] = (uint8_t)(crc >> (8 * k));
    }
}

/// An image built before version 2 (a raw .bin and an Intel HEX with a 128-byte block) still
/// reads, as version 1, but writing a version-2 block into it is refused and leaves nothing: its
/// firmware cannot read version 2, and the bytes after its block are not the block's.
START_TEST(version_1_images_read_but_are_never_written)
{
    static uint8_t img[0x4100];
    for (size_t i = 0; i < sizeof img; ++i) {
        img[i] = (uint8_t)(i * 13U);
    }
    v1_block_with(img + 0x4000, (int32_t)(1.002 * (1 << 30)));
    char path[256], out[256], err[512];
    path_in(path, sizeof path, "v1.bin");
    path_in(out, sizeof out, "v1-new.bin");
    put(path, img, sizeof img);
    img_t m;
    ck_assert_msg(img_load(path, &m, err, sizeof err) == 0, "%s", err);
    ck_assert_uint_eq(m.block_addr, 0x4000);
    ck_assert_uint_eq(m.version, 1);
    ck_assert_uint_eq(m.block_len, ODO_PARAMS_V1_SIZE);
    ck_assert_int_eq(m.status, ODO_PARAMS_OK);
    uint8_t nb[ODO_PARAMS_SIZE];
    block_with(nb, 1 << 30);
    ck_assert_int_eq(img_write_patched(&m, nb, out, NULL, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "version-1 parameter block (128 bytes)") != NULL, "%s", err);
    img_free(&m);
    ck_assert_int_eq(access(out, F_OK), -1);
    static uint8_t back[sizeof img];
    ck_assert_uint_eq(get(path, back, sizeof back), sizeof img);
    ck_assert_mem_eq(back, img, sizeof img);

    /* A version-1 block cut off before its 128 bytes is truncated, not another layout. */
    put(path, img, 0x4000 + 100);
    ck_assert_int_eq(img_load(path, &m, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "truncated") != NULL, "%s", err);

    /* The same block in an Intel HEX. */
    path_in(path, sizeof path, "v1.hex");
    FILE *f = fopen(path, "wb");
    const uint8_t ela[2] = {0x08, 0x00};
    hex_rec(f, 4, 0, ela, 2);
    for (unsigned off = 0; off < 0x100; off += 16) {
        hex_rec(f, 0, 0x4000 + off, img + 0x4000 + off, 16);
    }
    hex_rec(f, 1, 0, NULL, 0);
    fclose(f);
    ck_assert_msg(img_load(path, &m, err, sizeof err) == 0, "%s", err);
    ck_assert_uint_eq(m.version, 1);
    ck_assert_uint_eq(m.block_addr, 0x08004000);
    ck_assert_int_eq(img_write_patched(&m, nb, out, NULL, err, sizeof err), -1);
    img_free(&m);
}
END_TEST

int main(void)
{
    if (mkdtemp(g_dir) == NULL) {
        return 1;
    }
    Suite *s = suite_create("calib_image");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, raw_image_block_is_found_among_decoys_and_patched_in_place);
    tcase_add_test(tc, raw_image_refusals_name_the_problem);
    tcase_add_test(tc, intel_hex_records_straddling_the_block_are_patched_with_new_checksums);
    tcase_add_test(tc, version_1_images_read_but_are_never_written);
    suite_add_tcase(s, tc);
    const int rc = ts_run_suite(s);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    if (system(cmd) != 0) {
        return 1;
    }
    return rc;
}
