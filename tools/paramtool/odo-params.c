/// odo-params: write and inspect the firmware parameter block (odo/odo_params.h).
///
///   odo-params defaults --out FILE   write the 128-byte default block (FILE.tmp, fsync, rename)
///   odo-params show FILE             decode FILE and print every field as one JSON object
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
            "Write and inspect the odometry firmware parameter block (%u bytes, version %u).\n"
            "\n"
            "commands:\n"
            "  defaults --out FILE   write the default parameter block to FILE\n"
            "  show FILE             decode FILE, print every field as one JSON object\n"
            "\n"
            "Run '%s <command> --help' for a command's options.\n"
            "Exit status: 0 ok, 1 rejected block or I/O error, 2 usage error.\n",
            k_prog, ODO_PARAMS_SIZE, ODO_PARAMS_VERSION, k_prog);
}

static void usage_defaults(FILE *f)
{
    fprintf(f,
            "usage: %s defaults --out FILE\n"
            "\n"
            "Write the documented default parameter block (odo_params_defaults) to FILE.\n"
            "The block is written to FILE.tmp, flushed to disk and renamed over FILE, so FILE is\n"
            "either the old content or the complete new block; on error nothing is left behind.\n"
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
            "\"status\": \"ok\". A rejected block prints a JSON object with the status and reason,\n"
            "a message on stderr naming the reason (and, for a range error, the field), and exits 1.\n"
            "\n"
            "options:\n"
            "  -h, --help   show this help\n",
            k_prog);
}

static bool is_help(const char *a) { return strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0; }

/* ---------------------------------------------------------------------------------------------
 * defaults
 * ------------------------------------------------------------------------------------------- */
static int write_all(int fd, const uint8_t *b, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, b, n);
        if (w < 0) {
            if (errno == EINTR) {
                continue;
            }
            return -1;
        }
        b += (size_t)w;
        n -= (size_t)w;
    }
    return 0;
}

/// Write b to path atomically: path.tmp, fsync, rename. On failure, no path.tmp remains.
static int write_file_atomic(const char *path, const uint8_t *b, size_t n)
{
    size_t plen = strlen(path);
    char *tmp = malloc(plen + sizeof ".tmp");
    if (tmp == NULL) {
        fprintf(stderr, "%s: out of memory\n", k_prog);
        return -1;
    }
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, ".tmp", sizeof ".tmp");

    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        fprintf(stderr, "%s: cannot create %s: %s\n", k_prog, tmp, strerror(errno));
        free(tmp);
        return -1;
    }
    const char *step = "write";
    int rc = write_all(fd, b, n);
    if (rc == 0) {
        step = "fsync";
        rc = fsync(fd);
    }
    int saved = errno;
    if (close(fd) != 0 && rc == 0) {
        step = "close";
        rc = -1;
        saved = errno;
    }
    if (rc == 0) {
        step = "rename";
        rc = rename(tmp, path);
        saved = errno;
    }
    if (rc != 0) {
        fprintf(stderr, "%s: cannot %s %s: %s\n", k_prog, step,
                strcmp(step, "rename") == 0 ? path : tmp, strerror(saved));
        (void)unlink(tmp);
    }
    free(tmp);
    return rc;
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

/// The offending value, for the message. Length range: the minimum (the pair is named together).
static long long field_value(const odo_params_t *p, odo_param_field_t f, unsigned t)
{
    const odo_truck_params_t *tr = &p->truck[t < ODO_TRUCKS ? t : 0];
    switch (f) {
    case ODO_PF_VEHICLE: return p->vehicle;
    case ODO_PF_COUNTER_BITS: return p->counter_bits;
    case ODO_PF_HEADING_FORM: return p->heading_form;
    case ODO_PF_IPEC_MODE: return p->ipec_mode;
    case ODO_PF_TICK_US: return p->tick_us;
    case ODO_PF_MAX_WHEEL_SPEED: return p->max_wheel_speed_mm_s;
    case ODO_PF_WHEEL_DIAMETER: return tr->wheel_diameter_nm;
    case ODO_PF_COUNTS_PER_REV: return tr->counts_per_rev_milli;
    case ODO_PF_WHEELBASE: return tr->wheelbase_nm;
    case ODO_PF_ED: return tr->ed_q30;
    case ODO_PF_EB: return tr->eb_q30;
    case ODO_PF_ES: return tr->es_q30;
    case ODO_PF_TRUCK_FLAGS: return tr->flags;
    case ODO_PF_LINK_LENGTH: return p->link.length_nm;
    case ODO_PF_HITCH_OFFSET: return p->link.hitch_offset_nm;
    case ODO_PF_LENGTH_BIAS: return p->link.length_bias_nm;
    case ODO_PF_LENGTH_ECC: return p->link.length_ecc_nm;
    case ODO_PF_ALPHA_BIAS: return p->link.alpha_bias_bam;
    case ODO_PF_BETA_BIAS: return p->link.beta_bias_bam;
    case ODO_PF_ROTARY_BITS: return p->link.rotary_bits;
    case ODO_PF_STALE_TICKS: return p->link.stale_ticks;
    case ODO_PF_MAX_JUMP: return p->link.max_jump_bam;
    case ODO_PF_MAX_LENGTH_JUMP: return p->link.max_length_jump_um;
    case ODO_PF_LENGTH_RANGE: return p->link.length_min_um;
    case ODO_PF_NONE:
    case ODO_PF_RESERVED: break;
    }
    return 0;
}

