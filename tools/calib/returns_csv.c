/// returns.csv reader. See returns_csv.h.
#include "returns_csv.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char k_header[] = "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg";
static const char *const k_cols[] = {"run",           "direction", "x_abs_mm",  "y_abs_mm",
                                     "theta_abs_deg", "x_calc_mm", "y_calc_mm", "theta_calc_deg"};

static void chomp(char *s)
{
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == '\n' || s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t')) {
        s[--n] = '\0';
    }
}

int returns_read(const char *path, returns_t *r, char *err, size_t errlen)
{
    memset(r, 0, sizeof *r);
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    char line[1024];
    unsigned lineno = 0;
    int have_header = 0, rc = 0;
    while (rc == 0 && fgets(line, sizeof line, f) != NULL) {
        lineno++;
        if (strchr(line, '\n') == NULL && !feof(f)) {
            snprintf(err, errlen, "%s:%u: line longer than %zu characters", path, lineno, sizeof line - 2);
            rc = -1;
            break;
        }
        chomp(line);
        if (line[0] == '\0' || line[0] == '#') {
            continue;
        }
        if (!have_header) {
            if (strcmp(line, k_header) != 0) {
                snprintf(err, errlen, "%s:%u: header must be '%s'", path, lineno, k_header);
                rc = -1;
                break;
            }
            have_header = 1;
            continue;
        }
        char *field[9];
        size_t nf = 0;
        for (char *p = line;;) {
            if (nf < 9) {
                field[nf] = p;
            }
            nf++;
            char *comma = strchr(p, ',');
            if (comma == NULL) {
                break;
            }
            *comma = '\0';
            p = comma + 1;
        }
        if (nf != 8) {
            snprintf(err, errlen, "%s:%u: %zu fields, expected 8 (%s)", path, lineno, nf, k_header);
            rc = -1;
            break;
        }
        char *end = NULL;
        errno = 0;
        const long run = strtol(field[0], &end, 10);
        if (errno != 0 || end == field[0] || *end != '\0' || run < 1 || run > 1000000) {
            snprintf(err, errlen, "%s:%u: field 1 (run): '%s' is not a positive integer", path, lineno, field[0]);
            rc = -1;
            break;
        }
        int d;
        if (strcmp(field[1], "cw") == 0) {
            d = 0;
        } else if (strcmp(field[1], "ccw") == 0) {
            d = 1;
        } else {
            snprintf(err, errlen,
                     "%s:%u: field 2 (direction): '%s' must be cw or ccw (UMBmark is a square "
                     "run both ways)",
                     path, lineno, field[1]);
            rc = -1;
            break;
        }
        double v[6];
        for (int k = 0; k < 6 && rc == 0; ++k) {
            errno = 0;
            end = NULL;
            v[k] = strtod(field[2 + k], &end);
            const bool angle = k == 2 || k == 5;
            const double lim = angle ? RETURNS_MAX_ABS_DEG : RETURNS_MAX_ABS_MM;
            if (end == field[2 + k] || *end != '\0' || errno == ERANGE || !isfinite(v[k])) {
                snprintf(err, errlen, "%s:%u: field %d (%s): '%s' is not a finite number", path, lineno, 3 + k,
                         k_cols[2 + k], field[2 + k]);
                rc = -1;
            } else if (fabs(v[k]) > lim) {
                /* Beyond it the difference of two such values loses the resolution the
                 * calibration works in (1 um, 1 micro-degree); 1e308 deg came out as 0. */
                snprintf(err, errlen, "%s:%u: field %d (%s): '%s' is beyond +-%.0e %s: not a %s", path, lineno, 3 + k,
                         k_cols[2 + k], field[2 + k], lim, angle ? "deg" : "mm", angle ? "heading" : "return position");
                rc = -1;
            }
        }
        if (rc != 0) {
            break;
        }
        if (r->n[d] >= RETURNS_MAX_RUNS) {
            snprintf(err, errlen, "%s:%u: more than %u %s runs", path, lineno, RETURNS_MAX_RUNS, field[1]);
            rc = -1;
            break;
        }
        const size_t i = r->n[d]++;
        r->run[d][i] = (unsigned)run;
        r->ex_mm[d][i] = v[0] - v[3];
        r->ey_mm[d][i] = v[1] - v[4];
        r->etheta_deg[d][i] = remainder(v[2] - v[5], 360.0);
    }
    if (rc == 0 && ferror(f)) {
        snprintf(err, errlen, "%s: read error", path);
        rc = -1;
    }
    if (rc == 0 && !have_header) {
        snprintf(err, errlen, "%s:%u: empty file: no header '%s'", path, lineno, k_header);
        rc = -1;
    }
    fclose(f);
    return rc;
}

int returns_to_umb(const returns_t *r, odo_umb_return_t out[2][RETURNS_MAX_RUNS], char *err, size_t errlen)
{
    for (int d = 0; d < 2; ++d) {
        for (size_t i = 0; i < r->n[d]; ++i) {
            const double x = r->ex_mm[d][i] * 1000.0, y = r->ey_mm[d][i] * 1000.0;
            if (fabs(x) > ODO_UMB_MAX_ERR_UM || fabs(y) > ODO_UMB_MAX_ERR_UM) {
                snprintf(err, errlen,
                         "%s run %u: return error (%.1f, %.1f) mm is beyond the %.1f m the "
                         "calibration accepts",
                         d ? "ccw" : "cw", r->run[d][i], r->ex_mm[d][i], r->ey_mm[d][i], ODO_UMB_MAX_ERR_UM / 1e6);
                return -1;
            }
            out[d][i].ex_um = (int32_t)lround(x);
            out[d][i].ey_um = (int32_t)lround(y);
            out[d][i].etheta_udeg = (int32_t)lround(r->etheta_deg[d][i] * 1e6);
        }
    }
    return 0;
}
