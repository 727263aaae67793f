/*
 * Hand-written TDROC step for Drishti, paper and minimal formulations, double or float32
 * (-DWMR_FLOAT32): what a careful firmware engineer writes from the paper to be fast, under
 * the generated step's contract. Typed from the paper, not from generated code; the
 * benchmark checks it against wmr_tdroc_step (statuses on bad inputs and configurations,
 * torques over a recorded closed loop) before timing it. Not used by the toolchain.
 *
 * Contract (the generated step's): NULL pointers, then a state not initialised, then the
 * configuration compared bit for bit with the copy _init kept (a differing one is validated:
 * its field's error, else CONFIG_CHANGED), then the inputs (|x| <= 1e6: q, qdot ->
 * BAD_MEASUREMENT, else BAD_REFERENCE), then a non-finite result (tau, k-hat, ||s||, the
 * discarded rows of u) -> NONFINITE_OUTPUT, then saturation (WARN_SATURATED); the state and
 * tau are written only on success.
 *
 * What makes it fast, everything else being the paper's arithmetic:
 * - M-tilde(theta) of (14) is never built: its product with a vector is written out from
 *   its structure (m, K, Iz, Iw and three coefficients kept from _init; sin and cos of
 *   theta once a step, kept for the next step's (17)); the minimal form's S^T M S is
 *   constant for Drishti, so _init keeps its two entries;
 * - _init keeps every configuration-only quantity: P, 1/span and the (17) blend of inputs,
 *   the weights a^i and ||Mhat^-1|| / sum a^i for every window length (the filling window
 *   needs no normalisation per step);
 * - the window keeps its difference norms (one new norm a step), each written twice in a
 *   buffer of twice the window so the newest n are contiguous: no shift, no % ring index;
 * - the configuration check ORs the XOR of every value's bits (independent compares);
 *   the input check ORs the magnitude-bit compares of all 25 inputs (one branch).
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "hand_tdroc.h"

#ifdef HAND_FROZEN
#include "wmr_tdroc_frozen.h"
const wmr_tdroc_config_t HAND_NAME(frozen_config) = WMR_TDROC_FROZEN_CONFIG;
#endif

typedef wmr_real_t real;
#define L(x) WMR_LIT(x)
#ifdef WMR_FLOAT32
typedef uint32_t bits_t;
#define MAG_MASK 0x7fffffffu
#define HSIN(x) sinf(x)
#define HCOS(x) cosf(x)
#define HSQRT(x) sqrtf(x)
#define HFABS(x) fabsf(x)
#define HREAL_MAX FLT_MAX
#else
typedef uint64_t bits_t;
#define MAG_MASK UINT64_C(0x7fffffffffffffff)
#define HSIN(x) sin(x)
#define HCOS(x) cos(x)
#define HSQRT(x) sqrt(x)
#define HFABS(x) fabs(x)
#define HREAL_MAX DBL_MAX
#endif

static bits_t bits(real x)
{
    bits_t b;
    memcpy(&b, &x, sizeof b);
    return b;
}

static int within(real x, real lo, real hi) { return x >= lo && x <= hi; }

/* sqrt(sum x_i^2) that does not overflow while the x_i are finite. */
static real norm_n(const real *x, int n, real sum)
{
    real big = L(0.0), acc = L(0.0);
    int i;
    if (sum <= HREAL_MAX) {
        return HSQRT(sum);
    }
    for (i = 0; i < n; ++i) {
        const real a = HFABS(x[i]);
        big = a > big ? a : big;
    }
    for (i = 0; i < n; ++i) {
        const real t = x[i] / big;
        acc += t * t;
    }
    return big * HSQRT(acc);
}

/* P of (20) for A = [[0, 1], [-k1, -k2]], Q = diag(q1, q2). */
static void lyap(real k1, real k2, real q1, real q2, real *p11, real *p12, real *p22)
{
    *p11 = (k1 * k1 * q2 + k1 * q1 + k2 * k2 * q1) / (L(2.0) * k1 * k2);
    *p12 = q1 / (L(2.0) * k1);
    *p22 = (k1 * q2 + q1) / (L(2.0) * k1 * k2);
}

