/// odo-calib: UMBmark calibration (000_12e7709aa9cd375a.txt s. 6) and the parameter block in
/// firmware images. See tools/calib/README.md and `odo-calib --help`.
///
/// Exit status: 0 ok; 1 rejected input, a failed calibration or an I/O error (message on stderr
/// naming the file and, where there is one, the line); 2 usage error. Outputs are written to a
/// temporary file in the destination's folder and renamed into place, so on any error the
/// destination keeps its old content.
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "acceptance.h"
#include "calib_core.h"
#include "fit_cli.h"
#include "image.h"
#include "odo_cli.h"
#include "odo_out.h"
#include "params_diag.h"
#include "params_json.h"
#include "returns_csv.h"
#include "robot.h"

#define EXIT_FAIL  1
#define EXIT_USAGE 2
#define Q30        1073741824.0
#define BAM_DEG    (180.0 / 2147483648.0)

static const char *const k_prog = "odo-calib";

static void usage(FILE *f)
{
    fprintf(f, "usage: odo-calib <command> [options]      (odo-calib <command> --help for details)\n"
               "       odo-calib --help | --version\n"
               "\n"
               "  umbmark --returns returns.csv --side-mm 4000 (--robot R.json | --params P.json|P.bin)\n"
               "          [--robot R.json --params P] [--method paper|exact] [--json] [--out-params P.json|P.bin]\n"
               "      UMBmark calibration (000 s. 6) of truck A from the return errors (000 Eq. 3.1);\n"
               "      --params: the block the robot ran the test with (default: from --robot).\n"
               "  write --image FW --params P.json|P.bin [--out OUT] [--force]\n"
               "      put the parameter block into a firmware image (raw .bin, Intel HEX or ELF\n"
               "      .odo_params); CRC recomputed; in place unless --out.\n"
               "  read --image FW [--json]     print the image's parameter block (version 1 or 2)\n"
               "  verify --image FW            check the image's block (layout, version, CRC, ranges)\n"
               "  export --params P.json|P.bin --format ros2 [--controller-name NAME]\n"
               "      diff_drive_controller parameters (YAML): absolute values and multipliers\n"
               "  fit --runs DIR... --robot R.json [--fit GLOB...] [--judge GLOB...] [--out-params P]... [--json]\n"
               "      calibrate Ed, Eb, Es and the turn-radius-dependent wheelbase from runs on any path\n"
               "      with a truth track or return poses (odo-import folders); held-out before/after.\n"
               "  acceptance [--robots N] [--seed S] [--runs N] [--json] [--no-tape] [--quiet]\n"
               "      simulated labmates (Ed ~ U[0.995, 1.005], b ~ U[0.97, 1.03] x 340 mm, floor\n"
               "      roughness): Emax,syst before/after one pass, exact and paper methods; E-7/E-8\n"
               "      tape analogues; noise-free recovery. Prints a 000 Table III-like table.\n"
               "\n"
               "Exit status: 0 ok, 1 rejected input or I/O error, 2 usage error.\n");
}

static int is_help(const char *a) { return strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0; }

/// Options as name/value pairs; flags have value "1".
typedef struct {
    const char *name;
    int takes_value;
    const char *value;
} opt_t;

/// getopt_long over the table (so --name=value works too); argv[-1] is the command's name.
static int parse_opts(const char *cmd, int argc, char **argv, opt_t *o, size_t n)
{
    struct option lo[16];
    if (n >= sizeof lo / sizeof lo[0]) {
        return -1;
    }
    for (size_t k = 0; k < n; ++k) {
        lo[k].name = o[k].name + 2; /* "--image" -> "image" */
        lo[k].has_arg = o[k].takes_value ? required_argument : no_argument;
        lo[k].flag = NULL;
        lo[k].val = (int)k;
    }
    memset(&lo[n], 0, sizeof lo[n]);
    optind = 1;
    opterr = 0;
    for (int c; (c = getopt_long(argc + 1, argv - 1, ":", lo, NULL)) != -1;) {
        if (c == '?' || c == ':') {
            fprintf(stderr, "%s %s: %s '%s' (see %s %s --help)\n", k_prog, cmd,
                    c == ':' ? "missing value for" : "unknown argument", argv[optind - 2], k_prog, cmd);
            return -1;
        }
        o[c].value = o[c].takes_value ? optarg : "1";
    }
    if (optind < argc + 1) {
        fprintf(stderr, "%s %s: unexpected argument '%s' (see %s %s --help)\n", k_prog, cmd, argv[optind - 1], k_prog,
                cmd);
        return -1;
    }
    return 0;
}

