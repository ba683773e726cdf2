/// libFuzzer harness: the firmware-image patcher (tools/calib/image.h): raw .bin found by magic,
/// Intel HEX, ELF .odo_params. Byte 0 picks the file name's suffix; any image: a refusal with a
/// reason, or a block that is patched through hostlib/odo_out into a fresh file that loads back
/// with the new block and the old file untouched.
#include "fuzz_common.h"
#include "image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1U) {
        return 0;
    }
    static const char *const suffix[] = {".bin", ".hex", ".elf", ""};
    const char *path = fuzz_file(data + 1, size - 1U, suffix[data[0] & 3U]);
    img_t img;
    char err[512];
    if (img_load(path, &img, err, sizeof err) != 0) {
        return 0;
    }
    if (img.status == ODO_PARAMS_OK || img.status == ODO_PARAMS_ERR_CRC) {
        odo_params_t p;
        odo_params_defaults(&p);
        p.truck[0].ed_q30 = 1073741824 + 12345;
        uint8_t block[ODO_PARAMS_SIZE];
        (void)odo_params_encode(&p, block, sizeof block);
        char out[300];
        snprintf(out, sizeof out, "%s.out%s", path, suffix[data[0] & 3U]);
        if (img_write_patched(&img, block, out, NULL, err, sizeof err) == 0) {
            img_t back;
            if (img_load(out, &back, err, sizeof err) != 0 || back.status != ODO_PARAMS_OK ||
                memcmp(back.block, block, ODO_PARAMS_SIZE) != 0) {
                abort();
            }
            img_free(&back);
            (void)unlink(out);
        }
    }
    img_free(&img);
    return 0;
}