/* M-tilde(theta) of (14) times x, from its structure (see the file comment). */
typedef struct { real m, K, Iz, Iw, ca, cb, k5; } mt_t;

static void mt_mul(const mt_t *c, real s, real co, const real x[5], real y[5])
{
    const real sx = x[3] + x[4], dx = x[3] - x[4];
    const real a = s * x[0] - co * x[1], bb = co * x[0] + s * x[1];
    const real t = c->K * x[2] + c->ca * dx, u = c->cb * sx;
    const real ka = c->ca * a, kb = c->cb * bb, k5x = c->k5 * x[2];
    y[0] = c->m * x[0] + s * t - co * u;
    y[1] = c->m * x[1] - co * t - s * u;
    y[2] = c->K * a + c->Iz * x[2] - c->k5 * dx;
    y[3] = kb - ka + k5x + c->Iw * x[3];
    y[4] = kb + ka - k5x + c->Iw * x[4];
}

static void mt_coeffs(const wmr_params_t *p, mt_t *c)
{
    c->m = p->m;
    c->K = p->K;
    c->Iz = p->Iz;
    c->Iw = p->Iw;
    c->ca = (p->m * p->d - p->K) * p->r / p->b;
    c->cb = L(0.5) * p->m * p->r;
    c->k5 = p->r * (p->Iz - p->K * p->d) / p->b;
}

/* S^T M S of the minimal form: [[a11, a12], [a12, a11]]. */
static void mbar(const wmr_params_t *p, real *a11, real *a12)
{
    const real ia = p->Iz - L(2.0) * p->K * p->d + p->m * p->d * p->d;
    const real rb2 = p->r * p->r / (p->b * p->b);
    const real q = L(0.25) * p->m * p->r * p->r;
    *a11 = p->Iw + q + ia * rb2;
    *a12 = q - ia * rb2;
}

/* ||Mhat^-1||_F: the minimal form's in closed form, the paper form's at theta = 0 by
   Gauss-Jordan with partial pivoting (_init and the configuration check only). */
static real minv_norm(const wmr_params_t *p, int paper)
{
    real a[5][10], x[5], y[5];
    real sum = L(0.0);
    mt_t c;
    int i, j, k;
    if (!paper) {
        real a11, a12, det;
        mbar(p, &a11, &a12);
        det = a11 * a11 - a12 * a12;
        return HSQRT(L(2.0) * (a11 * a11 + a12 * a12)) / HFABS(det);
    }
    mt_coeffs(p, &c);
    for (j = 0; j < 5; ++j) {  /* column j of M-tilde(0) */
        for (i = 0; i < 5; ++i) {
            x[i] = i == j ? L(1.0) : L(0.0);
        }
        mt_mul(&c, L(0.0), L(1.0), x, y);
        for (i = 0; i < 5; ++i) {
            a[i][j] = y[i];
            a[i][5 + j] = i == j ? L(1.0) : L(0.0);
        }
    }
    for (k = 0; k < 5; ++k) {
        int piv = k;
        for (i = k + 1; i < 5; ++i) {
            if (HFABS(a[i][k]) > HFABS(a[piv][k])) {
                piv = i;
            }
        }
        for (j = 0; j < 10; ++j) {
            const real t = a[k][j];
            a[k][j] = a[piv][j];
            a[piv][j] = t;
        }
        for (j = 9; j >= k; --j) {
            a[k][j] /= a[k][k];
        }
        for (i = 0; i < 5; ++i) {
            if (i != k) {
                const real f = a[i][k];
                for (j = k; j < 10; ++j) {
                    a[i][j] -= f * a[k][j];
                }
            }
        }
    }
    for (i = 0; i < 5; ++i) {
        for (j = 5; j < 10; ++j) {
            sum += a[i][j] * a[i][j];
        }
    }
    return HSQRT(sum);
}

