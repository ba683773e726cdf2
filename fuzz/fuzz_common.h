/// Shared by the harnesses whose parsers read a path: the input goes into one private temp file
/// (on tmpfs when /dev/shm exists), rewritten each run.
#ifndef ODO_FUZZ_COMMON_H
#define ODO_FUZZ_COMMON_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/// A temp path ending in `suffix`, made once per process; the file holds data[0..size).
static inline const char *fuzz_file(const uint8_t *data, size_t size, const char *suffix)
{
    static char path[256];
    if (path[0] == '\0') {
        const char *dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        snprintf(path, sizeof path, "%s/odo-fuzz-%ld%s", dir, (long)getpid(), suffix);
    }
    FILE *f = fopen(path, "wb");
    if (f == NULL || (size > 0U && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        abort();
    }
    return path;
}

/// data as a NUL-terminated string (malloc'd; free it).
static inline char *fuzz_string(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 1U);
    if (s == NULL) {
        abort();
    }
    memcpy(s, data, size);
    s[size] = '\0';
    return s;
}

#endif
