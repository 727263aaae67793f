/*
 * The improved hand-written TDROC step for Drishti (issue 52): the competitor a careful
 * firmware engineer writes when the old one (hand_tdroc.c) is too slow. Same state, same
 * configuration check and _init (hand_tdroc.c, included for them with HAND_HELPERS_ONLY),
 * same contract and order of statuses, same arithmetic; built with -DHAND_FAST its
 * functions are handfast_* (handfastfz_* with -DHAND_FROZEN). The benchmark checks it
 * against wmr_tdroc_step like the old one before timing it. Not used by the toolchain.
 *
 * What the old one did slowly, and what this one does instead:
 * - norm_n called out of line three times, mt_mul twice: here every norm is written out
 *   (sqrt of the sum, the scaled form only past REAL_MAX, out of line and cold), and
 *   M-tilde(theta) x of (14) is inlined at both uses;
 * - both formulations in one body with loops of 5 or 2 chosen at run time: here one body
 *   per formulation, straight-line (the step branches once on the kept formulation; a
 *   frozen build on a constant);
 * - the kept constants copied into a local struct every step: here read in place from the
 *   state (run time) or folded from the compiled-in configuration (frozen);
 * - the configuration compared with branches on its int fields: here float32 (no padding)
 *   by memcmp of the whole struct, double (padded after each int) by the XOR of every
 *   value's bits, ints included, OR-ed straight-line: one branch (measured: memcmp of the
 *   double's runs of reals, or a loop over them, take more instructions);
 * - and one thing the old one shares with the generated step before issue 52: the input
 *   check's loop over all five entries, which gcc -O2 leaves scalar; here four entries in a
 *   loop it vectorises, then the fifth.
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#define HAND_HELPERS_ONLY
#include "hand_tdroc.c"

#if defined(__GNUC__)
#define FAST_INLINE static inline __attribute__((always_inline))
#define FAST_COLD static __attribute__((noinline, cold))
#else
#define FAST_INLINE static inline
#define FAST_COLD static
#endif

/* The scaled norm, past REAL_MAX only (finite x_i whose squares overflow). */
FAST_COLD real norm_scaled(const real *x, int n)
{
    return norm_n(x, n, HREAL_MAX * L(2.0));
}

FAST_INLINE real norm_fast(const real *x, int n, real sum)
{
    return sum <= HREAL_MAX ? HSQRT(sum) : norm_scaled(x, n);
}

#ifndef HAND_FROZEN
/* Bit for bit the kept configuration, padding never compared. */
FAST_INLINE int same_config(const wmr_tdroc_config_t *c, const wmr_tdroc_config_t *k)
{
    if (sizeof(wmr_tdroc_config_t) == 29u * sizeof(bits_t) && sizeof(int) == sizeof(bits_t)) {
        return memcmp(c, k, sizeof *c) == 0;  /* float32: 29 words, no padding */
    }
    {   /* double (padded after each int): every value's bits XOR-ed, OR-ed, straight-line
           (measured: fewer instructions than memcmp of the runs or a loop over them) */
        bits_t d = (bits_t)(unsigned)((c->formulation ^ k->formulation)
                                      | (c->accel_estimator ^ k->accel_estimator)
                                      | (c->n ^ k->n) | (c->hold_gain ^ k->hold_gain));
        d |= (bits(c->k1[0]) ^ bits(k->k1[0])) | (bits(c->k1[1]) ^ bits(k->k1[1]))
            | (bits(c->k1[2]) ^ bits(k->k1[2])) | (bits(c->k1[3]) ^ bits(k->k1[3]))
            | (bits(c->k1[4]) ^ bits(k->k1[4])) | (bits(c->k2[0]) ^ bits(k->k2[0]))
            | (bits(c->k2[1]) ^ bits(k->k2[1])) | (bits(c->k2[2]) ^ bits(k->k2[2]))
            | (bits(c->k2[3]) ^ bits(k->k2[3])) | (bits(c->k2[4]) ^ bits(k->k2[4]));
        d |= (bits(c->nominal.m) ^ bits(k->nominal.m)) | (bits(c->nominal.Iz) ^ bits(k->nominal.Iz))
            | (bits(c->nominal.K) ^ bits(k->nominal.K)) | (bits(c->nominal.Iw) ^ bits(k->nominal.Iw))
            | (bits(c->nominal.r) ^ bits(k->nominal.r)) | (bits(c->nominal.b) ^ bits(k->nominal.b))
            | (bits(c->nominal.d) ^ bits(k->nominal.d));
        d |= (bits(c->q_pos) ^ bits(k->q_pos)) | (bits(c->q_vel) ^ bits(k->q_vel))
            | (bits(c->h) ^ bits(k->h)) | (bits(c->tau_max) ^ bits(k->tau_max))
            | (bits(c->rate_window) ^ bits(k->rate_window)) | (bits(c->eps) ^ bits(k->eps))
            | (bits(c->a) ^ bits(k->a)) | (bits(c->held_gain) ^ bits(k->held_gain));
        return d == 0u;
    }
}
#endif

