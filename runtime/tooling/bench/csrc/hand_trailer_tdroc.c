/*
 * Hand-written TDROC step for the trailer robot, minimal formulation, double or float32
 * (-DTRAILER_FLOAT32): what a careful firmware engineer writes from the paper and a hand
 * derivation of the reduced mass matrix to be fast, under the generated step's contract.
 * Not derived from generated code; the benchmark checks it against trailer_tdroc_step
 * (statuses on bad inputs and configurations, torques over a recorded closed loop) before
 * timing it. Not used by the toolchain.
 *
 * Contract (the generated step's): NULL pointers, then a state not initialised, then the
 * configuration compared bit for bit with the copy _init kept (a differing one is validated:
 * its field's error, else CONFIG_CHANGED), then the 40 inputs (|x| <= 1e6: q, qdot ->
 * BAD_MEASUREMENT, else BAD_REFERENCE), then a non-finite result (tau, k-hat, ||s||) ->
 * NONFINITE_OUTPUT, then saturation (WARN_SATURATED); the state and tau are written only on
 * success. The controlled coordinates are the driven wheels' angles q[4] (right), q[5]
 * (left); tau = u (no B^T). One decision is not bit-identical: in float32 the nominal
 * check's "Mhat positive definite" (at psi = 0) can differ where its margin is below
 * float32's resolution (about 1e-6 of its terms: 1,115 of 10^6 random nominal sets within
 * the bounds, none in double); the benchmark's cases are far from that boundary.
 *
 * The model. With psi = theta_tractor - theta_cart the hitch angle and u = (v, w) the
 * tractor's forward speed and yaw rate, u = W phidot, W = [[rR/2, rL/2], [rR/(2 HB),
 * -rL/(2 HB)]], the reduced mass matrix in u (hand_trailer.c derives it) is
 *     Mbar_u = [[mvv, mvw], [mvw, mww]],
 * whose entries are constants plus quadratic forms in (c, s) = (cos psi, sin psi): with
 * cr = J_cr/r_cr^2, cl = J_cl/r_cl^2, jr = J_R/rR^2, jl = J_L/rL^2, e = CB/LC,
 *     alpha = cr + cl,  beta = J_c/LC^2 + e^2 alpha - 2 K1/LC,  g = e (cr - cl) + K2/LC,
 *     mvv = Jx + jr + jl          + alpha c^2 + beta s^2 + 2 g c s
 *     mww = Jth + HB^2 (jr + jl)  + A^2 (beta c^2 + alpha s^2 - 2 g c s)
 *     mvw = HB (jr - jl) + K4     + A g (s^2 - c^2) + A (alpha - beta) c s
 * (K1, K2 the cart's couplings K_theta_cart_x_tractor(_2), K4 = K_theta_tractor_x_tractor_2;
 * K_theta_tractor_x_tractor multiplies the tractor's lateral speed, 0 here: it is not in
 * Mhat). In the double angle (c^2 = (1 + C)/2, s^2 = (1 - C)/2, c s = S/2, C = cos 2psi,
 * S = sin 2psi) each is k0 + kc C + ks S, and Mhat = Mbar = W^T Mbar_u W is linear in
 * Mbar_u, so each of its entries m11, m12, m22 is m0 + mc C + ms S with nine coefficients
 * of the nominal parameters only.
 *
 * What makes it fast, everything else being the paper's arithmetic:
 * - Mhat(q) is three entries of two multiply-adds each from one sin/cos pair (of 2 psi, by
 *   libm: sincos) a step; _init keeps the nine coefficients; the step keeps its Mhat for the
 *   next step's (17), which needs Mhat(q(t-h)): no second sin/cos pair, no second Mhat;
 * - the sin/cos call comes first and the work that does not need it runs in its shadow;
 *   the law is (Mhat b + H1hat) + k-hat (Mhat s / max(||s||, eps)), so only one product
 *   waits for k-hat, and ||Mhat^-1||_F's square root runs beside 1/|det Mhat|;
 * - ||Mhat(q)^-1||_F of (25) in closed form from the same three entries;
 * - _init keeps every configuration-only quantity: P, 1/span and the (17) blend of inputs,
 *   the weights a^i and 1 / sum a^i for every window length;
 * - the window keeps its difference norms (one new norm a step), each written twice in a
 *   buffer of twice the window so the newest n are contiguous: no shift, no % ring index;
 * - the configuration check XORs the bits of runs of values (independent, vectorisable);
 *   the input check ORs the magnitude-bit compares of all 40 inputs (one branch);
 * - only the two driven wheels' history is kept (the other six coordinates are checked,
 *   never stored).
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "hand_trailer_tdroc.h"

#ifdef HAND_FROZEN
#include "trailer_tdroc_frozen.h"
const trailer_tdroc_config_t HAND_NAME(frozen_config) = TRAILER_TDROC_FROZEN_CONFIG;
#endif

typedef trailer_real_t real;
#define L(x) TRAILER_LIT(x)
#ifdef TRAILER_FLOAT32
typedef uint32_t bits_t;
#define MAG_MASK 0x7fffffffu
#define TOP_BIT 0x80000000u
#define BOUND_BITS 0x49742400u  /* 1e6f */
#define HSIN(x) sinf(x)
#define HCOS(x) cosf(x)
#define HSQRT(x) sqrtf(x)
#define HFABS(x) fabsf(x)
#define HREAL_MAX FLT_MAX
#else
typedef uint64_t bits_t;
#define MAG_MASK UINT64_C(0x7fffffffffffffff)
#define TOP_BIT UINT64_C(0x8000000000000000)
#define BOUND_BITS UINT64_C(0x412e848000000000)  /* 1e6 */
#define HSIN(x) sin(x)
#define HCOS(x) cos(x)
#define HSQRT(x) sqrt(x)
#define HFABS(x) fabs(x)
#define HREAL_MAX DBL_MAX
#endif

