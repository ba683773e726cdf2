/// odo_cli: see odo_cli.h.
#include "odo_cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef ODO_VERSION
#error "ODO_VERSION comes from CMake's project(VERSION) (hostlib/CMakeLists.txt)"
#endif

const char *odo_cli_version(void) { return ODO_VERSION; }

void odo_cli_print_version(const char *prog) { printf("%s %s\n", prog, ODO_VERSION); }

int odo_cli_ipec(const char *prog, const char *value)
{
    if (strcmp(value, "off") == 0) {
        return 0;
    }
    if (strcmp(value, "on") == 0 || strcmp(value, "paper") == 0) {
        return 1;
    }
    if (strcmp(value, "estimator") == 0) {
        return 2;
    }
    fprintf(stderr, "%s: --ipec must be off, on, paper or estimator, not '%s'\n", prog, value);
    return -1;
}

bool odo_cli_seed(const char *prog, const char *value, uint64_t *seed)
{
    char *end = NULL;
    errno = 0;
    const unsigned long long v = strtoull(value, &end, 10);
    if (value[0] < '0' || value[0] > '9' || errno != 0 || end == value || *end != '\0') {
        fprintf(stderr, "%s: --seed must be a non-negative integer, not '%s'\n", prog, value);
        return false;
    }
    *seed = (uint64_t)v;
    return true;
}

bool odo_cli_long(const char *prog, const char *name, const char *value, long lo, long hi, long *out)
{
    char *end = NULL;
    errno = 0;
    const long v = strtol(value, &end, 10);
    if (errno != 0 || end == value || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "%s: %s must be an integer in [%ld, %ld], not '%s'\n", prog, name, lo, hi, value);
        return false;
    }
    *out = v;
    return true;
}

void odo_cli_usage_hint(const char *prog) { fprintf(stderr, "%s: see %s --help\n", prog, prog); }

bool odo_cli_split_equals(int *argc, char ***argv)
{
    const int n = *argc;
    char **in = *argv;
    size_t extra = 0;
    for (int i = 1; i < n; ++i) {
        extra += strncmp(in[i], "--", 2) == 0 && strchr(in[i], '=') != NULL;
    }
    if (extra == 0U) {
        return true;
    }
    char **out = calloc((size_t)n + extra + 1U, sizeof *out);
    if (out == NULL) {
        return false;
    }
    int k = 0;
    for (int i = 0; i < n; ++i) {
        char *eq = (i > 0 && strncmp(in[i], "--", 2) == 0) ? strchr(in[i], '=') : NULL;
        if (eq == NULL) {
            out[k++] = in[i];
            continue;
        }
        *eq = '\0'; /* argv strings are ours to modify (C99 5.1.2.2.1) */
        out[k++] = in[i];
        out[k++] = eq + 1;
    }
    out[k] = NULL;
    *argc = k;
    *argv = out;
    return true;
}