/* The configuration-only values the step reads: in place from the state (run time), or
   from the compiled-in configuration, which the compiler folds (frozen). */
#ifdef HAND_FROZEN
#define NOM (HAND_NAME(frozen_config).nominal)
#define K_M (NOM.m)
#define K_K (NOM.K)
#define K_IZ (NOM.Iz)
#define K_IW (NOM.Iw)
#define K_CA ((NOM.m * NOM.d - NOM.K) * NOM.r / NOM.b)
#define K_CB (L(0.5) * NOM.m * NOM.r)
#define K_K5 (NOM.r * (NOM.Iz - NOM.K * NOM.d) / NOM.b)
#define K_IA (NOM.Iz - L(2.0) * NOM.K * NOM.d + NOM.m * NOM.d * NOM.d)
#define K_Q (L(0.25) * NOM.m * NOM.r * NOM.r)
#define K_RB2 (NOM.r * NOM.r / (NOM.b * NOM.b))
#define K_A11 (NOM.Iw + K_Q + K_IA * K_RB2)
#define K_A12 (K_Q - K_IA * K_RB2)
#define FCFG (HAND_NAME(frozen_config))
#define K_CENTRAL (FCFG.accel_estimator == WMR_ACCEL_CENTRAL)
#define K_INV_SPAN (L(1.0) / (K_CENTRAL ? L(2.0) * FCFG.h : FCFG.h))
#define K_C2 (FCFG.accel_estimator == WMR_ACCEL_MATCHED \
              ? FCFG.rate_window / (L(2.0) * FCFG.h) : L(0.0))
#define K_C1 (L(1.0) - K_C2)
#define K_P12(i) (FCFG.q_pos / (L(2.0) * FCFG.k1[i]))
#define K_P22(i) ((FCFG.k1[i] * FCFG.q_vel + FCFG.q_pos) / (L(2.0) * FCFG.k1[i] * FCFG.k2[i]))
#else
#define K_M (st->m)
#define K_K (st->K)
#define K_IZ (st->Iz)
#define K_IW (st->Iw)
#define K_CA (st->ca)
#define K_CB (st->cb)
#define K_K5 (st->k5)
#define K_A11 (st->a11)
#define K_A12 (st->a12)
#define K_CENTRAL (st->central)
#define K_INV_SPAN (st->inv_span)
#define K_C1 (st->c1)
#define K_C2 (st->c2)
#define K_P12(i) (st->p12[i])
#define K_P22(i) (st->p22[i])
#endif

/* y = M-tilde(theta) x of (14), written out (hand_tdroc.c's mt_mul, inlined). */
#define MT_MUL(s, co, x, y) do { \
        const real sx_ = (x)[3] + (x)[4], dx_ = (x)[3] - (x)[4]; \
        const real a_ = (s) * (x)[0] - (co) * (x)[1], b_ = (co) * (x)[0] + (s) * (x)[1]; \
        const real t_ = K_K * (x)[2] + K_CA * dx_, u_ = K_CB * sx_; \
        const real ka_ = K_CA * a_, kb_ = K_CB * b_, k5x_ = K_K5 * (x)[2]; \
        (y)[0] = K_M * (x)[0] + (s) * t_ - (co) * u_; \
        (y)[1] = K_M * (x)[1] - (co) * t_ - (s) * u_; \
        (y)[2] = K_K * a_ + K_IZ * (x)[2] - K_K5 * dx_; \
        (y)[3] = kb_ - ka_ + k5x_ + K_IW * (x)[3]; \
        (y)[4] = kb_ + ka_ - k5x_ + K_IW * (x)[4]; \
    } while (0)