static wmr_status_t check_config(const wmr_tdroc_config_t *c)
{
    /* Drishti's nominal bounds (the robot file's values times and over 1000) */
    static const real lo[7] = {-L(36000.0), -L(5720.0), -L(1000.0), -L(1000.0), L(9.6e-05),
                               L(0.000414), -L(1000.0)};
    static const real hi[7] = {L(36000.0), L(5720.0), L(1000.0), L(1000.0), L(1000.0),
                               L(1000.0), L(1000.0)};
    const wmr_params_t *p = &c->nominal;
    const real pv[7] = {p->m, p->Iz, p->K, p->Iw, p->r, p->b, p->d};
    int i;
    if (c->formulation != WMR_FORMULATION_PAPER && c->formulation != WMR_FORMULATION_MINIMAL) {
        return WMR_ERR_BAD_FORMULATION;
    }
    if (!within(c->h, WMR_H_MIN, WMR_H_MAX)) {
        return WMR_ERR_BAD_SAMPLE_TIME;
    }
    for (i = 0; i < 5; ++i) {
        if (!within(c->k1[i], WMR_GAIN_MIN, WMR_GAIN_MAX)
            || !within(c->k2[i], WMR_GAIN_MIN, WMR_GAIN_MAX)) {
            return WMR_ERR_BAD_GAINS;
        }
    }
    if (!within(c->q_pos, WMR_GAIN_MIN, WMR_GAIN_MAX)
        || !within(c->q_vel, WMR_GAIN_MIN, WMR_GAIN_MAX)) {
        return WMR_ERR_BAD_GAINS;
    }
    for (i = 0; i < 5; ++i) {
        real a, b, d;
        lyap(c->k1[i], c->k2[i], c->q_pos, c->q_vel, &a, &b, &d);
        if (!isfinite(a) || !isfinite(b) || !isfinite(d)) {
            return WMR_ERR_BAD_GAINS;
        }
    }
    if (!(c->tau_max > L(0.0) && c->tau_max <= WMR_TORQUE_LIMIT_MAX)) {
        return WMR_ERR_BAD_TORQUE_LIMIT;
    }
    if (!within(c->eps, WMR_GAIN_MIN, WMR_GAIN_MAX)) {
        return WMR_ERR_BAD_EPS;
    }
    if (c->accel_estimator < WMR_ACCEL_BACKWARD || c->accel_estimator > WMR_ACCEL_MATCHED
        || !within(c->rate_window, L(0.0), c->h)) {
        return WMR_ERR_BAD_ESTIMATOR;
    }
    if ((c->hold_gain != 0 && c->hold_gain != 1) || !within(c->held_gain, L(0.0), WMR_GAIN_MAX)) {
        return WMR_ERR_BAD_HELD_GAIN;
    }
    if (c->n < 2 || c->n > WMR_MAX_WINDOW) {
        return WMR_ERR_BAD_WINDOW;
    }
    if (!(c->a > L(0.0) && c->a <= L(1.0))) {
        return WMR_ERR_BAD_DISCOUNT;
    }
    for (i = 0; i < 7; ++i) {
        if (!within(pv[i], lo[i], hi[i])) {
            return WMR_ERR_BAD_NOMINAL;
        }
    }
    {   /* S^T M S positive definite; m, I, Iw > 0; m I - K^2 > 0 */
        real a11, a12;
        mbar(p, &a11, &a12);
        if (!(a11 > L(0.0)) || !(a11 * a11 - a12 * a12 > L(0.0)) || !(p->m > L(0.0))
            || !(p->Iz > L(0.0)) || !(p->Iw > L(0.0)) || !(p->Iz * p->m - p->K * p->K > L(0.0))) {
            return WMR_ERR_BAD_NOMINAL;
        }
    }
    if (!isfinite(minv_norm(p, c->formulation == WMR_FORMULATION_PAPER))) {
        return WMR_ERR_BAD_NOMINAL;
    }
    return WMR_OK;
}

