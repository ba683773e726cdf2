/// odo-params: write and inspect the firmware parameter block (odo/odo_params.h).
///
///   odo-params defaults --out FILE   write the default block (temp beside FILE, fsync, rename)
///   odo-params show FILE             decode FILE (version 1 or 2) and print every field as JSON
///   odo-params layout [--out FILE]   the header's field table (ODO_PARAMS_FIELDS) as JSON
///
/// Exit status: 0 success; 1 a rejected block or an I/O error (message on stderr naming the
/// reason); 2 a usage error. Encoding, decoding and range checks are the firmware's own
/// (odo_firmware); this file only moves bytes and formats text.
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "odo/odo_params.h"
#include "odo_cli.h"
#include "odo_out.h"
#include "params_diag.h"
#include "params_json.h"

#define EXIT_REJECTED 1
#define EXIT_USAGE    2

/// Larger files are not parameter blocks or flash dumps of one; refuse rather than read forever.
#define MAX_INPUT_BYTES (1024UL * 1024UL)

static const char *const k_prog = "odo-params";

static void usage_main(FILE *f)
{
    fprintf(f,
            "usage: %s <command> [options]\n"
            "\n"
            "Write and inspect the odometry firmware parameter block (%u bytes, version %u;\n"
            "version-1 blocks of %u bytes are still read).\n"
            "\n"
            "commands:\n"
            "  defaults --out FILE   write the default parameter block to FILE\n"
            "  show FILE             decode FILE, print every field as one JSON object\n"
            "  layout [--out FILE]   print the block's field table (offsets, widths, ranges) as JSON\n"
            "\n"
            "Run '%s <command> --help' for a command's options; '%s --version' prints the version.\n"
            "Exit status: 0 ok, 1 rejected block or I/O error, 2 usage error.\n",
            k_prog, ODO_PARAMS_SIZE, ODO_PARAMS_VERSION, ODO_PARAMS_V1_SIZE, k_prog, k_prog);
}

static void usage_defaults(FILE *f)
{
    fprintf(f,
            "usage: %s defaults --out FILE\n"
            "\n"
            "Write the documented default parameter block (odo_params_defaults) to FILE.\n"
            "The block is written to a fresh temp file beside FILE, flushed to disk and renamed over\n"
            "FILE, so FILE is either the old content or the complete new block; on error nothing is\n"
            "left behind. Missing folders are created; FILE must not be a folder, link or device.\n"
            "\n"
            "options:\n"
            "  -o, --out FILE   output file (required)\n"
            "  -h, --help       show this help\n",
            k_prog);
}

static void usage_show(FILE *f)
{
    fprintf(f,
            "usage: %s show FILE\n"
            "\n"
            "Decode the parameter block in FILE with the firmware's own decoder (magic, version,\n"
            "length, CRC-32, ranges) and print every field as one JSON object on stdout, with\n"
            "\"status\": \"ok\". A version-1 block shows as version 1 with scrub_q30 0. A rejected block\n"
            "prints a JSON object with the status and reason, a message on stderr naming the reason\n"
            "(and the offending field: version, length, crc32, a field, or a reserved byte), and exits 1.\n"
            "\n"
            "options:\n"
            "  -h, --help   show this help\n",
            k_prog);
}

static void usage_layout(FILE *f)
{
    fprintf(f,
            "usage: %s layout [--out FILE]\n"
            "\n"
            "Print the parameter block's field table, expanded from ODO_PARAMS_FIELDS in\n"
            "firmware/include/odo/odo_params.h, as one JSON object: header, sizes and CRC offsets\n"
            "of every version, and per field its JSON name, scope, offsets (one per truck for truck\n"
            "fields), width, type, signedness, range, unit and the version that introduced it.\n"
            "With --out, write it to a temp file beside FILE and rename it over FILE.\n"
            "\n"
            "options:\n"
            "  -o, --out FILE   output file (default: stdout)\n"
            "  -h, --help       show this help\n",
            k_prog);
}

static bool is_help(const char *a) { return strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0; }

/* ---------------------------------------------------------------------------------------------
 * defaults
 * ------------------------------------------------------------------------------------------- */