/* (25) over the window after this step: the new norm, then the kept ones (contiguous from
   the old head), weighted by a^i and scaled once; held, or 0 before two Omega's. */
FAST_INLINE real window_gain(const hand_tdroc_state_t *st, const wmr_tdroc_config_t *cfg,
    int pushed, int count, real dnew)
{
    real gain;
    int i;
    if (cfg->hold_gain) {
        return cfg->held_gain;
    }
    if (count < 2) {
        return L(0.0);
    }
    {
        const int active = count - 1 < cfg->n ? count - 1 : cfg->n;
        const real *older = &st->dn[st->head];
        real acc;
        if (pushed) {
            acc = dnew;
            for (i = 1; i < active; ++i) {
                acc += st->apow[i] * older[i - 1];
            }
        } else {
            acc = L(0.0);
            for (i = 0; i < active; ++i) {
                acc += st->apow[i] * older[i];
            }
        }
        gain = st->scale[active] * acc;
    }
    return gain <= WMR_GAIN_MAX ? gain : WMR_GAIN_MAX;
}

/* Saturation and commit, shared by both formulations (the state written on success only). */
FAST_INLINE wmr_status_t commit(hand_tdroc_state_t *st, const wmr_tdroc_config_t *cfg,
    int pushed, int head, int count, real dnew, const real H1[5], const real qdot[5],
    real sth, real cth, real gain, real sn, real udisc, real t0, real t1, real tau[2])
{
    wmr_status_t status = WMR_OK;
    const real tm = cfg->tau_max;
    if (t0 > tm) { t0 = tm; status = WMR_WARN_SATURATED; }
    else if (t0 < -tm) { t0 = -tm; status = WMR_WARN_SATURATED; }
    if (t1 > tm) { t1 = tm; status = WMR_WARN_SATURATED; }
    else if (t1 < -tm) { t1 = -tm; status = WMR_WARN_SATURATED; }
    if (pushed) {
        st->dn[head] = dnew;
        st->dn[head + WMR_MAX_WINDOW] = dnew;
    }
    st->head = head;
    st->omega_count = count;
    st->H1hat[0] = H1[0];
    st->H1hat[1] = H1[1];
    st->H1hat[2] = H1[2];
    st->H1hat[3] = H1[3];
    st->H1hat[4] = H1[4];
    memcpy(st->qdot_prev2, st->qdot_prev, sizeof st->qdot_prev);
    memcpy(st->qdot_prev, qdot, sizeof st->qdot_prev);
    st->tau_prev2[0] = st->tau_prev[0];
    st->tau_prev2[1] = st->tau_prev[1];
    st->tau_prev[0] = t0;
    st->tau_prev[1] = t1;
    st->sin_prev = sth;
    st->cos_prev = cth;
    st->gain = gain;
    st->s_norm = sn;
    st->u_discarded = udisc;
    st->tau[0] = t0;
    st->tau[1] = t1;
    st->steps += st->steps < 4294967295u;
    tau[0] = t0;
    tau[1] = t1;
    return status;
}