#ifndef HAND_FROZEN
/* Bit for bit the kept configuration (padding never compared). */
static int unchanged(const wmr_tdroc_config_t *c, const wmr_tdroc_config_t *k)
{
    bits_t d = 0u;
    int i;
    for (i = 0; i < 5; ++i) {
        d |= (bits(c->k1[i]) ^ bits(k->k1[i])) | (bits(c->k2[i]) ^ bits(k->k2[i]));
    }
    d |= (bits(c->nominal.m) ^ bits(k->nominal.m)) | (bits(c->nominal.Iz) ^ bits(k->nominal.Iz))
        | (bits(c->nominal.K) ^ bits(k->nominal.K)) | (bits(c->nominal.Iw) ^ bits(k->nominal.Iw))
        | (bits(c->nominal.r) ^ bits(k->nominal.r)) | (bits(c->nominal.b) ^ bits(k->nominal.b))
        | (bits(c->nominal.d) ^ bits(k->nominal.d));
    d |= (bits(c->q_pos) ^ bits(k->q_pos)) | (bits(c->q_vel) ^ bits(k->q_vel))
        | (bits(c->h) ^ bits(k->h)) | (bits(c->tau_max) ^ bits(k->tau_max))
        | (bits(c->rate_window) ^ bits(k->rate_window)) | (bits(c->eps) ^ bits(k->eps))
        | (bits(c->a) ^ bits(k->a)) | (bits(c->held_gain) ^ bits(k->held_gain));
    return d == 0u && c->formulation == k->formulation
        && c->accel_estimator == k->accel_estimator && c->n == k->n
        && c->hold_gain == k->hold_gain;
}
#endif

wmr_status_t HAND_NAME(tdroc_init)(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config)
{
    hand_tdroc_state_t s;
    wmr_status_t st;
    real wi = L(1.0), wsum = L(0.0);
    mt_t c;
    int i;
    if (state == NULL || config == NULL) {
        return WMR_ERR_NULL_POINTER;
    }
#ifdef HAND_FROZEN
    if (config != &HAND_NAME(frozen_config)) {
        return WMR_ERR_CONFIG_CHANGED;
    }
#endif
    st = check_config(config);
    if (st != WMR_OK) {
        return st;
    }
    memset(&s, 0, sizeof s);
    s.magic = WMR_STATE_MAGIC;
#ifndef HAND_FROZEN
    s.config = *config;
#endif
    s.paper = config->formulation == WMR_FORMULATION_PAPER;
    for (i = 0; i < 5; ++i) {
        real p11;
        lyap(config->k1[i], config->k2[i], config->q_pos, config->q_vel, &p11, &s.p12[i],
             &s.p22[i]);
    }
    mt_coeffs(&config->nominal, &c);
    s.m = c.m;
    s.K = c.K;
    s.Iz = c.Iz;
    s.Iw = c.Iw;
    s.ca = c.ca;
    s.cb = c.cb;
    s.k5 = c.k5;
    mbar(&config->nominal, &s.a11, &s.a12);
    s.central = config->accel_estimator == WMR_ACCEL_CENTRAL;
    s.inv_span = L(1.0) / (s.central ? L(2.0) * config->h : config->h);
    s.c2 = config->accel_estimator == WMR_ACCEL_MATCHED
        ? config->rate_window / (L(2.0) * config->h) : L(0.0);
    s.c1 = L(1.0) - s.c2;
    {
        const real mn = minv_norm(&config->nominal, s.paper);
        s.scale[0] = L(0.0);
        for (i = 0; i < WMR_MAX_WINDOW; ++i) {
            s.apow[i] = wi;
            wsum += wi;
            wi *= config->a;
            s.scale[i + 1] = mn / wsum;
        }
    }
    *state = s;
    return WMR_OK;
}

/* The improved competitor (hand_*_fast.c) includes this file for what precedes: the
   helpers, the configuration check and compare, _init; its step is its own. */
#ifndef HAND_HELPERS_ONLY
/* What the step reads that depends on the configuration only. A run-time build loads it
   from the state (_init computed it); a frozen build computes it from the compiled-in
   configuration, which the compiler folds to constants. */
typedef struct {
    mt_t c;
    real a11, a12, inv_span, c1, c2;
    real p12[5], p22[5];
    int paper, central;
} kept_t;

