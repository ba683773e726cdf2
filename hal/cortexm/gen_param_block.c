/// Build-time generator, run on the BUILD HOST (compiled with the host `cc` by
/// hal/cortexm/CMakeLists.txt, linked with firmware/src/odo_params.c):
///
///   gen_param_block OUT.c
///
/// writes OUT.c, a C file defining odo_param_block (odo_board.h) as the ODO_PARAMS_SIZE bytes
/// (256, version 2) of odo_params_encode(odo_params_defaults()), placed in section .odo_params,
/// and the absolute symbol __odo_params_block_size = ODO_PARAMS_SIZE, which the linker script
/// (odo_cm4.ld) checks the section's size against. The C preprocessor cannot compute the CRC-32,
/// and the firmware's own codec is the single source of truth for the layout, so the block (and
/// its size, for the linker) is produced by that codec rather than written out by hand.
///
/// The layout is explicit little-endian, so a block encoded on the host is the block the target
/// reads. Before writing, the block is decoded back and must be ODO_PARAMS_OK; otherwise (or on any
/// I/O error) it prints why, removes OUT.c and exits 1, failing the build.
#include <stdio.h>
#include <stdlib.h>

#include "odo/odo_params.h"

static int fail(const char *out_path, const char *why)
{
    (void)fprintf(stderr, "gen_param_block: %s\n", why);
    if (out_path != NULL) {
        (void)remove(out_path);
    }
    return EXIT_FAILURE;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        (void)fprintf(stderr, "usage: %s OUT.c\n", argc > 0 ? argv[0] : "gen_param_block");
        return EXIT_FAILURE;
    }
    const char *out_path = argv[1];

    odo_params_t params;
    odo_params_defaults(&params);

    uint8_t block[ODO_PARAMS_SIZE];
    if (odo_params_encode(&params, block, sizeof block) != ODO_PARAMS_SIZE) {
        return fail(NULL, "odo_params_encode did not produce ODO_PARAMS_SIZE bytes");
    }
    if (block[0] != 'O' || block[1] != 'D' || block[2] != 'O' || block[3] != 'P') {
        return fail(NULL, "encoded block does not start with the magic \"ODOP\"");
    }
    odo_params_t back;
    odo_params_status_t st = odo_params_decode(block, sizeof block, &back);
    if (st != ODO_PARAMS_OK) {
        (void)fprintf(stderr, "gen_param_block: the default block does not decode: %s\n", odo_params_status_str(st));
        return EXIT_FAILURE;
    }

    FILE *f = fopen(out_path, "w");
    if (f == NULL) {
        perror(out_path);
        return EXIT_FAILURE;
    }
    (void)fprintf(f,
                  "/* Generated at build time by hal/cortexm/gen_param_block.c from odo_params_defaults().\n"
                  " * Do not edit: change the defaults in firmware/src/odo_params.c, or patch a built image\n"
                  " * with `odo-calib write`. Layout: firmware/include/odo/odo_params.h. */\n"
                  "#include \"odo_board.h\"\n\n"
                  "/* The block's size as a link-time constant, for odo_cm4.ld's ASSERT on .odo_params. */\n"
                  "__asm__(\".global __odo_params_block_size\\n\\t.set __odo_params_block_size, %u\");\n\n"
                  "__attribute__((section(\".odo_params\"), used, aligned(4)))\n"
                  "const uint8_t odo_param_block[ODO_PARAMS_SIZE] = {\n",
                  ODO_PARAMS_SIZE);
    for (size_t i = 0; i < sizeof block; ++i) {
        (void)fprintf(f, "%s0x%02XU,%s", (i % 12U) == 0U ? "    " : " ", (unsigned)block[i],
                      ((i % 12U) == 11U || i + 1U == sizeof block) ? "\n" : "");
    }
    (void)fprintf(f, "};\n");
    if (ferror(f) != 0) {
        (void)fclose(f);
        return fail(out_path, "write error");
    }
    if (fclose(f) != 0) {
        return fail(out_path, "write error on close");
    }
    return EXIT_SUCCESS;
}