#include "hand_trailer_geometry.h"

#define NNOM 15     /* nominal parameters */

/* What a frozen build folds (the coefficients of the compiled-in configuration) must be
   inlined into the step, however large it is. */
#if defined(__GNUC__)
#define HAND_INLINE static inline __attribute__((always_inline))
#else
#define HAND_INLINE static inline
#endif

/* The configuration compare reads runs of reals as arrays (no padding inside a run): the
   nominal parameters; k1[8], k2[8], q_pos, q_vel, h, tau_max; rate_window, eps. */
typedef char nominal_is_a_run[sizeof(trailer_params_t) == NNOM * sizeof(real) ? 1 : -1];
typedef char gains_are_a_run[offsetof(trailer_tdroc_config_t, tau_max)
                             == offsetof(trailer_tdroc_config_t, k1) + 19 * sizeof(real)
                             ? 1 : -1];
typedef char estimator_is_a_run[offsetof(trailer_tdroc_config_t, eps)
                                == offsetof(trailer_tdroc_config_t, rate_window) + sizeof(real)
                                ? 1 : -1];

/* The bits of p[i] (p an array of reals, or any object read as one). */
static inline bits_t load_bits(const void *p, int i)
{
    bits_t b;
    memcpy(&b, (const unsigned char *)p + (size_t)i * sizeof b, sizeof b);
    return b;
}

/* sqrt(x0^2 + x1^2) that does not overflow while x0, x1 are finite. */
static inline real norm2(real x0, real x1)
{
    const real sum = x0 * x0 + x1 * x1;
    if (sum <= HREAL_MAX) {
        return HSQRT(sum);
    }
    {
        const real a0 = HFABS(x0), a1 = HFABS(x1);
        const real big = a0 > a1 ? a0 : a1;
        const real y0 = x0 / big, y1 = x1 / big;
        return big * HSQRT(y0 * y0 + y1 * y1);
    }
}

/* P of (20): A^T P + P A = -Q for A = [[0, 1], [-k1, -k2]], Q = diag(q1, q2). */
HAND_INLINE void lyap(real k1, real k2, real q1, real q2, real *p11, real *p12, real *p22)
{
    *p11 = (k1 * k1 * q2 + k1 * q1 + k2 * k2 * q1) / (L(2.0) * k1 * k2);
    *p12 = q1 / (L(2.0) * k1);
    *p22 = (k1 * q2 + q1) / (L(2.0) * k1 * k2);
}

/* Mbar_u's entries (mvv, mvw, mww), each as k[0] + k[1] c^2 + k[2] s^2 + k[3] c s with
   c = cos psi, s = sin psi (the file comment derives them). */