static inline void kept(const hand_tdroc_state_t *st, const wmr_tdroc_config_t *cfg, kept_t *k)
{
#ifdef HAND_FROZEN
    int i;
    (void)st;
    mt_coeffs(&cfg->nominal, &k->c);
    mbar(&cfg->nominal, &k->a11, &k->a12);
    k->paper = cfg->formulation == WMR_FORMULATION_PAPER;
    k->central = cfg->accel_estimator == WMR_ACCEL_CENTRAL;
    k->inv_span = L(1.0) / (k->central ? L(2.0) * cfg->h : cfg->h);
    k->c2 = cfg->accel_estimator == WMR_ACCEL_MATCHED
        ? cfg->rate_window / (L(2.0) * cfg->h) : L(0.0);
    k->c1 = L(1.0) - k->c2;
    for (i = 0; i < 5; ++i) {
        real p11;
        lyap(cfg->k1[i], cfg->k2[i], cfg->q_pos, cfg->q_vel, &p11, &k->p12[i], &k->p22[i]);
    }
#else
    const mt_t c = {st->m, st->K, st->Iz, st->Iw, st->ca, st->cb, st->k5};
    (void)cfg;
    k->c = c;
    k->a11 = st->a11;
    k->a12 = st->a12;
    k->paper = st->paper;
    k->central = st->central;
    k->inv_span = st->inv_span;
    k->c1 = st->c1;
    k->c2 = st->c2;
    memcpy(k->p12, st->p12, sizeof k->p12);
    memcpy(k->p22, st->p22, sizeof k->p22);
#endif
}

/* The step after the pointer, state and configuration checks; cfg is the kept (or the
   compiled-in) configuration. */