static bool is_truck_field(odo_param_field_t f) { return f >= ODO_PF_WHEEL_DIAMETER && f <= ODO_PF_TRUCK_FLAGS; }

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
    fprintf(f, "{\"file\": ");
    json_str(f, path);
    fprintf(f, ", \"status\": \"ok\", \"magic\": \"ODOP\", \"version\": %u, \"length\": %u, "
               "\"crc32\": \"0x%08" PRIX32 "\",\n",
            (unsigned)le16(&b[4]), (unsigned)le16(&b[6]), le32(&b[ODO_PARAMS_CRC_OFFSET]));
    odo_params_json_fields(f, p);
    fputs("}\n", f);
}

/// Explain a rejected block: detail[] gets the specifics, field[] the offending field (range only).
static void diagnose(odo_params_status_t st, const uint8_t *b, size_t n, char *detail, size_t dcap,
                     char *field, size_t fcap)
{
    detail[0] = '\0';
    field[0] = '\0';
    switch (st) {
    case ODO_PARAMS_ERR_SHORT:
        snprintf(detail, dcap, "%zu bytes, a version-%u block is %u", n, ODO_PARAMS_VERSION,
                 ODO_PARAMS_SIZE);
        break;
    case ODO_PARAMS_ERR_MAGIC:
        snprintf(detail, dcap, "first bytes %02X %02X %02X %02X, expected 4F 44 4F 50 ('ODOP')", b[0],
                 b[1], b[2], b[3]);
        break;
    case ODO_PARAMS_ERR_VERSION:
        snprintf(detail, dcap, "version %u, this tool knows %u", (unsigned)le16(&b[4]),
                 ODO_PARAMS_VERSION);
        break;
    case ODO_PARAMS_ERR_LENGTH:
        snprintf(detail, dcap, "declared length %u, version %u blocks are %u", (unsigned)le16(&b[6]),
                 ODO_PARAMS_VERSION, ODO_PARAMS_SIZE);
        break;
    case ODO_PARAMS_ERR_CRC:
        snprintf(detail, dcap, "stored CRC-32 0x%08" PRIX32 ", computed 0x%08" PRIX32,
                 le32(&b[ODO_PARAMS_CRC_OFFSET]), odo_crc32(b, ODO_PARAMS_CRC_OFFSET));
        break;
    case ODO_PARAMS_ERR_RANGE: {
        /* Header and CRC are good: parse without range checks, then let the firmware's own
         * validator name the field. A parse that fails on range means a reserved byte: find it
         * by re-encoding (encode writes reserved bytes as 0). */
        odo_params_t p;
        odo_param_field_t f = ODO_PF_NONE;
        uint8_t t = 0;
        if (odo_params_parse(b, n, &p) == ODO_PARAMS_ERR_RANGE) {
            uint8_t re[ODO_PARAMS_SIZE];
            (void)odo_params_encode(&p, re, sizeof re);
            for (unsigned i = 0; i < ODO_PARAMS_CRC_OFFSET; i++) {
                if (re[i] != b[i]) {
                    snprintf(field, fcap, "reserved");
                    snprintf(detail, dcap, "reserved byte at offset %u is 0x%02X, must be 0", i, b[i]);
                    break;
                }
            }
            break;
        }
        (void)odo_params_validate(&p, &f, &t);
        if (is_truck_field(f)) {
            snprintf(field, fcap, "truck[%u].%s", (unsigned)t, odo_params_field_name(f));
        } else {
            snprintf(field, fcap, "%s", odo_params_field_name(f));
        }
        if (f == ODO_PF_LENGTH_RANGE) {
            snprintf(detail, dcap, "field %s = %" PRIu32 "/%" PRIu32 " is outside its documented range",
                     field, p.link.length_min_um, p.link.length_max_um);
        } else {
            snprintf(detail, dcap, "field %s = %lld is outside its documented range", field,
                     field_value(&p, f, t));
        }
        break;
    }
    case ODO_PARAMS_OK:
    case ODO_PARAMS_ERR_ARG:
        break;
    }
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
        fprintf(stderr, "%s: %s: larger than %lu bytes, not a parameter block\n", k_prog, path,
                MAX_INPUT_BYTES);
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

    char detail[160];
    char field[64];
    diagnose(st, buf, n, detail, sizeof detail, field, sizeof field);
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

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage_main(stderr);
        return EXIT_USAGE;
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
    fprintf(stderr, "%s: unknown command '%s'\n", k_prog, argv[1]);
    usage_main(stderr);
    return EXIT_USAGE;
}