HAND_INLINE void mbar_u(const trailer_params_t *p, real vv[4], real vw[4], real ww[4])
{
    const real e = CB / LC;
    const real cr = p->J_theta_cart_right / (p->radius_cart_right * p->radius_cart_right);
    const real cl = p->J_theta_cart_left / (p->radius_cart_left * p->radius_cart_left);
    const real jr = p->J_theta_right / (p->radius_right * p->radius_right);
    const real jl = p->J_theta_left / (p->radius_left * p->radius_left);
    const real alpha = cr + cl;
    const real beta = p->J_theta_cart / (LC * LC) + e * e * alpha
        - L(2.0) * p->K_theta_cart_x_tractor / LC;
    const real g = e * (cr - cl) + p->K_theta_cart_x_tractor_2 / LC;
    vv[0] = p->J_x_tractor + jr + jl;
    vv[1] = alpha;
    vv[2] = beta;
    vv[3] = L(2.0) * g;
    vw[0] = HB * (jr - jl) + p->K_theta_tractor_x_tractor_2;
    vw[1] = -A * g;
    vw[2] = A * g;
    vw[3] = A * (alpha - beta);
    ww[0] = p->J_theta_tractor + HB * HB * (jr + jl);
    ww[1] = A * A * beta;
    ww[2] = A * A * alpha;
    ww[3] = -L(2.0) * A * A * g;
}

/* W^T Mbar_u W, W = [[rR/2, rL/2], [rR/(2 HB), -rL/(2 HB)]]: the wheel-rate entries (11,
   12, 22) of one term of Mbar_u (it is linear in Mbar_u). */
HAND_INLINE void to_wheels(const trailer_params_t *p, real vv, real vw, real ww, real m[3])
{
    const real rv = L(0.5) * p->radius_right, rw = p->radius_right * (L(0.5) / HB);
    const real lv = L(0.5) * p->radius_left, lw = -p->radius_left * (L(0.5) / HB);
    m[0] = rv * (rv * vv + rw * vw) + rw * (rv * vw + rw * ww);
    m[1] = lv * (rv * vv + rw * vw) + lw * (rv * vw + rw * ww);
    m[2] = lv * (lv * vv + lw * vw) + lw * (lv * vw + lw * ww);
}

/* Mhat = S^T M S in wheel rates, entries (11, 12, 22): m0 + mc cos 2psi + ms sin 2psi
   (c^2 = (1 + C)/2, s^2 = (1 - C)/2, c s = S/2): three products a step fewer than the
   quadratic form. Its rounding is that of the larger of m0, mc, ms rather than of the entry:
   for the shipped robot's nominal parameters they are of the entries' size (float32 torques
   agree with ours to about 2e-6 of the largest), but a nominal model whose cart coupling or
   inertia dwarfs the rest by several orders loses that many digits in float32. */
HAND_INLINE void mhat_coeffs(const trailer_params_t *p, real m0[3], real mc[3], real ms[3])
{
    /* straight-line (no loops): a frozen build folds it to nine constants */
    real vv[4], vw[4], ww[4], w0[3], wc2[3], ws2[3], wcs[3];
    mbar_u(p, vv, vw, ww);
    to_wheels(p, vv[0], vw[0], ww[0], w0);
    to_wheels(p, vv[1], vw[1], ww[1], wc2);
    to_wheels(p, vv[2], vw[2], ww[2], ws2);
    to_wheels(p, vv[3], vw[3], ww[3], wcs);
    m0[0] = w0[0] + L(0.5) * (wc2[0] + ws2[0]);
    m0[1] = w0[1] + L(0.5) * (wc2[1] + ws2[1]);
    m0[2] = w0[2] + L(0.5) * (wc2[2] + ws2[2]);
    mc[0] = L(0.5) * (wc2[0] - ws2[0]);
    mc[1] = L(0.5) * (wc2[1] - ws2[1]);
    mc[2] = L(0.5) * (wc2[2] - ws2[2]);
    ms[0] = L(0.5) * wcs[0];
    ms[1] = L(0.5) * wcs[1];
    ms[2] = L(0.5) * wcs[2];
}

#ifndef HAND_FROZEN
static int within(real x, real lo, real hi) { return x >= lo && x <= hi; }

