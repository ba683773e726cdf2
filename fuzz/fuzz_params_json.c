/// libFuzzer harness: the parameter block as JSON (tools/lib/params_json.h, jansson) and the
/// loader that tells a JSON file from a raw block by content. Whatever is accepted is a block
/// the firmware accepts (odo_params_validate) and writes back to JSON that parses to the same.
#include "fuzz_common.h"
#include "params_json.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char err[512];
    odo_params_t p, q;
    char *text = fuzz_string(data, size);
    if (odo_params_json_parse(text, "fuzz.json", &p, err, sizeof err) == 0) {
        if (odo_params_validate(&p, NULL, NULL) != ODO_PARAMS_OK) {
            abort();
        }
        char *buf = NULL;
        size_t len = 0;
        FILE *m = open_memstream(&buf, &len);
        if (m == NULL || odo_params_json_write(m, &p) != 0 || fclose(m) != 0 ||
            odo_params_json_parse(buf, "again.json", &q, err, sizeof err) != 0 || memcmp(&p, &q, sizeof p) != 0) {
            abort();
        }
        free(buf);
    }
    free(text);
    (void)odo_params_file_load(fuzz_file(data, size, ".json"), &p, err, sizeof err);
    return 0;
}
