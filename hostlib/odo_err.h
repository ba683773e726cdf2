/* One-line error messages into a caller's buffer: the form every host tool's parser and writer
 * reports a bad input in ("<origin>: <where>: <why>"), written here once. */
#ifndef ODO_ERR_H
#define ODO_ERR_H

#include <stdarg.h>
#include <stddef.h>

#if defined(__GNUC__)
#define ODO_ERR_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define ODO_ERR_PRINTF(f, a)
#endif

/* Formats into err (nothing when err is NULL or errlen is 0; truncated to errlen - 1 characters)
 * and returns -1, so a parser can `return odo_errf(err, errlen, "...", ...)`. */
int odo_errf(char *err, size_t errlen, const char *fmt, ...) ODO_ERR_PRINTF(3, 4);

/* The same with "<origin>: <where>: " in front; where may be NULL ("<origin>: " only). */
int odo_errf_at(char *err, size_t errlen, const char *origin, const char *where, const char *fmt, ...)
    ODO_ERR_PRINTF(5, 6);
int odo_verrf_at(char *err, size_t errlen, const char *origin, const char *where, const char *fmt, va_list ap)
    ODO_ERR_PRINTF(5, 0);

#endif