/// Write b to path by hostlib/odo_out.h's rule: a fresh temp beside it (O_EXCL|O_NOFOLLOW, so a
/// symlink planted at any temp name is never followed), fsync, rename; a FIFO, device, folder or
/// symlink at path is refused. On failure nothing is left behind.
static int write_file_atomic(const char *path, const uint8_t *b, size_t n)
{
    char err[4096 + 256];
    if (odo_out_write(path, b, n, NULL, err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s\n", k_prog, err);
        return -1;
    }
    return 0;
}

static int cmd_defaults(int argc, char **argv)
{
    const char *out = NULL;
    for (int i = 0; i < argc; i++) {
        if (is_help(argv[i])) {
            usage_defaults(stdout);
            return 0;
        }
        if (strcmp(argv[i], "--out") == 0 || strcmp(argv[i], "-o") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "%s: defaults: %s needs a file name\n", k_prog, argv[i]);
                return EXIT_USAGE;
            }
            out = argv[++i];
        } else if (strncmp(argv[i], "--out=", 6) == 0) {
            out = argv[i] + 6;
        } else {
            fprintf(stderr, "%s: defaults: unexpected argument '%s'\n", k_prog, argv[i]);
            usage_defaults(stderr);
            return EXIT_USAGE;
        }
    }
    if (out == NULL || out[0] == '\0') {
        fprintf(stderr, "%s: defaults: --out FILE is required\n", k_prog);
        usage_defaults(stderr);
        return EXIT_USAGE;
    }

    odo_params_t p;
    uint8_t block[ODO_PARAMS_SIZE];
    odo_params_defaults(&p);
    if (odo_params_encode(&p, block, sizeof block) != ODO_PARAMS_SIZE) {
        fprintf(stderr, "%s: internal error: encoding the defaults failed\n", k_prog);
        return EXIT_REJECTED;
    }
    return write_file_atomic(out, block, sizeof block) == 0 ? 0 : EXIT_REJECTED;
}

/* ---------------------------------------------------------------------------------------------
 * show
 * ------------------------------------------------------------------------------------------- */
static uint16_t le16(const uint8_t *b) { return (uint16_t)(b[0] | (b[1] << 8)); }

static uint32_t le32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static const char *status_key(odo_params_status_t s)
{
    switch (s) {
    case ODO_PARAMS_OK: return "ok";
    case ODO_PARAMS_ERR_SHORT: return "short";
    case ODO_PARAMS_ERR_MAGIC: return "magic";
    case ODO_PARAMS_ERR_VERSION: return "version";
    case ODO_PARAMS_ERR_LENGTH: return "length";
    case ODO_PARAMS_ERR_CRC: return "crc";
    case ODO_PARAMS_ERR_RANGE: return "range";
    case ODO_PARAMS_ERR_ARG: return "arg";
    }
    return "unknown";
}

/// Print s as a JSON string (file names may hold anything).
static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *c = (const unsigned char *)s; *c != '\0'; c++) {
        if (*c == '"' || *c == '\\') {
            fprintf(f, "\\%c", *c);
        } else if (*c < 0x20U) {
            fprintf(f, "\\u%04x", *c);
        } else {
            fputc(*c, f);
        }
    }
    fputc('"', f);
}

static void print_json(FILE *f, const char *path, const uint8_t *b, const odo_params_t *p)
{
    /* The block as stored: a version-1 block keeps its version, length and CRC offset. */
    const size_t crc_off = odo_params_version_size(le16(&b[4])) - 4U;
    fprintf(f, "{\"file\": ");
    json_str(f, path);
    fprintf(f,
            ", \"status\": \"ok\", \"magic\": \"ODOP\", \"version\": %u, \"length\": %u, "
            "\"crc32\": \"0x%08" PRIX32 "\",\n",
            (unsigned)le16(&b[4]), (unsigned)le16(&b[6]), le32(&b[crc_off]));
    odo_params_json_fields(f, p, le16(&b[4]));
    fputs("}\n", f);
}