static inline wmr_status_t step_body(hand_tdroc_state_t *state, const wmr_tdroc_config_t *cfg,
    const real q[5], const real qdot[5], const real q_des[5], const real qdot_des[5],
    const real qddot_des[5], real tau[2])
{
    const bits_t bound = bits(L(1.0e6));
    real H1[5], u[5], e[5], ed[5], s[5], ua[5];
    real gain, sn, t0, t1, udisc, sth = L(0.0), cth = L(0.0), dnew = L(0.0);
    wmr_status_t st = WMR_OK;
    kept_t k;
    int paper, nc, off;
    const int pushed = state->steps >= 2u;
    int count = state->omega_count, head = state->head;
    unsigned meas = 0u, ref = 0u;
    int i;
    for (i = 0; i < 5; ++i) {
        meas |= ((bits(q[i]) & MAG_MASK) > bound) | ((bits(qdot[i]) & MAG_MASK) > bound);
        ref |= ((bits(q_des[i]) & MAG_MASK) > bound) | ((bits(qdot_des[i]) & MAG_MASK) > bound)
            | ((bits(qddot_des[i]) & MAG_MASK) > bound);
    }
    if ((meas | ref) != 0u) {
        return meas != 0u ? WMR_ERR_BAD_MEASUREMENT : WMR_ERR_BAD_REFERENCE;
    }
    /* the generated step's bound on the ring's head and count (issue 52): a corrupted
       state is refused before the ring is read or written */
    if (((unsigned)head >= (unsigned)WMR_MAX_WINDOW)
        || ((unsigned)count > (unsigned)WMR_MAX_WINDOW + 1u)) {
        return WMR_ERR_NOT_INITIALISED;
    }
    kept(state, cfg, &k);
    paper = k.paper;
    nc = paper ? 5 : 2;
    off = paper ? 0 : 3;
    /* (17): H1hat = u(t-h) - Mhat(q(t-h)) qddot(t-h). */
    if (pushed) {
        const real *then = k.central ? state->qdot_prev2 : state->qdot_prev;
        const real up0 = k.c1 * state->tau_prev[0] + k.c2 * state->tau_prev2[0];
        const real up1 = k.c1 * state->tau_prev[1] + k.c2 * state->tau_prev2[1];
        real qdd[5], dd[5], d2 = L(0.0);
        if (paper) {
            real mq[5];
            for (i = 0; i < 5; ++i) {
                qdd[i] = (qdot[i] - then[i]) * k.inv_span;
            }
            mt_mul(&k.c, state->sin_prev, state->cos_prev, qdd, mq);
            H1[0] = -mq[0];
            H1[1] = -mq[1];
            H1[2] = -mq[2];
            H1[3] = up0 - mq[3];
            H1[4] = up1 - mq[4];
        } else {
            qdd[3] = (qdot[3] - then[3]) * k.inv_span;
            qdd[4] = (qdot[4] - then[4]) * k.inv_span;
            H1[0] = up0 - (k.a11 * qdd[3] + k.a12 * qdd[4]);
            H1[1] = up1 - (k.a12 * qdd[3] + k.a11 * qdd[4]);
            H1[2] = H1[3] = H1[4] = L(0.0);
        }
        for (i = 0; i < nc; ++i) {  /* the window's new difference norm */
            dd[i] = H1[i] - state->H1hat[i];
            d2 += dd[i] * dd[i];
        }
        dnew = norm_n(dd, nc, d2);
        head = head == 0 ? WMR_MAX_WINDOW - 1 : head - 1;
        count += count <= WMR_MAX_WINDOW;
    } else {
        for (i = 0; i < 5; ++i) {
            H1[i] = L(0.0);
        }
    }
    /* (25) over the window as it is after this step: the new norm, then the kept ones
       (contiguous from the old head), weighted by a^i and scaled once. */
    if (cfg->hold_gain) {
        gain = cfg->held_gain;
    } else if (count >= 2) {
        const int active = count - 1 < cfg->n ? count - 1 : cfg->n;
        const real *older = &state->dn[state->head];
        real acc;
        if (pushed) {
            acc = dnew;
            for (i = 1; i < active; ++i) {
                acc += state->apow[i] * older[i - 1];
            }
        } else {
            acc = L(0.0);
            for (i = 0; i < active; ++i) {
                acc += state->apow[i] * older[i];
            }
        }
        gain = state->scale[active] * acc;
        gain = gain <= WMR_GAIN_MAX ? gain : WMR_GAIN_MAX;
    } else {
        gain = L(0.0);
    }
    /* (18), (22), (24): u_a = qddot_d + K1 e + K2 edot + k s / max(||s||, eps). */
    sn = L(0.0);
    for (i = 0; i < nc; ++i) {
        e[i] = q_des[off + i] - q[off + i];
        ed[i] = qdot_des[off + i] - qdot[off + i];
        s[i] = k.p12[off + i] * e[i] + k.p22[off + i] * ed[i];
        sn += s[i] * s[i];
    }
    sn = norm_n(s, nc, sn);
    {
        const real ks = gain / (sn >= cfg->eps ? sn : cfg->eps);
        for (i = 0; i < nc; ++i) {
            ua[i] = qddot_des[off + i] + cfg->k1[off + i] * e[i] + cfg->k2[off + i] * ed[i]
                + ks * s[i];
        }
    }
    if (paper) {
        sth = HSIN(q[2]);
        cth = HCOS(q[2]);
        mt_mul(&k.c, sth, cth, ua, u);
        for (i = 0; i < 5; ++i) {
            u[i] += H1[i];
        }
        t0 = u[3];
        t1 = u[4];
        udisc = norm_n(u, 3, u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    } else {
        t0 = k.a11 * ua[0] + k.a12 * ua[1] + H1[0];
        t1 = k.a12 * ua[0] + k.a11 * ua[1] + H1[1];
        udisc = L(0.0);
    }
    if (isnan((t0 - t0) + (t1 - t1) + (gain - gain) + (sn - sn) + (udisc - udisc))) {
        return WMR_ERR_NONFINITE_OUTPUT;
    }
    if (t0 > cfg->tau_max) { t0 = cfg->tau_max; st = WMR_WARN_SATURATED; }
    else if (t0 < -cfg->tau_max) { t0 = -cfg->tau_max; st = WMR_WARN_SATURATED; }
    if (t1 > cfg->tau_max) { t1 = cfg->tau_max; st = WMR_WARN_SATURATED; }
    else if (t1 < -cfg->tau_max) { t1 = -cfg->tau_max; st = WMR_WARN_SATURATED; }
    /* Commit. */
    if (pushed) {
        state->dn[head] = dnew;
        state->dn[head + WMR_MAX_WINDOW] = dnew;
    }
    state->head = head;
    state->omega_count = count;
    for (i = 0; i < 5; ++i) {
        state->H1hat[i] = H1[i];
        state->qdot_prev2[i] = state->qdot_prev[i];
        state->qdot_prev[i] = qdot[i];
    }
    state->tau_prev2[0] = state->tau_prev[0];
    state->tau_prev2[1] = state->tau_prev[1];
    state->tau_prev[0] = t0;
    state->tau_prev[1] = t1;
    state->sin_prev = sth;
    state->cos_prev = cth;
    state->gain = gain;
    state->s_norm = sn;
    state->u_discarded = udisc;
    state->tau[0] = t0;
    state->tau[1] = t1;
    state->steps += state->steps < 4294967295u;
    tau[0] = t0;
    tau[1] = t1;
    return st;
}

wmr_status_t HAND_NAME(tdroc_step)(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const real q[5], const real qdot[5], const real q_des[5], const real qdot_des[5],
    const real qddot_des[5], real tau[2])
{
    if (state == NULL || config == NULL || q == NULL || qdot == NULL || q_des == NULL
        || qdot_des == NULL || qddot_des == NULL || tau == NULL) {
        return WMR_ERR_NULL_POINTER;
    }
    if (state->magic != WMR_STATE_MAGIC) {
        return WMR_ERR_NOT_INITIALISED;
    }
#ifdef HAND_FROZEN
    if (config != &HAND_NAME(frozen_config)) {
        return WMR_ERR_CONFIG_CHANGED;
    }
    return step_body(state, &HAND_NAME(frozen_config), q, qdot, q_des, qdot_des, qddot_des, tau);
#else
    if (!unchanged(config, &state->config)) {
        const wmr_status_t st = check_config(config);
        return st != WMR_OK ? st : WMR_ERR_CONFIG_CHANGED;
    }
    return step_body(state, &state->config, q, qdot, q_des, qdot_des, qddot_des, tau);
#endif
}

int HAND_NAME(forward_dynamics_checked)(const real *in, real *qdd)
{
    const real m = in[0], I = in[1], K = in[2], Iw = in[3], r = in[4], b = in[5], d = in[6];
    const real th = in[9], wr = in[15], wl = in[16], tr = in[17], tl = in[18];
    real c, s, ia, rb, rb2, q, a11, a12, det, inv, g, dw, h1, h2, f1, f2, er, el, v, w, vd, wd;
    real x0, x1, y0, y1;
    if (isnan((m - m) + (I - I) + (K - K) + (Iw - Iw) + (r - r) + (b - b) + (d - d) + (th - th)
              + (wr - wr) + (wl - wl) + (tr - tr) + (tl - tl))) {
        return WMR_ERR_NONFINITE_INPUT;
    }
    ia = I - L(2.0) * K * d + m * d * d;
    rb = r / b;
    rb2 = rb * rb;
    q = L(0.25) * m * r * r;
    a11 = Iw + q + ia * rb2;
    a12 = q - ia * rb2;
    det = a11 * a11 - a12 * a12;
    if (!(r > L(0.0)) || !(b > L(0.0)) || !(a11 > L(0.0)) || !(det > L(0.0))) {
        return WMR_ERR_BAD_PARAMS;
    }
    inv = L(1.0) / det;
    c = HCOS(th);
    s = HSIN(th);
    g = r * rb2 * (K - m * d);
    dw = wl - wr;
    h1 = g * wl * dw;
    h2 = -g * wr * dw;
    f1 = tr - h1;
    f2 = tl - h2;
    er = (a11 * f1 - a12 * f2) * inv;
    el = (a11 * f2 - a12 * f1) * inv;
    v = L(0.5) * r * (wr + wl);
    w = -rb * dw;
    vd = L(0.5) * r * (er + el);
    wd = rb * (er - el);
    x0 = vd - d * w * w;  /* along the heading */
    x1 = d * wd + v * w;  /* along its normal */
    y0 = x0 * c - x1 * s;
    y1 = x0 * s + x1 * c;
    if (isnan((y0 - y0) + (y1 - y1) + (wd - wd) + (er - er) + (el - el))) {
        return WMR_ERR_NONFINITE_OUTPUT;
    }
    qdd[0] = y0;
    qdd[1] = y1;
    qdd[2] = wd;
    qdd[3] = er;
    qdd[4] = el;
    return WMR_OK;
}
#endif /* HAND_HELPERS_ONLY */
