#include "odo_err.h"

#include <stdio.h>

int odo_verrf_at(char *err, size_t errlen, const char *origin, const char *where, const char *fmt, va_list ap)
{
    if (err == NULL || errlen == 0U) {
        return -1;
    }
    int n = 0;
    if (origin != NULL) {
        n = snprintf(err, errlen, "%s: %s%s", origin, where != NULL ? where : "", where != NULL ? ": " : "");
    }
    if (n >= 0 && (size_t)n < errlen) {
        (void)vsnprintf(err + n, errlen - (size_t)n, fmt, ap);
    }
    return -1;
}

int odo_errf_at(char *err, size_t errlen, const char *origin, const char *where, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)odo_verrf_at(err, errlen, origin, where, fmt, ap);
    va_end(ap);
    return -1;
}

int odo_errf(char *err, size_t errlen, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)odo_verrf_at(err, errlen, NULL, NULL, fmt, ap);
    va_end(ap);
    return -1;
}