static int cmd_show(int argc, char **argv)
{
    const char *path = NULL;
    for (int i = 0; i < argc; i++) {
        if (is_help(argv[i])) {
            usage_show(stdout);
            return 0;
        }
        if (argv[i][0] == '-' && argv[i][1] != '\0') {
            fprintf(stderr, "%s: show: unknown option '%s'\n", k_prog, argv[i]);
            usage_show(stderr);
            return EXIT_USAGE;
        }
        if (path != NULL) {
            fprintf(stderr, "%s: show: exactly one FILE expected\n", k_prog);
            usage_show(stderr);
            return EXIT_USAGE;
        }
        path = argv[i];
    }
    if (path == NULL) {
        fprintf(stderr, "%s: show: FILE is required\n", k_prog);
        usage_show(stderr);
        return EXIT_USAGE;
    }

    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "%s: cannot open %s: %s\n", k_prog, path, strerror(errno));
        return EXIT_REJECTED;
    }
    uint8_t *buf = malloc(MAX_INPUT_BYTES + 1);
    if (buf == NULL) {
        fclose(f);
        fprintf(stderr, "%s: out of memory\n", k_prog);
        return EXIT_REJECTED;
    }
    size_t n = fread(buf, 1, MAX_INPUT_BYTES + 1, f);
    bool read_err = ferror(f) != 0;
    fclose(f);
    if (read_err) {
        fprintf(stderr, "%s: cannot read %s\n", k_prog, path);
        free(buf);
        return EXIT_REJECTED;
    }
    if (n > MAX_INPUT_BYTES) {
        fprintf(stderr, "%s: %s: larger than %lu bytes, not a parameter block\n", k_prog, path, MAX_INPUT_BYTES);
        free(buf);
        return EXIT_REJECTED;
    }

    odo_params_t p;
    odo_params_status_t st = odo_params_decode(buf, n, &p);
    if (st == ODO_PARAMS_OK) {
        print_json(stdout, path, buf, &p);
        free(buf);
        return 0;
    }

    char detail[192];
    char field[64];
    odo_params_explain(st, buf, n, field, sizeof field, detail, sizeof detail);
    printf("{\"file\": ");
    json_str(stdout, path);
    printf(", \"status\": \"%s\", \"reason\": ", status_key(st));
    json_str(stdout, odo_params_status_str(st));
    if (field[0] != '\0') {
        printf(", \"field\": ");
        json_str(stdout, field);
    }
    if (detail[0] != '\0') {
        printf(", \"detail\": ");
        json_str(stdout, detail);
    }
    printf("}\n");
    fprintf(stderr, "%s: %s: rejected: %s%s%s\n", k_prog, path, odo_params_status_str(st),
            detail[0] != '\0' ? ": " : "", detail);
    free(buf);
    return EXIT_REJECTED;
}

/* ---------------------------------------------------------------------------------------------
 * layout: ODO_PARAMS_FIELDS as data, for Python and the image checks (one source, no copies)
 * ------------------------------------------------------------------------------------------- */
static const char *scope_key(const char *scope)
{
    return strcmp(scope, "TRUCK") == 0 ? "truck" : strcmp(scope, "LINK") == 0 ? "link" : "top";
}

