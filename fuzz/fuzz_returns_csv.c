/// libFuzzer harness: the UMBmark returns.csv reader (tools/calib/returns_csv.h) and its
/// conversion to the firmware's integer return records. Any bytes: an error naming the file and
/// line, or records the UMBmark statistics (firmware/src/odo_umbmark.c) take without UB.
#include "fuzz_common.h"
#include "odo/odo_umbmark.h"
#include "returns_csv.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static returns_t r;
    static odo_umb_return_t ret[2][RETURNS_MAX_RUNS];
    char err[512];
    const char *path = fuzz_file(data, size, ".csv");
    if (returns_read(path, &r, err, sizeof err) != 0) {
        if (strstr(err, path) == NULL) {
            abort(); /* every rejection names the file */
        }
        return 0;
    }
    (void)returns_to_umb(&r, ret, err, sizeof err);
    return 0;
}