static const char *opt(const opt_t *o, size_t n, const char *name)
{
    for (size_t k = 0; k < n; ++k) {
        if (strcmp(o[k].name, name) == 0) {
            return o[k].value;
        }
    }
    return NULL;
}

static int ends_with(const char *s, const char *suf)
{
    const size_t a = strlen(s), b = strlen(suf);
    return a >= b && strcmp(s + a - b, suf) == 0;
}

/// Write an output by hostlib/odo_out.h's rule (temp beside it, fsync, rename; never an input).
static int write_atomic(const char *path, const void *data, size_t len, const odo_out_inputs_t *ins)
{
    char err[PATH_MAX + 256];
    if (odo_out_write(path, data, len, ins, err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s\n", k_prog, err);
        return -1;
    }
    return 0;
}

/// Parameters as JSON text (malloc'd) or as the 128-byte block, by the output's extension.
int calib_write_params(const char *path, const odo_params_t *p, const odo_out_inputs_t *ins)
{
    if (ends_with(path, ".bin")) {
        uint8_t block[ODO_PARAMS_SIZE];
        (void)odo_params_encode(p, block, sizeof block);
        return write_atomic(path, block, sizeof block, ins);
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (m == NULL || odo_params_json_write(m, p) != 0 || fclose(m) != 0) {
        free(buf);
        fprintf(stderr, "%s: out of memory\n", k_prog);
        return -1;
    }
    const int rc = write_atomic(path, buf, len, ins);
    free(buf);
    return rc;
}

/* ---------------------------------------------------------------------------------------------
 * umbmark
 * ------------------------------------------------------------------------------------------- */

static void print_calib_json(FILE *f, const calib_result_t *c, const char *returns_path, double side_mm,
                             const char *out_params)
{
    const odo_umb_stats_t *s = &c->st;
    const odo_umb_calib_t *p = &c->paper;
    fprintf(f, "{\"method\": \"%s\", \"returns\": \"%s\", \"side_mm\": %.3f,\n",
            c->method == CALIB_EXACT ? "exact" : "paper", returns_path, side_mm);
    fprintf(f, " \"Ed\": %.9f, \"Eb\": %.9f, \"cL\": %.9f, \"cR\": %.9f, \"b_actual_mm\": %.4f,\n", c->ed_q30 / Q30,
            c->eb_q30 / Q30, c->cl_q30 / Q30, c->cr_q30 / Q30, c->b_actual_mm);
    fprintf(f, " \"ed_q30\": %" PRId32 ", \"eb_q30\": %" PRId32 ", \"ed_in_force\": %.9f, \"eb_in_force\": %.9f,\n",
            c->ed_q30, c->eb_q30, c->ed_in_force, c->eb_in_force);
    fprintf(f,
            " \"alpha_deg\": %.6f, \"beta_deg\": %.6f, \"alpha_x_deg\": %.6f, \"alpha_y_deg\": %.6f, "
            "\"beta_x_deg\": %.6f, \"beta_y_deg\": %.6f,\n \"alpha_disagree_deg\": %.6f, \"beta_disagree_deg\": %.6f, "
            "\"radius_mm\": %.1f,\n",
            p->alpha_bam * BAM_DEG, p->beta_bam * BAM_DEG, p->alpha_x_bam * BAM_DEG, p->alpha_y_bam * BAM_DEG,
            p->beta_x_bam * BAM_DEG, p->beta_y_bam * BAM_DEG, p->alpha_disagree_bam * BAM_DEG,
            p->beta_disagree_bam * BAM_DEG, (double)p->radius_um / 1000.0);
    fprintf(f,
            " \"runs_cw\": %u, \"runs_ccw\": %u, \"cg_cw_mm\": [%.3f, %.3f], \"cg_ccw_mm\": [%.3f, %.3f], "
            "\"r_cg_cw_mm\": %.3f, \"r_cg_ccw_mm\": %.3f,\n",
            s->n[0], s->n[1], s->cg_x_um[0] / 1000.0, s->cg_y_um[0] / 1000.0, s->cg_x_um[1] / 1000.0,
            s->cg_y_um[1] / 1000.0, s->r_cg_um[0] / 1000.0, s->r_cg_um[1] / 1000.0);
    fprintf(f, " \"emax_syst_mm\": %.3f, \"sigma_mm\": %.3f, \"sem_mm\": %.3f, \"second_pass_advised\": %s,\n",
            s->emax_syst_um / 1000.0, s->sigma_um / 1000.0, s->sem_um / 1000.0,
            s->second_pass_advised ? "true" : "false");
    fprintf(f, " \"theta_bias_cw_deg\": %.6f, \"theta_bias_ccw_deg\": %.6f, \"avg_abs_theta_deg\": %.6f,\n",
            s->theta_bias_udeg[0] / 1e6, s->theta_bias_udeg[1] / 1e6, s->avg_abs_theta_udeg / 1e6);
    fprintf(
        f,
        " \"paper\": {\"Ed\": %.9f, \"Eb\": %.9f, \"b_actual_mm\": %.4f, \"ed_measured\": %.9f, \"eb_measured\": %.9f},\n",
        p->ed_q30 / Q30, p->eb_q30 / Q30, p->b_actual_nm / 1e6, p->ed_meas_q30 / Q30, p->eb_meas_q30 / Q30);
    if (c->method == CALIB_EXACT) {
        fprintf(f,
                " \"exact\": {\"Ed\": %.9f, \"b_mm\": %.5f, \"residual_mm\": %.4f, \"iterations\": %d, "
                "\"converged\": %s, \"identifiable\": %s, \"singular_value_ratio\": %.3e},\n",
                c->fit.ed, c->fit.b_mm, c->fit.residual_mm, c->fit.iterations, c->fit.converged ? "true" : "false",
                c->fit.identifiable ? "true" : "false", c->fit.sv_max > 0 ? c->fit.sv_min / c->fit.sv_max : 0.0);
    }
    fprintf(f,
            " \"not_identifiable\": [\"es: a closed square does not show the scale error; measure it with a tape "
            "(000 App. B)\", \"truck B: UMBmark returns are truck A's\"%s],\n",
            c->method == CALIB_EXACT && !c->fit.identifiable ? ", \"Ed and b: the data do not separate them\"" : "");
    fprintf(f, " \"out_params\": ");
    if (out_params != NULL) {
        fprintf(f, "\"%s\"}\n", out_params);
    } else {
        fprintf(f, "null}\n");
    }
}

static void print_calib_table(FILE *f, const calib_result_t *c)
{
    const odo_umb_stats_t *s = &c->st;
    const odo_umb_calib_t *p = &c->paper;
    fprintf(f, "UMBmark (000 s. 3): %u cw + %u ccw runs\n", s->n[0], s->n[1]);
    fprintf(f, "  cg cw  (%9.2f, %9.2f) mm   r %8.2f mm   (Eqs. 3.2, 3.3)\n", s->cg_x_um[0] / 1e3, s->cg_y_um[0] / 1e3,
            s->r_cg_um[0] / 1e3);
    fprintf(f, "  cg ccw (%9.2f, %9.2f) mm   r %8.2f mm\n", s->cg_x_um[1] / 1e3, s->cg_y_um[1] / 1e3,
            s->r_cg_um[1] / 1e3);
    fprintf(f, "  Emax,syst %.2f mm (Eq. 3.4)   sigma %.2f mm   SEM %.2f mm   second pass %s (Emax,syst %s 3 SEM)\n",
            s->emax_syst_um / 1e3, s->sigma_um / 1e3, s->sem_um / 1e3,
            s->second_pass_advised ? "advised" : "not needed", s->second_pass_advised ? ">" : "<=");
    fprintf(f, "  alpha %.4f deg (x %.4f, y %.4f)   beta %.4f deg (x %.4f, y %.4f)   (Eqs. 6.22, 6.26)\n",
            p->alpha_bam * BAM_DEG, p->alpha_x_bam * BAM_DEG, p->alpha_y_bam * BAM_DEG, p->beta_bam * BAM_DEG,
            p->beta_x_bam * BAM_DEG, p->beta_y_bam * BAM_DEG);
    fprintf(f, "\n%-8s %12s %12s %12s %12s %14s\n", "method", "Ed", "Eb", "cL", "cR", "b_actual mm");
    fprintf(f, "%-8s %12.7f %12.7f %12.7f %12.7f %14.3f\n", "paper", p->ed_q30 / Q30, p->eb_q30 / Q30, p->cl_q30 / Q30,
            p->cr_q30 / Q30, p->b_actual_nm / 1e6);
    if (c->method == CALIB_EXACT) {
        fprintf(f, "%-8s %12.7f %12.7f %12.7f %12.7f %14.3f   (fit residual %.3f mm, %d iterations%s)\n", "exact",
                c->ed_q30 / Q30, c->eb_q30 / Q30, c->cl_q30 / Q30, c->cr_q30 / Q30, c->b_actual_mm, c->fit.residual_mm,
                c->fit.iterations, c->fit.identifiable ? "" : ", NOT identifiable");
    }
    fprintf(f, "\nnot identifiable from UMBmark: Es (measure with a tape, 000 App. B); truck B.\n");
}

/// The parameter block in force from --robot and/or --params.
static int params_in_force(const char *cmd, const char *robot_path, const char *params_path, odo_params_t *p)
{
    char err[512];
    if (params_path != NULL) {
        if (odo_params_file_load(params_path, p, err, sizeof err) != 0) {
            fprintf(stderr, "%s %s: %s\n", k_prog, cmd, err);
            return -1;
        }
        return 0;
    }
    static sim_robot_t robot;
    if (sim_robot_parse_file(robot_path, &robot, err, sizeof err) != 0 ||
        sim_robot_to_params(&robot, p, err, sizeof err) != 0) {
        fprintf(stderr, "%s %s: %s\n", k_prog, cmd, err);
        return -1;
    }
    return 0;
}

static int cmd_umbmark(int argc, char **argv)
{
    opt_t o[] = {{"--returns", 1, NULL}, {"--side-mm", 1, NULL}, {"--robot", 1, NULL},     {"--params", 1, NULL},
                 {"--method", 1, NULL},  {"--json", 0, NULL},    {"--out-params", 1, NULL}};
    const size_t n = sizeof o / sizeof o[0];
    for (int i = 0; i < argc; ++i) {
        if (is_help(argv[i])) {
            printf("usage: odo-calib umbmark --returns returns.csv --side-mm L (--robot R.json | --params P)\n"
                   "                        [--method paper|exact] [--json] [--out-params P.json|P.bin]\n"
                   "\n"
                   "Reads the return errors (host_sim/README.md returns.csv contract, 000 Eq. 3.1), computes\n"
                   "the centres of gravity, Emax,syst, sigma and SEM (Eqs. 3.2-3.4, s. 6.3), alpha and beta\n"
                   "(x and y forms, Eqs. 6.19-6.26) and the corrections Ed, Eb, cL, cR, b_actual (Eqs.\n"
                   "6.23-6.34). --method exact (default) fits Ed and b to the centres of gravity without\n"
                   "small-angle approximations, starting from the paper's answer; --method paper stops there.\n"
                   "--robot: the robot description the test ran with (host_sim/robots); --params: the\n"
                   "parameter block it ran with (overrides the robot's calibration). --out-params writes\n"
                   "the new block (JSON as `odo-params show` prints it, or .bin) for `odo-calib write` or\n"
                   "`odo-sim --params`.\n");
            return 0;
        }
    }
    if (parse_opts("umbmark", argc, argv, o, n) != 0) {
        return EXIT_USAGE;
    }
    const char *returns_path = opt(o, n, "--returns"), *side = opt(o, n, "--side-mm"), *robot = opt(o, n, "--robot"),
               *params = opt(o, n, "--params"), *method = opt(o, n, "--method"), *out = opt(o, n, "--out-params");
    const int json = opt(o, n, "--json") != NULL;
    if (returns_path == NULL || side == NULL || (robot == NULL && params == NULL)) {
        fprintf(stderr, "%s umbmark: --returns, --side-mm and --robot (or --params) are required\n", k_prog);
        return EXIT_USAGE;
    }
    calib_method_t m = CALIB_EXACT;
    if (method != NULL && strcmp(method, "paper") == 0) {
        m = CALIB_PAPER;
    } else if (method != NULL && strcmp(method, "exact") != 0) {
        fprintf(stderr, "%s umbmark: --method must be paper or exact, not '%s'\n", k_prog, method);
        return EXIT_USAGE;
    }
    char *end = NULL;
    errno = 0;
    const double side_mm = strtod(side, &end);
    if (end == side || *end != '\0' || errno != 0 || !isfinite(side_mm) || side_mm <= 0.0) {
        fprintf(stderr, "%s umbmark: --side-mm must be a positive number of mm, not '%s'\n", k_prog, side);
        return EXIT_FAIL;
    }
    odo_params_t in_force;
    if (params_in_force("umbmark", robot, params, &in_force) != 0) {
        return EXIT_FAIL;
    }
    static returns_t r;
    char err[512];
    if (returns_read(returns_path, &r, err, sizeof err) != 0) {
        fprintf(stderr, "%s umbmark: %s\n", k_prog, err);
        return EXIT_FAIL;
    }
    calib_result_t c;
    if (calib_umbmark(&r, side_mm, &in_force, m, &c, err, sizeof err) != 0) {
        fprintf(stderr, "%s umbmark: %s: %s\n", k_prog, returns_path, err);
        return EXIT_FAIL;
    }
    if (out != NULL) {
        odo_params_t np;
        calib_apply(&in_force, &c, &np);
        odo_out_inputs_t ins; /* --out-params equal to --returns (or the robot, the block) is refused */
        odo_out_inputs_init(&ins);
        (void)odo_out_inputs_add(&ins, returns_path, err, sizeof err);
        (void)odo_out_inputs_add(&ins, robot, err, sizeof err);
        (void)odo_out_inputs_add(&ins, params, err, sizeof err);
        if (calib_write_params(out, &np, &ins) != 0) {
            return EXIT_FAIL;
        }
    }
    if (json) {
        print_calib_json(stdout, &c, returns_path, side_mm, out);
    } else {
        print_calib_table(stdout, &c);
        if (out != NULL) {
            printf("parameters written to %s\n", out);
        }
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * write / read / verify
 * ------------------------------------------------------------------------------------------- */

static int help_if(int argc, char **argv, const char *text)
{
    for (int i = 0; i < argc; ++i) {
        if (is_help(argv[i])) {
            fputs(text, stdout);
            return 1;
        }
    }
    return 0;
}

static int cmd_write(int argc, char **argv)
{
    if (help_if(argc, argv,
                "usage: odo-calib write --image FW --params P.json|P.bin [--out OUT] [--force]\n"
                "\n"
                "Replace the parameter block inside a firmware image: raw .bin (found by its magic), Intel\n"
                "HEX, or ELF (section .odo_params). The image's block must be a version-2 block (a\n"
                "version-1 image is refused: its firmware cannot read version 2) with a good CRC unless\n"
                "--force. P may be a version-1 or version-2 JSON or raw block; a version-1 one is written\n"
                "as version 2 with scrub_q30 = 0. The new block is encoded by the firmware's own codec\n"
                "(CRC-32 recomputed) and written to OUT (default: FW itself) through a temporary file\n"
                "that is read back before it is renamed into place; on any error FW and OUT keep their\n"
                "old content.\n")) {
        return 0;
    }
    opt_t o[] = {{"--image", 1, NULL}, {"--params", 1, NULL}, {"--out", 1, NULL}, {"--force", 0, NULL}};
    const size_t n = sizeof o / sizeof o[0];
    if (parse_opts("write", argc, argv, o, n) != 0) {
        return EXIT_USAGE;
    }
    const char *image = opt(o, n, "--image"), *params = opt(o, n, "--params"), *out = opt(o, n, "--out");
    if (image == NULL || params == NULL) {
        fprintf(stderr, "%s write: --image and --params are required\n", k_prog);
        return EXIT_USAGE;
    }
    char err[512];
    odo_params_t p;
    if (odo_params_file_load(params, &p, err, sizeof err) != 0) {
        fprintf(stderr, "%s write: %s\n", k_prog, err);
        return EXIT_FAIL;
    }
    img_t img;
    if (img_load(image, &img, err, sizeof err) != 0) {
        fprintf(stderr, "%s write: %s\n", k_prog, err);
        return EXIT_FAIL;
    }
    if (img.status == ODO_PARAMS_ERR_CRC && opt(o, n, "--force") == NULL) {
        fprintf(stderr,
                "%s write: %s: the block at 0x%llx has a bad CRC-32 (corrupted image?); --force to "
                "overwrite it anyway\n",
                k_prog, image, (unsigned long long)img.block_addr);
        img_free(&img);
        return EXIT_FAIL;
    }
    uint8_t block[ODO_PARAMS_SIZE];
    (void)odo_params_encode(&p, block, sizeof block);
    /* The block file is an input: --out equal to --params is refused. The image itself is the
     * documented in-place default, so it is not. */
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    (void)odo_out_inputs_add(&ins, params, err, sizeof err);
    const int rc = img_write_patched(&img, block, out != NULL ? out : image, &ins, err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "%s write: %s\n", k_prog, err);
    } else {
        fprintf(stderr, "%s: wrote the version-%u parameter block (CRC-32 0x%08" PRIX32 ") at 0x%llx of %s image %s\n",
                k_prog, ODO_PARAMS_VERSION, odo_crc32(block, ODO_PARAMS_CRC_OFFSET), (unsigned long long)img.block_addr,
                img_format_name(img.fmt), out != NULL ? out : image);
    }
    img_free(&img);
    return rc == 0 ? 0 : EXIT_FAIL;
}

static int load_image_cmd(const char *cmd, int argc, char **argv, img_t *img, int *json)
{
    opt_t o[] = {{"--image", 1, NULL}, {"--json", 0, NULL}};
    const size_t n = json != NULL ? 2 : 1;
    if (parse_opts(cmd, argc, argv, o, n) != 0) {
        return EXIT_USAGE;
    }
    if (opt(o, n, "--image") == NULL) {
        fprintf(stderr, "%s %s: --image is required\n", k_prog, cmd);
        return EXIT_USAGE;
    }
    if (json != NULL) {
        *json = opt(o, n, "--json") != NULL;
    }
    char err[512];
    if (img_load(opt(o, n, "--image"), img, err, sizeof err) != 0) {
        fprintf(stderr, "%s %s: %s\n", k_prog, cmd, err);
        return EXIT_FAIL;
    }
    return 0;
}

/// The image's block, decoded; on failure a message naming the field (params_diag.h), exit code.
static int decode_image_block(const char *cmd, const img_t *img, odo_params_t *p)
{
    const odo_params_status_t st = odo_params_decode(img->block, img->block_len, p);
    if (st == ODO_PARAMS_OK) {
        return 0;
    }
    char field[64], detail[192];
    odo_params_explain(st, img->block, img->block_len, field, sizeof field, detail, sizeof detail);
    fprintf(stderr, "%s %s: %s image: block at 0x%llx: %s%s%s\n", k_prog, cmd, img_format_name(img->fmt),
            (unsigned long long)img->block_addr, odo_params_status_str(st), detail[0] != '\0' ? ": " : "", detail);
    return EXIT_FAIL;
}

static uint32_t stored_crc(const img_t *img)
{
    const uint8_t *c = img->block + img->block_len - 4U;
    return (uint32_t)c[0] | (uint32_t)c[1] << 8 | (uint32_t)c[2] << 16 | (uint32_t)c[3] << 24;
}

static int cmd_read(int argc, char **argv)
{
    if (help_if(argc, argv,
                "usage: odo-calib read --image FW [--json]\n\nPrint the parameter block of a firmware "
                "image (.bin, Intel HEX, ELF), version 1 or 2; --json in the shape `odo-params show` "
                "prints (a version-1 block without scrub_q30).\n")) {
        return 0;
    }
    img_t img;
    int json = 0;
    const int rc = load_image_cmd("read", argc, argv, &img, &json);
    if (rc != 0) {
        return rc;
    }
    odo_params_t p;
    if (decode_image_block("read", &img, &p) != 0) {
        img_free(&img);
        return EXIT_FAIL;
    }
    if (json) {
        odo_params_json_write_stored(stdout, &p, img.version, stored_crc(&img));
    } else {
        printf("%s image, parameter block at 0x%llx, version %u, CRC-32 0x%08" PRIX32 "\n", img_format_name(img.fmt),
               (unsigned long long)img.block_addr, img.version, stored_crc(&img));
        for (unsigned k = 0; k < ODO_TRUCKS; ++k) {
            const odo_truck_params_t *t = &p.truck[k];
            int32_t cl_q = 0, cr_q = 0;
            (void)odo_umb_correction_factors(t->ed_q30, &cl_q, &cr_q);
            printf("truck %c: Dn %.4f mm, b %.4f mm, counts/rev %.3f, Ed %.7f, Eb %.7f, Es %.7f, scrub k %.7f "
                   "(cL %.7f, cR %.7f, b_actual %.4f mm on spot turns)\n",
                   'A' + k, t->wheel_diameter_nm / 1e6, t->wheelbase_nm / 1e6, t->counts_per_rev_milli / 1e3,
                   t->ed_q30 / Q30, t->eb_q30 / Q30, t->es_q30 / Q30, t->scrub_q30 / Q30, cl_q / Q30, cr_q / Q30,
                   t->wheelbase_nm / 1e6 * (t->eb_q30 / Q30));
        }
        if (img.version < ODO_PARAMS_VERSION) {
            printf("(a version-%u block: scrub_q30 reads as 0; `odo-calib write` refuses this image, whose firmware "
                   "reads version %u only)\n",
                   img.version, img.version);
        }
    }
    img_free(&img);
    return 0;
}

static int cmd_verify(int argc, char **argv)
{
    if (help_if(argc, argv,
                "usage: odo-calib verify --image FW\n\nCheck the parameter block of a firmware image as "
                "the firmware does at boot (magic, version 1 or 2, length, CRC-32, every range, reserved "
                "bytes zero). Exit 0 iff the firmware would accept it; otherwise the message names the "
                "offending field.\n")) {
        return 0;
    }
    img_t img;
    const int rc = load_image_cmd("verify", argc, argv, &img, NULL);
    if (rc != 0) {
        return rc;
    }
    odo_params_t p;
    if (decode_image_block("verify", &img, &p) != 0) {
        img_free(&img);
        return EXIT_FAIL;
    }
    printf("ok: %s image, parameter block at 0x%llx, version %u, CRC-32 good, every field in range\n",
           img_format_name(img.fmt), (unsigned long long)img.block_addr, img.version);
    img_free(&img);
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * export
 * ------------------------------------------------------------------------------------------- */

static int cmd_export(int argc, char **argv)
{
    if (help_if(argc, argv,
                "usage: odo-calib export --params P.json|P.bin --format ros2 [--controller-name NAME]\n"
                "\n"
                "Print truck A's calibration as a ros2_controllers diff_drive_controller parameter\n"
                "file (YAML) under NAME (default diff_drive_controller: the name your controller has in\n"
                "the controller manager). Absolute values and multipliers both: wheel_separation = b\n"
                "(nominal) with wheel_separation_multiplier = Eb (000 Eq. 6.28), wheel_radius = Dn/2\n"
                "with left/right_wheel_radius_multiplier = cL/Es, cR/Es (Eqs. 6.33-6.35, App. B);\n"
                "diff_drive_controller multiplies them. The model's turn-radius-dependent wheelbase\n"
                "(scrub, odo-calib fit) has no diff_drive_controller parameter: it is printed as a\n"
                "comment with the effective separation it implies on arcs (tools/calib/README.md).\n")) {
        return 0;
    }
    opt_t o[] = {{"--params", 1, NULL}, {"--format", 1, NULL}, {"--controller-name", 1, NULL}};
    const size_t n = 3;
    if (parse_opts("export", argc, argv, o, n) != 0) {
        return EXIT_USAGE;
    }
    const char *params = opt(o, n, "--params"), *format = opt(o, n, "--format");
    const char *name =
        opt(o, n, "--controller-name") != NULL ? opt(o, n, "--controller-name") : "diff_drive_controller";
    if (params == NULL || format == NULL) {
        fprintf(stderr, "%s export: --params and --format are required\n", k_prog);
        return EXIT_USAGE;
    }
    if (strcmp(format, "ros2") != 0) {
        fprintf(stderr, "%s export: unknown format '%s' (ros2)\n", k_prog, format);
        return EXIT_USAGE;
    }
    /* A ROS 2 node name: letters, digits and underscores, not starting with a digit. */
    int name_ok = name[0] != '\0' && !(name[0] >= '0' && name[0] <= '9');
    for (const char *c = name; *c != '\0' && name_ok; ++c) {
        name_ok = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') || *c == '_';
    }
    if (!name_ok) {
        fprintf(stderr, "%s export: --controller-name '%s' is not a ROS 2 node name ([A-Za-z_][A-Za-z0-9_]*)\n", k_prog,
                name);
        return EXIT_USAGE;
    }
    odo_params_t p;
    char err[512];
    if (odo_params_file_load(params, &p, err, sizeof err) != 0) {
        fprintf(stderr, "%s export: %s\n", k_prog, err);
        return EXIT_FAIL;
    }
    const odo_truck_params_t *t = &p.truck[0];
    int32_t cl = 0, cr = 0;
    (void)odo_umb_correction_factors(t->ed_q30, &cl, &cr);
    const double es = t->es_q30 / Q30, eb = t->eb_q30 / Q30, scrub = t->scrub_q30 / Q30;
    printf("# odo-calib export --format ros2, from %s (truck A)\n"
           "# diff_drive_controller uses wheel_separation * wheel_separation_multiplier and\n"
           "# wheel_radius * <side>_wheel_radius_multiplier. Ed %.9f, Eb %.9f, Es %.9f.\n"
           "# Effective: wheel_separation %.6f m, left radius %.6f m, right radius %.6f m.\n"
           "# scrub (turn-radius-dependent wheelbase) %.6f: not a diff_drive_controller parameter; the\n"
           "# separation above is the spot-turn one; on an arc of radius R it is b Eb / (1 - scrub (1 - b/(2R))).\n"
           "%s:\n"
           "  ros__parameters:\n"
           "    wheel_separation: %.6f\n"
           "    wheel_radius: %.6f\n"
           "    wheel_separation_multiplier: %.9f\n"
           "    left_wheel_radius_multiplier: %.9f\n"
           "    right_wheel_radius_multiplier: %.9f\n",
           params, t->ed_q30 / Q30, eb, es, t->wheelbase_nm / 1e9 * eb, t->wheel_diameter_nm / 2e9 * cl / Q30 / es,
           t->wheel_diameter_nm / 2e9 * cr / Q30 / es, scrub, name, t->wheelbase_nm / 1e9, t->wheel_diameter_nm / 2e9,
           eb, cl / Q30 / es, cr / Q30 / es);
    return 0;
}

int main(int argc, char **argv)
{
    if (!odo_cli_split_equals(&argc, &argv)) {
        return EXIT_FAIL;
    }
    if (argc >= 2 && strcmp(argv[1], "--version") == 0) {
        odo_cli_print_version(k_prog);
        return 0;
    }
    if (argc < 2 || is_help(argv[1])) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? EXIT_USAGE : 0;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "umbmark") == 0) {
        return cmd_umbmark(argc - 2, argv + 2);
    }
    if (strcmp(cmd, "write") == 0) {
        return cmd_write(argc - 2, argv + 2);
    }
    if (strcmp(cmd, "read") == 0) {
        return cmd_read(argc - 2, argv + 2);
    }
    if (strcmp(cmd, "verify") == 0) {
        return cmd_verify(argc - 2, argv + 2);
    }
    if (strcmp(cmd, "export") == 0) {
        return cmd_export(argc - 2, argv + 2);
    }
    if (strcmp(cmd, "fit") == 0) {
        return calib_fit_main(argc - 2, argv + 2);
    }
    if (strcmp(cmd, "acceptance") == 0) {
        return calib_acceptance_main(argc - 2, argv + 2);
    }
    fprintf(stderr, "%s: unknown command '%s'\n", k_prog, cmd);
    usage(stderr);
    return EXIT_USAGE;
}
