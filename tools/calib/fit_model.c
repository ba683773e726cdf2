/// `odo-calib fit`: the model and its least-squares fit (fit_model.h).
#include "fit_model.h"
#include "odo_err.h"

#include <gsl/gsl_blas.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo_ref.h"

#define Q30 1073741824.0

static int32_t q30(double v) { return (int32_t)llround(v * Q30); }

void fit_params_to_truck(const fit_params_t *p, odo_truck_params_t *t)
{
    t->ed_q30 = q30(p->ed);
    t->eb_q30 = q30(p->eb);
    t->es_q30 = q30(p->es);
    t->scrub_q30 = q30(p->k);
}

void fit_params_from_truck(const odo_truck_params_t *t, fit_params_t *p)
{
    p->ed = odo_ref_q30(t->ed_q30);
    p->eb = odo_ref_q30(t->eb_q30);
    p->es = odo_ref_q30(t->es_q30);
    p->k = odo_ref_q30(t->scrub_q30);
}

void fit_integrate(const fit_run_t *run, const odo_truck_params_t *base, unsigned heading_form, const fit_params_t *p,
                   double x0, double y0, double th0, double *x, double *y, double *th)
{
    odo_truck_params_t tp = *base;
    fit_params_to_truck(p, &tp);
    odo_ref_t r;
    odo_ref_init(&r, &tp, (uint8_t)heading_form, x0, y0, th0); /* the scrub term included */
    for (size_t i = 0; i < run->n; ++i) {
        if (i > 0) {
            odo_ref_step(&r, run->delta[i][0], run->delta[i][1]);
        }
        if (x != NULL)
            x[i] = r.x_mm;
        if (y != NULL)
            y[i] = r.y_mm;
        if (th != NULL)
            th[i] = r.theta_rad;
    }
}

/* ---------------------------------------------------------------------------------------------
 * Parameter vector: free model parameters, scaled to order one ((E - 1) x 1e3, k x 1e3), then per
 * folder with a fitted track lx, ly (mm), phi (mrad).
 * ------------------------------------------------------------------------------------------- */
typedef struct {
    const fit_set_t *s;
    const odo_truck_params_t *base;
    unsigned form;
    fit_params_t start;
    fit_free_t fr;
    int rig_slot[FIT_MAX_GROUPS]; /* index of lx in x, or -1 */
    size_t np;
    double *bx, *by, *bth; /* scratch, longest run */
} ctx_t;

static void unpack(const ctx_t *c, const gsl_vector *v, fit_params_t *p, fit_rig_t *rig)
{
    size_t j = 0;
    *p = c->start;
    if (c->fr.ed)
        p->ed = 1.0 + gsl_vector_get(v, j++) * 1e-3;
    if (c->fr.eb)
        p->eb = 1.0 + gsl_vector_get(v, j++) * 1e-3;
    if (c->fr.es)
        p->es = 1.0 + gsl_vector_get(v, j++) * 1e-3;
    if (c->fr.k)
        p->k = gsl_vector_get(v, j++) * 1e-3;
    for (size_t g = 0; g < FIT_MAX_GROUPS; ++g) {
        memset(&rig[g], 0, sizeof rig[g]);
        if (c->rig_slot[g] >= 0) {
            const size_t o = (size_t)c->rig_slot[g];
            rig[g].lx_mm = gsl_vector_get(v, o);
            rig[g].ly_mm = gsl_vector_get(v, o + 1);
            rig[g].phi_rad = gsl_vector_get(v, o + 2) * 1e-3;
            rig[g].fitted = true;
        }
    }
}

static size_t n_residuals(const fit_set_t *s)
{
    size_t n = 0;
    for (size_t i = 0; i < s->n_runs; ++i) {
        const fit_run_t *r = &s->run[i];
        if (r->fit) {
            n += r->has_track ? 3 * (r->n - 1) : 3;
        }
    }
    return n;
}

/* Axle-centre start pose from the tracked point's first sample. */
static void centre_pose(const fit_run_t *r, size_t i, const fit_rig_t *g, double *x, double *y, double *th)
{
    const double a = r->tth_rad[i] - g->phi_rad, c = cos(a), sn = sin(a);
    *x = r->tx_mm[i] - (c * g->lx_mm - sn * g->ly_mm);
    *y = r->ty_mm[i] - (sn * g->lx_mm + c * g->ly_mm);
    *th = a;
}

