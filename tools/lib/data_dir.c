#include "data_dir.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/// "<root>/<rel>" into out; "" and -1 when it does not fit.
static int join(char *out, size_t out_len, const char *root, const char *rel)
{
    const int n = snprintf(out, out_len, "%s/%s", root, rel);
    if (n < 0 || (size_t)n >= out_len) {
        out[0] = '\0';
        return -1;
    }
    return 0;
}

int odo_data_path(const char *rel, char *out, size_t out_len)
{
    if (out_len == 0U) {
        return -1;
    }
    const char *env = getenv("ODO_SOURCE_DIR");
    if (env != NULL && env[0] != '\0') {
        return join(out, out_len, env, rel);
    }
    char exe[PATH_MAX];
    const ssize_t k = readlink("/proc/self/exe", exe, sizeof exe - 1U);
    exe[k > 0 ? k : 0] = '\0';
    char *slash = strrchr(exe, '/');
    if (slash != NULL) {
        *slash = '\0';
    }
    char root[PATH_MAX + 32];
    struct stat st;
    /* A build tree, build/<preset>/bin, inside a checkout. */
    snprintf(root, sizeof root, "%s/../../..", exe);
    char probe[sizeof root + 32];
    snprintf(probe, sizeof probe, "%s/can/odometry.dbc", root);
    if (stat(probe, &st) != 0 || !S_ISREG(st.st_mode)) {
        snprintf(root, sizeof root, "%s/../share/odometry", exe); /* installed: PREFIX/bin */
    }
    return join(out, out_len, root, rel);
}
