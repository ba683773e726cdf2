/// odo-calib's parameter-block writer (params_out.h), shared by `umbmark` and `fit`.
#include "params_out.h"

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo_params_json.h"

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
        fprintf(stderr, "odo-calib: %s\n", err);
        return -1;
    }
    return 0;
}

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
        fprintf(stderr, "odo-calib: out of memory\n");
        return -1;
    }
    const int rc = write_atomic(path, buf, len, ins);
    free(buf);
    return rc;
}