static void print_layout(FILE *f)
{
    fprintf(f,
            "{\"magic\": \"ODOP\", \"magic_u32\": %lu, \"version\": %u, \"size\": %u, "
            "\"crc_offset\": %u, \"header_size\": %u, \"trucks\": %u,\n",
            (unsigned long)ODO_PARAMS_MAGIC, ODO_PARAMS_VERSION, ODO_PARAMS_SIZE, ODO_PARAMS_CRC_OFFSET,
            ODO_PARAMS_HEADER_SIZE, (unsigned)ODO_TRUCKS);
    fputs(" \"versions\": [", f);
    for (unsigned v = 1U; v <= ODO_PARAMS_VERSION; ++v) {
        const size_t size = odo_params_version_size((uint16_t)v);
        fprintf(f, "%s{\"version\": %u, \"size\": %zu, \"crc_offset\": %zu}", v == 1U ? "" : ", ", v, size, size - 4U);
    }
    fputs("],\n \"header\": [{\"name\": \"magic\", \"offset\": 0, \"width\": 4, \"type\": \"u32\"}, "
          "{\"name\": \"version\", \"offset\": 4, \"width\": 2, \"type\": \"u16\"}, "
          "{\"name\": \"length\", \"offset\": 6, \"width\": 2, \"type\": \"u16\"}],\n"
          " \"checks\": [\"link.length_min_um < link.length_max_um\"],\n \"fields\": [",
          f);
    const char *sep = "\n  ";
    /* Straight from the X-macro: every column as written in odo_params.h. */
#define LAYOUT_ROW(id, scope, member, json, since, off, stride, type, lo, hi, unit)                           \
    do {                                                                                                      \
        const odo_param_field_info_t *fi = odo_params_field_info(ODO_PF_##id);                                \
        fprintf(f,                                                                                            \
                "%s{\"id\": \"%s\", \"name\": \"%s\", \"scope\": \"%s\", \"member\": \"%s\", "                \
                "\"since\": %d, \"offsets\": [%d",                                                            \
                sep, #id, json, scope_key(#scope), #member, since, off);                                      \
        if (strcmp(#scope, "TRUCK") == 0) {                                                                   \
            for (unsigned t = 1U; t < ODO_TRUCKS; ++t) {                                                      \
                fprintf(f, ", %d", (off) + (int)t * (stride));                                                \
            }                                                                                                 \
        }                                                                                                     \
        fprintf(f,                                                                                            \
                "], \"width\": %u, \"type\": \"%s\", \"signed\": %s, \"min\": %" PRId64 ", \"max\": %" PRId64 \
                ", \"unit\": \"%s\", \"enum\": %u}",                                                          \
                fi->width,                                                                                    \
                strcmp(#type, "I32") == 0   ? "i32"                                                           \
                : strcmp(#type, "U32") == 0 ? "u32"                                                           \
                : strcmp(#type, "U16") == 0 ? "u16"                                                           \
                                            : "u8",                                                           \
                strcmp(#type, "I32") == 0 ? "true" : "false", (int64_t)(lo), (int64_t)(hi), unit,             \
                (unsigned)ODO_PF_##id);                                                                       \
        sep = ",\n  ";                                                                                        \
    } while (0);
    ODO_PARAMS_FIELDS(LAYOUT_ROW)
#undef LAYOUT_ROW
    fputs("]}\n", f);
}

static int cmd_layout(int argc, char **argv)
{
    const char *out = NULL;
    for (int i = 0; i < argc; i++) {
        if (is_help(argv[i])) {
            usage_layout(stdout);
            return 0;
        }
        if ((strcmp(argv[i], "--out") == 0 || strcmp(argv[i], "-o") == 0) && i + 1 < argc) {
            out = argv[++i];
        } else {
            fprintf(stderr, "%s: layout: unexpected argument '%s'\n", k_prog, argv[i]);
            usage_layout(stderr);
            return EXIT_USAGE;
        }
    }
    if (out == NULL) {
        print_layout(stdout);
        return fflush(stdout) == 0 ? 0 : EXIT_REJECTED;
    }
    char *text = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&text, &len);
    if (m == NULL) {
        fprintf(stderr, "%s: out of memory\n", k_prog);
        return EXIT_REJECTED;
    }
    print_layout(m);
    if (fclose(m) != 0) {
        free(text);
        fprintf(stderr, "%s: out of memory\n", k_prog);
        return EXIT_REJECTED;
    }
    const int rc = write_file_atomic(out, (const uint8_t *)text, len) == 0 ? 0 : EXIT_REJECTED;
    free(text);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage_main(stderr);
        return EXIT_USAGE;
    }
    if (strcmp(argv[1], "--version") == 0) {
        odo_cli_print_version(k_prog);
        return 0;
    }
    if (is_help(argv[1])) {
        usage_main(stdout);
        return 0;
    }
    if (strcmp(argv[1], "defaults") == 0) {
        return cmd_defaults(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "show") == 0) {
        return cmd_show(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "layout") == 0) {
        return cmd_layout(argc - 2, argv + 2);
    }
    fprintf(stderr, "%s: unknown command '%s'\n", k_prog, argv[1]);
    usage_main(stderr);
    return EXIT_USAGE;
}