/* The paper formulation (five controlled rows), straight-line. */
FAST_INLINE wmr_status_t step_paper(hand_tdroc_state_t *st, const wmr_tdroc_config_t *cfg,
    const real q[5], const real qdot[5], const real q_des[5], const real qdot_des[5],
    const real qddot_des[5], real tau[2])
{
    const int pushed = st->steps >= 2u;
    int count = st->omega_count, head = st->head;
    real H1[5], e[5], ed[5], s[5], ua[5], u[5];
    real dnew = L(0.0), gain, sn2, sn, ks, udisc;
    const real sth = HSIN(q[2]), cth = HCOS(q[2]);  /* first: the rest runs in its shadow */
    int i;
    if (pushed) {
        const real *then = K_CENTRAL ? st->qdot_prev2 : st->qdot_prev;
        const real isp = K_INV_SPAN;
        real qdd[5], mq[5], dd[5];
        for (i = 0; i < 5; ++i) {
            qdd[i] = (qdot[i] - then[i]) * isp;
        }
        MT_MUL(st->sin_prev, st->cos_prev, qdd, mq);
        H1[0] = -mq[0];
        H1[1] = -mq[1];
        H1[2] = -mq[2];
        H1[3] = (K_C1 * st->tau_prev[0] + K_C2 * st->tau_prev2[0]) - mq[3];
        H1[4] = (K_C1 * st->tau_prev[1] + K_C2 * st->tau_prev2[1]) - mq[4];
        for (i = 0; i < 5; ++i) {
            dd[i] = H1[i] - st->H1hat[i];
        }
        dnew = norm_fast(dd, 5, dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2] + dd[3] * dd[3]
                         + dd[4] * dd[4]);
        head = head == 0 ? WMR_MAX_WINDOW - 1 : head - 1;
        count += count <= WMR_MAX_WINDOW;
    } else {
        H1[0] = H1[1] = H1[2] = H1[3] = H1[4] = L(0.0);
    }
    gain = window_gain(st, cfg, pushed, count, dnew);
    for (i = 0; i < 5; ++i) {
        e[i] = q_des[i] - q[i];
        ed[i] = qdot_des[i] - qdot[i];
        s[i] = K_P12(i) * e[i] + K_P22(i) * ed[i];
    }
    sn2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3] + s[4] * s[4];
    sn = norm_fast(s, 5, sn2);
    ks = gain / (sn >= cfg->eps ? sn : cfg->eps);
    for (i = 0; i < 5; ++i) {
        ua[i] = qddot_des[i] + cfg->k1[i] * e[i] + cfg->k2[i] * ed[i] + ks * s[i];
    }
    MT_MUL(sth, cth, ua, u);
    for (i = 0; i < 5; ++i) {
        u[i] += H1[i];
    }
    udisc = norm_fast(u, 3, u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (isnan((u[3] - u[3]) + (u[4] - u[4]) + (gain - gain) + (sn - sn) + (udisc - udisc))) {
        return WMR_ERR_NONFINITE_OUTPUT;
    }
    return commit(st, cfg, pushed, head, count, dnew, H1, qdot, sth, cth, gain, sn, udisc,
                  u[3], u[4], tau);
}

/* The minimal formulation (the two wheels: rows 3, 4), straight-line. */
FAST_INLINE wmr_status_t step_minimal(hand_tdroc_state_t *st, const wmr_tdroc_config_t *cfg,
    const real q[5], const real qdot[5], const real q_des[5], const real qdot_des[5],
    const real qddot_des[5], real tau[2])
{
    const int pushed = st->steps >= 2u;
    int count = st->omega_count, head = st->head;
    const real a11 = K_A11, a12 = K_A12;
    real H1[5] = {L(0.0), L(0.0), L(0.0), L(0.0), L(0.0)};
    real dnew = L(0.0), gain, e0, e1, ed0, ed1, s0, s1, sn, ks, ua0, ua1, t0, t1;
    if (pushed) {
        const real *then = K_CENTRAL ? st->qdot_prev2 : st->qdot_prev;
        const real qdd0 = (qdot[3] - then[3]) * K_INV_SPAN;
        const real qdd1 = (qdot[4] - then[4]) * K_INV_SPAN;
        real dd[2];
        H1[0] = (K_C1 * st->tau_prev[0] + K_C2 * st->tau_prev2[0]) - (a11 * qdd0 + a12 * qdd1);
        H1[1] = (K_C1 * st->tau_prev[1] + K_C2 * st->tau_prev2[1]) - (a12 * qdd0 + a11 * qdd1);
        dd[0] = H1[0] - st->H1hat[0];
        dd[1] = H1[1] - st->H1hat[1];
        dnew = norm_fast(dd, 2, dd[0] * dd[0] + dd[1] * dd[1]);
        head = head == 0 ? WMR_MAX_WINDOW - 1 : head - 1;
        count += count <= WMR_MAX_WINDOW;
    }
    gain = window_gain(st, cfg, pushed, count, dnew);
    e0 = q_des[3] - q[3];
    e1 = q_des[4] - q[4];
    ed0 = qdot_des[3] - qdot[3];
    ed1 = qdot_des[4] - qdot[4];
    s0 = K_P12(3) * e0 + K_P22(3) * ed0;
    s1 = K_P12(4) * e1 + K_P22(4) * ed1;
    {
        const real sv[2] = {s0, s1};
        sn = norm_fast(sv, 2, s0 * s0 + s1 * s1);
    }
    ks = gain / (sn >= cfg->eps ? sn : cfg->eps);
    ua0 = qddot_des[3] + cfg->k1[3] * e0 + cfg->k2[3] * ed0 + ks * s0;
    ua1 = qddot_des[4] + cfg->k1[4] * e1 + cfg->k2[4] * ed1 + ks * s1;
    t0 = a11 * ua0 + a12 * ua1 + H1[0];
    t1 = a12 * ua0 + a11 * ua1 + H1[1];
    if (isnan((t0 - t0) + (t1 - t1) + (gain - gain) + (sn - sn))) {
        return WMR_ERR_NONFINITE_OUTPUT;
    }
    return commit(st, cfg, pushed, head, count, dnew, H1, qdot, L(0.0), L(0.0), gain, sn,
                  L(0.0), t0, t1, tau);
}