/* trailer_tdroc_check_config's decisions, in its order (the first failing field's status).
   A frozen build has none: the `freeze` command validated its configuration. */
static trailer_status_t check_config(const trailer_tdroc_config_t *c)
{
    /* Each nominal parameter within a factor 1000 of the robot file's value (or of 1): the
       bounds of the generated check, the positive parameters' lower bounds positive */
    static const real lo[NNOM] = {
        L(0.0051415), L(4e-06), L(4e-06), L(7.000000000000001e-05), L(7.000000000000001e-05),
        L(0.003421094), L(0.0535), -L(8250.0), -L(1000.0), -L(3750.0), -L(1000.0),
        L(8e-05), L(8e-05), L(9.6e-05), L(9.6e-05)};
    static const real hi[NNOM] = {
        L(5141.500000000001), L(1000.0), L(1000.0), L(1000.0), L(1000.0), L(3421.094),
        L(53500.0), L(8250.0), L(1000.0), L(3750.0), L(1000.0), L(1000.0), L(1000.0),
        L(1000.0), L(1000.0)};
    const trailer_params_t *p = &c->nominal;
    const real pv[NNOM] = {
        p->J_theta_cart, p->J_theta_cart_left, p->J_theta_cart_right, p->J_theta_left,
        p->J_theta_right, p->J_theta_tractor, p->J_x_tractor, p->K_theta_cart_x_tractor,
        p->K_theta_cart_x_tractor_2, p->K_theta_tractor_x_tractor,
        p->K_theta_tractor_x_tractor_2, p->radius_cart_left, p->radius_cart_right,
        p->radius_left, p->radius_right};
    int i;
    if (c->formulation != TRAILER_FORMULATION_MINIMAL) {
        return TRAILER_ERR_BAD_FORMULATION;
    }
    if (!within(c->h, TRAILER_H_MIN, TRAILER_H_MAX)) {
        return TRAILER_ERR_BAD_SAMPLE_TIME;
    }
    for (i = 0; i < 8; ++i) {  /* every coordinate's gains, the unused ones too */
        if (!within(c->k1[i], TRAILER_GAIN_MIN, TRAILER_GAIN_MAX)
            || !within(c->k2[i], TRAILER_GAIN_MIN, TRAILER_GAIN_MAX)) {
            return TRAILER_ERR_BAD_GAINS;
        }
    }
    if (!within(c->q_pos, TRAILER_GAIN_MIN, TRAILER_GAIN_MAX)
        || !within(c->q_vel, TRAILER_GAIN_MIN, TRAILER_GAIN_MAX)) {
        return TRAILER_ERR_BAD_GAINS;
    }
    for (i = 0; i < 8; ++i) {  /* P of (20) finite (always, for gains within their bounds) */
        real a, b, d;
        lyap(c->k1[i], c->k2[i], c->q_pos, c->q_vel, &a, &b, &d);
        if (!isfinite(a) || !isfinite(b) || !isfinite(d)) {
            return TRAILER_ERR_BAD_GAINS;
        }
    }
    if (!(c->tau_max > L(0.0) && c->tau_max <= TRAILER_TORQUE_LIMIT_MAX)) {
        return TRAILER_ERR_BAD_TORQUE_LIMIT;
    }
    if (!within(c->eps, TRAILER_GAIN_MIN, TRAILER_GAIN_MAX)) {
        return TRAILER_ERR_BAD_EPS;
    }
    if (c->accel_estimator < TRAILER_ACCEL_BACKWARD || c->accel_estimator > TRAILER_ACCEL_MATCHED
        || !within(c->rate_window, L(0.0), c->h)) {
        return TRAILER_ERR_BAD_ESTIMATOR;
    }
    if ((c->hold_gain != 0 && c->hold_gain != 1)
        || !within(c->held_gain, L(0.0), TRAILER_GAIN_MAX)) {
        return TRAILER_ERR_BAD_HELD_GAIN;
    }
    if (c->n < 2 || c->n > TRAILER_MAX_WINDOW) {
        return TRAILER_ERR_BAD_WINDOW;
    }
    if (!(c->a > L(0.0) && c->a <= L(1.0))) {
        return TRAILER_ERR_BAD_DISCOUNT;
    }
    for (i = 0; i < NNOM; ++i) {  /* NaN fails both compares; lo > 0 makes J, r positive */
        if (!within(pv[i], lo[i], hi[i])) {
            return TRAILER_ERR_BAD_NOMINAL;
        }
    }
    {   /* Mhat at psi = 0 positive definite (Sylvester), and ||Mhat^-1|| of (25) finite there;
           from the quadratic form at c = 1, s = 0 (its own rounding, not the double angle's) */
        real vv[4], vw[4], ww[4], m[3], m11, m12, m22, det;
        mbar_u(p, vv, vw, ww);
        to_wheels(p, vv[0] + vv[1], vw[0] + vw[1], ww[0] + ww[1], m);
        m11 = m[0];
        m12 = m[1];
        m22 = m[2];
        det = m11 * m22 - m12 * m12;
        if (!(m11 > L(0.0)) || !(det > L(0.0))
            || !isfinite(HSQRT(m11 * m11 + L(2.0) * m12 * m12 + m22 * m22) / det)) {
            return TRAILER_ERR_BAD_NOMINAL;
        }
    }
    return TRAILER_OK;
}