static int residuals(const gsl_vector *v, void *user, gsl_vector *f)
{
    const ctx_t *c = user;
    fit_params_t p;
    static fit_rig_t rig[FIT_MAX_GROUPS];
    unpack(c, v, &p, rig);
    const double wb = c->base->wheelbase_nm * 1e-6; /* mm per rad of heading residual */
    size_t k = 0;
    for (size_t i = 0; i < c->s->n_runs; ++i) {
        const fit_run_t *r = &c->s->run[i];
        if (!r->fit) {
            continue;
        }
        if (r->has_track) {
            const fit_rig_t *g = &rig[r->group];
            double x0, y0, th0;
            centre_pose(r, 0, g, &x0, &y0, &th0);
            fit_integrate(r, c->base, c->form, &p, x0, y0, th0, c->bx, c->by, c->bth);
            for (size_t t = 1; t < r->n; ++t) {
                const double cs = cos(c->bth[t]), sn = sin(c->bth[t]);
                gsl_vector_set(f, k++, c->bx[t] + cs * g->lx_mm - sn * g->ly_mm - r->tx_mm[t]);
                gsl_vector_set(f, k++, c->by[t] + sn * g->lx_mm + cs * g->ly_mm - r->ty_mm[t]);
                gsl_vector_set(f, k++, (c->bth[t] + g->phi_rad - r->tth_rad[t]) * wb);
            }
        } else {
            fit_return_err_t e;
            fit_return_error(r, c->base, c->form, &p, &rig[r->group], &e);
            const double w = sqrt((double)r->n);
            gsl_vector_set(f, k++, e.ex_mm * w);
            gsl_vector_set(f, k++, e.ey_mm * w);
            gsl_vector_set(f, k++, e.eth_deg * M_PI / 180.0 * wb * w);
        }
    }
    return GSL_SUCCESS;
}

void fit_return_error(const fit_run_t *run, const odo_truck_params_t *base, unsigned heading_form,
                      const fit_params_t *p, const fit_rig_t *rig, fit_return_err_t *e)
{
    double x, y, th;
    /* the model's return: from the origin, heading +x; only the end pose is kept */
    {
        odo_truck_params_t tp = *base;
        fit_params_to_truck(p, &tp);
        odo_ref_t r;
        odo_ref_init(&r, &tp, (uint8_t)heading_form, 0.0, 0.0, 0.0);
        for (size_t i = 1; i < run->n; ++i) {
            odo_ref_step(&r, run->delta[i][0], run->delta[i][1]);
        }
        x = r.x_mm;
        y = r.y_mm;
        th = r.theta_rad;
    }
    double tx, ty, tth;
    if (run->has_track) {
        double x0, y0, a0, x1, y1, a1;
        centre_pose(run, 0, rig, &x0, &y0, &a0);
        centre_pose(run, run->n - 1, rig, &x1, &y1, &a1);
        const double c = cos(a0), s = sin(a0);
        tx = c * (x1 - x0) + s * (y1 - y0);
        ty = -s * (x1 - x0) + c * (y1 - y0);
        tth = a1 - a0;
    } else {
        tx = run->ret[0];
        ty = run->ret[1];
        /* a return pose carries the heading modulo a turn: take the branch nearest the model's */
        tth = run->ret[2] + 2.0 * M_PI * round((th - run->ret[2]) / (2.0 * M_PI));
    }
    e->ex_mm = x - tx;
    e->ey_mm = y - ty;
    e->eth_deg = (th - tth) * 180.0 / M_PI;
    e->pos_mm = hypot(e->ex_mm, e->ey_mm);
}