wmr_status_t HAND_NAME(tdroc_step)(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const real q[5], const real qdot[5], const real q_des[5], const real qdot_des[5],
    const real qddot_des[5], real tau[2])
{
    const bits_t bound = bits(L(1.0e6));
    const wmr_tdroc_config_t *cfg;
    bits_t meas = 0u, ref = 0u;
    int i;
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
    cfg = &HAND_NAME(frozen_config);
#else
    if (!same_config(config, &state->config)) {
        const wmr_status_t st = check_config(config);
        return st != WMR_OK ? st : WMR_ERR_CONFIG_CHANGED;
    }
    cfg = &state->config;
#endif
    /* |x| <= 1e6 on the magnitudes' bits: bound - |x| wraps (the top bit) iff |x| > bound
       (NaN and Inf included); OR-ed, one branch. Four entries of each input in a loop gcc -O2
       vectorises (no scalar rest), then the fifth. */
    for (i = 0; i < 4; ++i) {
        meas |= (bound - (bits(q[i]) & MAG_MASK)) | (bound - (bits(qdot[i]) & MAG_MASK));
        ref |= (bound - (bits(q_des[i]) & MAG_MASK)) | (bound - (bits(qdot_des[i]) & MAG_MASK))
            | (bound - (bits(qddot_des[i]) & MAG_MASK));
    }
    for (i = 4; i < 5; ++i) {
        meas |= (bound - (bits(q[i]) & MAG_MASK)) | (bound - (bits(qdot[i]) & MAG_MASK));
        ref |= (bound - (bits(q_des[i]) & MAG_MASK)) | (bound - (bits(qdot_des[i]) & MAG_MASK))
            | (bound - (bits(qddot_des[i]) & MAG_MASK));
    }
    if (((meas | ref) & ~MAG_MASK) != 0u) {
        return (meas & ~MAG_MASK) != 0u ? WMR_ERR_BAD_MEASUREMENT : WMR_ERR_BAD_REFERENCE;
    }
    /* the ring's head and count bounded at their use (issue 52) */
    if (((unsigned)state->head >= (unsigned)WMR_MAX_WINDOW)
        || ((unsigned)state->omega_count > (unsigned)WMR_MAX_WINDOW + 1u)) {
        return WMR_ERR_NOT_INITIALISED;
    }
#ifdef HAND_FROZEN
    if (cfg->formulation == WMR_FORMULATION_PAPER) {  /* a constant: one body compiled */
#else
    if (state->paper) {
#endif
        return step_paper(state, cfg, q, qdot, q_des, qdot_des, qddot_des, tau);
    }
    return step_minimal(state, cfg, q, qdot, q_des, qdot_des, qddot_des, tau);
}