/* The XOR of the bits of n consecutive reals at a and b: 0 iff all equal bit for bit. In
   blocks of four (what the compiler vectorises), then the rest. */
static inline bits_t xor_run(const unsigned char *a, const unsigned char *b, int n)
{
    bits_t d = 0u;
    int i;
    for (i = 0; i < (n & ~3); ++i) {
        d |= load_bits(a, i) ^ load_bits(b, i);
    }
    for (i = n & ~3; i < n; ++i) {
        d |= load_bits(a, i) ^ load_bits(b, i);
    }
    return d;
}

/* Bit for bit the kept configuration (padding never compared): runs of reals and the four
   ints, XOR-ed and OR-ed, one branch. */
static int unchanged(const trailer_tdroc_config_t *c, const trailer_tdroc_config_t *k)
{
    const unsigned char *cb = (const unsigned char *)c, *kb = (const unsigned char *)k;
    const size_t gains = offsetof(trailer_tdroc_config_t, k1);
    const size_t rw = offsetof(trailer_tdroc_config_t, rate_window);
    const size_t a = offsetof(trailer_tdroc_config_t, a);
    const size_t held = offsetof(trailer_tdroc_config_t, held_gain);
    const unsigned ints = (unsigned)((c->formulation ^ k->formulation)
        | (c->accel_estimator ^ k->accel_estimator) | (c->n ^ k->n)
        | (c->hold_gain ^ k->hold_gain));
    const bits_t d = xor_run(cb, kb, NNOM) | xor_run(cb + gains, kb + gains, 20)
        | xor_run(cb + rw, kb + rw, 2) | xor_run(cb + a, kb + a, 1)
        | xor_run(cb + held, kb + held, 1) | (bits_t)ints;
    return d == 0u;
}
#endif

trailer_status_t HAND_NAME(tdroc_init)(hand_tdroc_state_t *state,
    const trailer_tdroc_config_t *config)
{
    hand_tdroc_state_t s;
    real wi = L(1.0), wsum = L(0.0);
    int i;
    if (state == NULL || config == NULL) {
        return TRAILER_ERR_NULL_POINTER;
    }
#ifdef HAND_FROZEN
    if (config != &HAND_NAME(frozen_config)) {
        return TRAILER_ERR_CONFIG_CHANGED;
    }
#else
    {
        const trailer_status_t st = check_config(config);
        if (st != TRAILER_OK) {
            return st;
        }
    }
#endif
    memset(&s, 0, sizeof s);
    s.magic = TRAILER_STATE_MAGIC;
#ifndef HAND_FROZEN
    s.config = *config;
#endif
    for (i = 0; i < 2; ++i) {
        real p11;
        lyap(config->k1[4 + i], config->k2[4 + i], config->q_pos, config->q_vel, &p11,
             &s.p12[i], &s.p22[i]);
    }
    mhat_coeffs(&config->nominal, s.m0, s.mc, s.ms);
    s.central = config->accel_estimator == TRAILER_ACCEL_CENTRAL;
    s.inv_span = L(1.0) / (s.central ? L(2.0) * config->h : config->h);
    s.c2 = config->accel_estimator == TRAILER_ACCEL_MATCHED
        ? config->rate_window / (L(2.0) * config->h) : L(0.0);
    s.c1 = L(1.0) - s.c2;
    s.inv_wsum[0] = L(0.0);
    for (i = 0; i < TRAILER_MAX_WINDOW; ++i) {
        s.apow[i] = wi;
        wsum += wi;
        wi *= config->a;
        s.inv_wsum[i + 1] = L(1.0) / wsum;
    }
    *state = s;
    return TRAILER_OK;
}