int fit_run_fit(const fit_set_t *s, const odo_truck_params_t *base, unsigned heading_form, const fit_params_t *start,
                fit_free_t free_, fit_result_t *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    ctx_t c = {s, base, heading_form, *start, free_, {0}, 0, NULL, NULL, NULL};
    bool any_track = false;
    size_t longest = 0;
    for (size_t g = 0; g < FIT_MAX_GROUPS; ++g) {
        c.rig_slot[g] = -1;
    }
    for (size_t i = 0; i < s->n_runs; ++i) {
        longest = s->run[i].n > longest ? s->run[i].n : longest;
        any_track = any_track || (s->run[i].fit && s->run[i].has_track);
    }
    if (!any_track) {
        c.fr.es = false; /* closed paths do not show the scale (optiodom README; 000 App. B) */
    }
    c.np = (size_t)c.fr.ed + (size_t)c.fr.eb + (size_t)c.fr.es + (size_t)c.fr.k;
    for (size_t i = 0; i < s->n_runs; ++i) {
        const fit_run_t *r = &s->run[i];
        if (r->fit && r->has_track && c.rig_slot[r->group] < 0) {
            c.rig_slot[r->group] = (int)c.np;
            c.np += 3;
        }
    }
    const size_t nr = n_residuals(s);
    if (c.np == 0) {
        return odo_errf(err, errlen, "nothing to fit: every parameter is fixed");
    }
    if (nr < c.np) {
        return odo_errf(err, errlen, "%zu residuals for %zu unknowns: fit more runs", nr, c.np);
    }
    c.bx = malloc(longest * sizeof(double));
    c.by = malloc(longest * sizeof(double));
    c.bth = malloc(longest * sizeof(double));
    gsl_vector *x = gsl_vector_calloc(c.np);
    {
        size_t j = 0;
        if (c.fr.ed)
            gsl_vector_set(x, j++, (start->ed - 1.0) * 1e3);
        if (c.fr.eb)
            gsl_vector_set(x, j++, (start->eb - 1.0) * 1e3);
        if (c.fr.es)
            gsl_vector_set(x, j++, (start->es - 1.0) * 1e3);
        if (c.fr.k)
            gsl_vector_set(x, j++, start->k * 1e3);
    }
    gsl_multifit_nlinear_fdf fdf = {0};
    fdf.f = residuals;
    fdf.df = NULL; /* finite differences */
    fdf.n = nr;
    fdf.p = c.np;
    fdf.params = &c;
    gsl_multifit_nlinear_parameters fp = gsl_multifit_nlinear_default_parameters();
    fp.h_df = 1e-4; /* in the scaled units: about 100 Q30 steps of Ed, so block rounding does not
                       make the Jacobian noisy */
    gsl_multifit_nlinear_workspace *w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &fp, nr, c.np);
    int rc = 0;
    if (c.bx == NULL || c.by == NULL || c.bth == NULL || x == NULL || w == NULL) {
        rc = odo_errf(err, errlen, "out of memory (%zu residuals x %zu unknowns)", nr, c.np);
    }
    int info = 0;
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    if (rc == 0) {
        gsl_multifit_nlinear_init(x, &fdf, w);
        const int st = gsl_multifit_nlinear_driver(200, 1e-10, 1e-10, 1e-12, NULL, NULL, &info, w);
        out->converged = st == GSL_SUCCESS;
        out->iterations = (int)gsl_multifit_nlinear_niter(w);
        const gsl_vector *xf = gsl_multifit_nlinear_position(w);
        unpack(&c, xf, &out->p, out->rig);
        const gsl_vector *fr = gsl_multifit_nlinear_residual(w);
        double chisq = 0.0;
        gsl_blas_ddot(fr, fr, &chisq);
        out->n_residuals = nr;
        out->rms_mm = sqrt(chisq / (double)nr);
        gsl_matrix *cov = gsl_matrix_alloc(c.np, c.np);
        if (cov != NULL && gsl_multifit_nlinear_covar(gsl_multifit_nlinear_jac(w), 0.0, cov) == GSL_SUCCESS) {
            const double sc = nr > c.np ? chisq / (double)(nr - c.np) : 0.0;
            size_t j = 0;
            if (c.fr.ed) {
                out->sd.ed = sqrt(gsl_matrix_get(cov, j, j) * sc) * 1e-3;
                j++;
            }
            if (c.fr.eb) {
                out->sd.eb = sqrt(gsl_matrix_get(cov, j, j) * sc) * 1e-3;
                j++;
            }
            if (c.fr.es) {
                out->sd.es = sqrt(gsl_matrix_get(cov, j, j) * sc) * 1e-3;
                j++;
            }
            if (c.fr.k) {
                out->sd.k = sqrt(gsl_matrix_get(cov, j, j) * sc) * 1e-3;
                j++;
            }
        }
        gsl_matrix_free(cov);
        if (!out->converged) {
            rc = odo_errf(err, errlen, "the fit did not converge in %d iterations", out->iterations);
        } else if (fabs(out->p.k) > FIT_SCRUB_MAX || fabs(out->p.ed - 1.0) > 0.2 || fabs(out->p.eb - 1.0) > 0.2 ||
                   fabs(out->p.es - 1.0) > 0.2) {
            rc = odo_errf(err, errlen,
                          "fitted parameters out of the block's range (Ed %.5f, Eb %.5f, Es %.5f, scrub %.5f): "
                          "runs of another robot, or a wrong robot description?",
                          out->p.ed, out->p.eb, out->p.es, out->p.k);
        }
    }
    gsl_set_error_handler(old);
    out->es_free = c.fr.es;
    out->k_free = c.fr.k;
    gsl_multifit_nlinear_free(w);
    gsl_vector_free(x);
    free(c.bx);
    free(c.by);
    free(c.bth);
    return rc;
}