/* The improved competitor (hand_*_fast.c) includes this file for what precedes: the
   helpers, the configuration check and compare, _init; its step is its own. */
#ifndef HAND_HELPERS_ONLY
/* What the step reads that depends on the configuration only. A run-time build loads it
   from the state (_init computed it); a frozen build computes it from the compiled-in
   configuration, which the compiler folds to constants. */
typedef struct {
    real m0[3], mc[3], ms[3];
    real p12[2], p22[2];
    real inv_span, c1, c2;
    int central;
} kept_t;

HAND_INLINE void kept(const hand_tdroc_state_t *st, const trailer_tdroc_config_t *cfg,
    kept_t *k)
{
#ifdef HAND_FROZEN
    real p11;
    (void)st;
    mhat_coeffs(&cfg->nominal, k->m0, k->mc, k->ms);
    lyap(cfg->k1[4], cfg->k2[4], cfg->q_pos, cfg->q_vel, &p11, &k->p12[0], &k->p22[0]);
    lyap(cfg->k1[5], cfg->k2[5], cfg->q_pos, cfg->q_vel, &p11, &k->p12[1], &k->p22[1]);
    k->central = cfg->accel_estimator == TRAILER_ACCEL_CENTRAL;
    k->inv_span = L(1.0) / (k->central ? L(2.0) * cfg->h : cfg->h);
    k->c2 = cfg->accel_estimator == TRAILER_ACCEL_MATCHED
        ? cfg->rate_window / (L(2.0) * cfg->h) : L(0.0);
    k->c1 = L(1.0) - k->c2;
#else
    (void)cfg;
    memcpy(k->m0, st->m0, sizeof k->m0);
    memcpy(k->mc, st->mc, sizeof k->mc);
    memcpy(k->ms, st->ms, sizeof k->ms);
    memcpy(k->p12, st->p12, sizeof k->p12);
    memcpy(k->p22, st->p22, sizeof k->p22);
    k->inv_span = st->inv_span;
    k->c1 = st->c1;
    k->c2 = st->c2;
    k->central = st->central;
#endif
}

/* The step after the pointer, state and configuration checks; cfg is the kept (or the
   compiled-in) configuration. Ordered for latency: the one sin/cos pair (a library call)
   first, then everything that does not need it (the errors, s and 1/max(||s||, eps), the
   TDE with the kept Mhat(q(t-h)), the window), which runs in the call's shadow; then
   Mhat(q) and the one chain det -> 1/|det| -> k-hat -> tau. */
HAND_INLINE trailer_status_t step_body(hand_tdroc_state_t *state,
    const trailer_tdroc_config_t *cfg, const real q[8], const real qdot[8], const real q_des[8],
    const real qdot_des[8], const real qddot_des[8], real tau[2])
{
    const int pushed = state->steps >= 2u;
    trailer_status_t st = TRAILER_OK;
    int count = state->omega_count, head = state->head;
    bits_t meas = 0u, ref = 0u;
    real C, S, m11, m12, m22, e0, e1, ed0, ed1, s0, s1, sn, inv_mx, n0, n1, b0, b1, H0, H1;
    real wacc = L(0.0), dnew = L(0.0), gain, t0, t1;
    kept_t k;
    int i;
    /* |x| <= 1e6 for all 40 inputs, on the magnitudes' bits: for IEEE values of one sign
       their order is that of the bits, and +Inf and every NaN lie above every finite value;
       both below 2^63 (2^31), so bound - |x| wraps, setting the top bit, exactly when |x| >
       bound. Subtractions OR-ed (vectorised), one branch. */
    for (i = 0; i < 8; ++i) {
        meas |= (BOUND_BITS - (load_bits(q, i) & MAG_MASK))
            | (BOUND_BITS - (load_bits(qdot, i) & MAG_MASK));
        ref |= (BOUND_BITS - (load_bits(q_des, i) & MAG_MASK))
            | (BOUND_BITS - (load_bits(qdot_des, i) & MAG_MASK))
            | (BOUND_BITS - (load_bits(qddot_des, i) & MAG_MASK));
    }
    if (((meas | ref) & TOP_BIT) != 0u) {
        return (meas & TOP_BIT) != 0u ? TRAILER_ERR_BAD_MEASUREMENT : TRAILER_ERR_BAD_REFERENCE;
    }
    /* the generated step's bound on the ring's head and count (issue 52): a corrupted
       state is refused before the ring is read or written */
    if (((unsigned)head >= (unsigned)TRAILER_MAX_WINDOW)
        || ((unsigned)count > (unsigned)TRAILER_MAX_WINDOW + 1u)) {
        return TRAILER_ERR_NOT_INITIALISED;
    }
    kept(state, cfg, &k);
    /* Mhat(q) from the one sin/cos pair of 2 psi (exact doubling; |2 psi| <= 4e6). */
    {
        const real psi2 = L(2.0) * (q[2] - q[3]);
        C = HCOS(psi2);
        S = HSIN(psi2);
    }
    /* (18), (24): the wheels' errors, s = B^T P e and 1/max(||s||, eps). */
    e0 = q_des[4] - q[4];
    e1 = q_des[5] - q[5];
    ed0 = qdot_des[4] - qdot[4];
    ed1 = qdot_des[5] - qdot[5];
    s0 = k.p12[0] * e0 + k.p22[0] * ed0;
    s1 = k.p12[1] * e1 + k.p22[1] * ed1;
    sn = norm2(s0, s1);
    inv_mx = L(1.0) / (sn >= cfg->eps ? sn : cfg->eps);  /* NaN: eps, as fmax */
    n0 = s0 * inv_mx;  /* s / max(||s||, eps): at most 1 in magnitude */
    n1 = s1 * inv_mx;
    /* (22)'s feedforward and PD part, u_a without the switching term */
    b0 = qddot_des[4] + cfg->k1[4] * e0 + cfg->k2[4] * ed0;
    b1 = qddot_des[5] + cfg->k1[5] * e1 + cfg->k2[5] * ed1;
    /* (17): H1hat = u(t-h) - Mhat(q(t-h)) qddot(t-h), from the third step on. */
    if (pushed) {
        const real *then = k.central ? state->qdot_prev2 : state->qdot_prev;
        const real qdd0 = (qdot[4] - then[0]) * k.inv_span;
        const real qdd1 = (qdot[5] - then[1]) * k.inv_span;
        const real *mp = state->m_prev;
        H0 = (k.c1 * state->tau_prev[0] + k.c2 * state->tau_prev2[0])
            - (mp[0] * qdd0 + mp[1] * qdd1);
        H1 = (k.c1 * state->tau_prev[1] + k.c2 * state->tau_prev2[1])
            - (mp[1] * qdd0 + mp[2] * qdd1);
        /* the window's new difference norm ||Omega(1) - Omega(2)||, and (25)'s weighted sum
           over the window after this step: the new norm, then the kept ones, contiguous
           from the old head */
        dnew = norm2(H0 - state->H1hat[0], H1 - state->H1hat[1]);
        head = head == 0 ? TRAILER_MAX_WINDOW - 1 : head - 1;
        count += count <= TRAILER_MAX_WINDOW;
        if (count >= 2) {
            const int active = count - 1 < cfg->n ? count - 1 : cfg->n;
            const real *older = &state->dn[state->head];
            wacc = dnew;
            for (i = 1; i < active; ++i) {
                wacc += state->apow[i] * older[i - 1];
            }
            wacc *= state->inv_wsum[active];
        }
    } else {
        H0 = L(0.0);
        H1 = L(0.0);
    }
    m11 = k.m0[0] + k.mc[0] * C + k.ms[0] * S;
    m12 = k.m0[1] + k.mc[1] * C + k.ms[1] * S;
    m22 = k.m0[2] + k.mc[2] * C + k.ms[2] * S;
    /* (25): k-hat = ||Mhat(q)^-1||_F sum w_i ||Omega(i) - Omega(i+1)||, capped (NaN and Inf
       as well); held, or 0 before two Omega's (count >= 2 only ever after a push). For a
       symmetric 2x2, ||M^-1||_F = sqrt(m11^2 + 2 m12^2 + m22^2) / |det M|. */
    if (cfg->hold_gain) {
        gain = cfg->held_gain;
    } else if (count >= 2) {
        /* the square root and the reciprocal of |det| run side by side */
        const real inv_det = L(1.0) / HFABS(m11 * m22 - m12 * m12);
        const real frob = HSQRT(m11 * m11 + L(2.0) * m12 * m12 + m22 * m22);
        gain = (frob * wacc) * inv_det;
        gain = gain <= TRAILER_GAIN_MAX ? gain : TRAILER_GAIN_MAX;
    } else {
        gain = L(0.0);
    }
    /* (22), (24): tau = Mhat(q) (u_a + k s / max(||s||, eps)) + H1hat, as
       (Mhat b + H1hat) + k (Mhat s / max(||s||, eps)): only the last product waits for k
       (and Mhat s / max(||s||, eps) is at most ||Mhat|| in size: it cannot overflow where
       the law as written does not). */
    t0 = (m11 * b0 + m12 * b1 + H0) + gain * (m11 * n0 + m12 * n1);
    t1 = (m12 * b0 + m22 * b1 + H1) + gain * (m12 * n0 + m22 * n1);
    if (isnan((t0 - t0) + (t1 - t1) + (sn - sn))) {  /* gain is finite: capped or held */
        return TRAILER_ERR_NONFINITE_OUTPUT;
    }
    if (t0 > cfg->tau_max) { t0 = cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    else if (t0 < -cfg->tau_max) { t0 = -cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    if (t1 > cfg->tau_max) { t1 = cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    else if (t1 < -cfg->tau_max) { t1 = -cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    /* Commit. */
    if (pushed) {
        state->dn[head] = dnew;
        state->dn[head + TRAILER_MAX_WINDOW] = dnew;
    }
    state->head = head;
    state->omega_count = count;
    state->H1hat[0] = H0;
    state->H1hat[1] = H1;
    state->qdot_prev2[0] = state->qdot_prev[0];
    state->qdot_prev2[1] = state->qdot_prev[1];
    state->qdot_prev[0] = qdot[4];
    state->qdot_prev[1] = qdot[5];
    state->tau_prev2[0] = state->tau_prev[0];
    state->tau_prev2[1] = state->tau_prev[1];
    state->tau_prev[0] = t0;
    state->tau_prev[1] = t1;
    state->m_prev[0] = m11;
    state->m_prev[1] = m12;
    state->m_prev[2] = m22;
    state->gain = gain;
    state->s_norm = sn;
    state->tau[0] = t0;
    state->tau[1] = t1;
    state->steps += state->steps < TRAILER_STEPS_MAX;
    tau[0] = t0;
    tau[1] = t1;
    return st;
}

trailer_status_t HAND_NAME(tdroc_step)(hand_tdroc_state_t *state,
    const trailer_tdroc_config_t *config, const real q[8], const real qdot[8],
    const real q_des[8], const real qdot_des[8], const real qddot_des[8], real tau[2])
{
    if (state == NULL || config == NULL || q == NULL || qdot == NULL || q_des == NULL
        || qdot_des == NULL || qddot_des == NULL || tau == NULL) {
        return TRAILER_ERR_NULL_POINTER;
    }
    if (state->magic != TRAILER_STATE_MAGIC) {
        return TRAILER_ERR_NOT_INITIALISED;
    }
#ifdef HAND_FROZEN
    if (config != &HAND_NAME(frozen_config)) {
        return TRAILER_ERR_CONFIG_CHANGED;
    }
    return step_body(state, &HAND_NAME(frozen_config), q, qdot, q_des, qdot_des, qddot_des, tau);
#else
    if (!unchanged(config, &state->config)) {
        const trailer_status_t st = check_config(config);
        return st != TRAILER_OK ? st : TRAILER_ERR_CONFIG_CHANGED;
    }
    return step_body(state, &state->config, q, qdot, q_des, qdot_des, qddot_des, tau);
#endif
}
#endif /* HAND_HELPERS_ONLY */
