/*
 * The improved hand-written TDROC step for the trailer (issue 52), minimal formulation,
 * double or float32: the old competitor (hand_trailer_tdroc.c, included for its helpers,
 * configuration check and _init with HAND_HELPERS_ONLY) with what was left of its per-step
 * overhead removed. Same state, same contract and order of statuses, same arithmetic;
 * built with -DHAND_FAST its functions are handfast_* (handfastfz_* with -DHAND_FROZEN).
 * The benchmark checks it against trailer_tdroc_step like the old one before timing it.
 * Not used by the toolchain.
 *
 * What changes against the old one:
 * - the kept constants (M-hat's nine coefficients, P, 1/span, the (17) blend) are read in
 *   place from the state, not copied into a local struct each step (a frozen build folds
 *   them from the compiled-in configuration);
 * - the configuration compare: float32 has no padding, so the whole struct is 43 words
 *   XOR-ed and OR-ed in one loop (memcmp's work without its early exit); double keeps the
 *   runs of reals and the four ints, one branch either way;
 * - the norms written out (the scaled form only past REAL_MAX, out of line and cold).
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#define HAND_HELPERS_ONLY
#include "hand_trailer_tdroc.c"

#if defined(__GNUC__)
#define FAST_COLD static __attribute__((noinline, cold))
#else
#define FAST_COLD static
#endif

FAST_COLD real norm2_scaled(real x0, real x1)
{
    const real a0 = HFABS(x0), a1 = HFABS(x1);
    const real big = a0 > a1 ? a0 : a1;
    const real y0 = x0 / big, y1 = x1 / big;
    return big * HSQRT(y0 * y0 + y1 * y1);
}

HAND_INLINE real norm2_fast(real x0, real x1)
{
    const real sum = x0 * x0 + x1 * x1;
    return sum <= HREAL_MAX ? HSQRT(sum) : norm2_scaled(x0, x1);
}

#ifndef HAND_FROZEN
/* Bit for bit the kept configuration, padding never compared: one branch. */
HAND_INLINE int same_config(const trailer_tdroc_config_t *c, const trailer_tdroc_config_t *k)
{
    const unsigned char *a = (const unsigned char *)c, *b = (const unsigned char *)k;
    if (sizeof(trailer_tdroc_config_t) == 43u * sizeof(bits_t) && sizeof(int) == sizeof(bits_t)) {
        return xor_run(a, b, 43) == 0u;  /* float32: 43 words, no padding */
    }
    return unchanged(c, k);  /* double: the runs of reals and the ints */
}
#endif

#ifdef HAND_FROZEN
#define FCFG (HAND_NAME(frozen_config))
#define K_CENTRAL (FCFG.accel_estimator == TRAILER_ACCEL_CENTRAL)
#define K_INV_SPAN (L(1.0) / (K_CENTRAL ? L(2.0) * FCFG.h : FCFG.h))
#define K_C2 (FCFG.accel_estimator == TRAILER_ACCEL_MATCHED \
              ? FCFG.rate_window / (L(2.0) * FCFG.h) : L(0.0))
#define K_C1 (L(1.0) - K_C2)
#define K_P12(i) (FCFG.q_pos / (L(2.0) * FCFG.k1[4 + (i)]))
#define K_P22(i) ((FCFG.k1[4 + (i)] * FCFG.q_vel + FCFG.q_pos) \
                  / (L(2.0) * FCFG.k1[4 + (i)] * FCFG.k2[4 + (i)]))
#define K_M0(i) (m0[i])
#define K_MC(i) (mc[i])
#define K_MS(i) (ms[i])
#else
#define K_CENTRAL (state->central)
#define K_INV_SPAN (state->inv_span)
#define K_C1 (state->c1)
#define K_C2 (state->c2)
#define K_P12(i) (state->p12[i])
#define K_P22(i) (state->p22[i])
#define K_M0(i) (state->m0[i])
#define K_MC(i) (state->mc[i])
#define K_MS(i) (state->ms[i])
#endif

trailer_status_t HAND_NAME(tdroc_step)(hand_tdroc_state_t *state,
    const trailer_tdroc_config_t *config, const real q[8], const real qdot[8],
    const real q_des[8], const real qdot_des[8], const real qddot_des[8], real tau[2])
{
    const trailer_tdroc_config_t *cfg;
    trailer_status_t st = TRAILER_OK;
    int pushed, count, head;
    bits_t meas = 0u, ref = 0u;
    real C, S, m11, m12, m22, e0, e1, ed0, ed1, s0, s1, sn, inv_mx, n0, n1, b0, b1, H0, H1;
    real wacc = L(0.0), dnew = L(0.0), gain, t0, t1;
    int i;
#ifdef HAND_FROZEN
    real m0[3], mc[3], ms[3];  /* of the compiled-in configuration: folded to constants */
#endif
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
    cfg = &HAND_NAME(frozen_config);
    mhat_coeffs(&cfg->nominal, m0, mc, ms);
#else
    if (!same_config(config, &state->config)) {
        const trailer_status_t bad = check_config(config);
        return bad != TRAILER_OK ? bad : TRAILER_ERR_CONFIG_CHANGED;
    }
    cfg = &state->config;
#endif
    /* |x| <= 1e6 for all 40 inputs on the magnitudes' bits (hand_trailer_tdroc.c) */
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
    pushed = state->steps >= 2u;
    count = state->omega_count;
    head = state->head;
    if (((unsigned)head >= (unsigned)TRAILER_MAX_WINDOW)
        || ((unsigned)count > (unsigned)TRAILER_MAX_WINDOW + 1u)) {
        return TRAILER_ERR_NOT_INITIALISED;
    }
    {   /* one sin/cos pair of 2 psi, first: the rest runs in its shadow */
        const real psi2 = L(2.0) * (q[2] - q[3]);
        C = HCOS(psi2);
        S = HSIN(psi2);
    }
    e0 = q_des[4] - q[4];
    e1 = q_des[5] - q[5];
    ed0 = qdot_des[4] - qdot[4];
    ed1 = qdot_des[5] - qdot[5];
    s0 = K_P12(0) * e0 + K_P22(0) * ed0;
    s1 = K_P12(1) * e1 + K_P22(1) * ed1;
    sn = norm2_fast(s0, s1);
    inv_mx = L(1.0) / (sn >= cfg->eps ? sn : cfg->eps);
    n0 = s0 * inv_mx;
    n1 = s1 * inv_mx;
    b0 = qddot_des[4] + cfg->k1[4] * e0 + cfg->k2[4] * ed0;
    b1 = qddot_des[5] + cfg->k1[5] * e1 + cfg->k2[5] * ed1;
    if (pushed) {
        const real *then = K_CENTRAL ? state->qdot_prev2 : state->qdot_prev;
        const real qdd0 = (qdot[4] - then[0]) * K_INV_SPAN;
        const real qdd1 = (qdot[5] - then[1]) * K_INV_SPAN;
        const real *mp = state->m_prev;
        H0 = (K_C1 * state->tau_prev[0] + K_C2 * state->tau_prev2[0])
            - (mp[0] * qdd0 + mp[1] * qdd1);
        H1 = (K_C1 * state->tau_prev[1] + K_C2 * state->tau_prev2[1])
            - (mp[1] * qdd0 + mp[2] * qdd1);
        dnew = norm2_fast(H0 - state->H1hat[0], H1 - state->H1hat[1]);
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
    m11 = K_M0(0) + K_MC(0) * C + K_MS(0) * S;
    m12 = K_M0(1) + K_MC(1) * C + K_MS(1) * S;
    m22 = K_M0(2) + K_MC(2) * C + K_MS(2) * S;
    if (cfg->hold_gain) {
        gain = cfg->held_gain;
    } else if (count >= 2) {
        const real inv_det = L(1.0) / HFABS(m11 * m22 - m12 * m12);
        const real frob = HSQRT(m11 * m11 + L(2.0) * m12 * m12 + m22 * m22);
        gain = (frob * wacc) * inv_det;
        gain = gain <= TRAILER_GAIN_MAX ? gain : TRAILER_GAIN_MAX;
    } else {
        gain = L(0.0);
    }
    t0 = (m11 * b0 + m12 * b1 + H0) + gain * (m11 * n0 + m12 * n1);
    t1 = (m12 * b0 + m22 * b1 + H1) + gain * (m12 * n0 + m22 * n1);
    if (isnan((t0 - t0) + (t1 - t1) + (sn - sn))) {
        return TRAILER_ERR_NONFINITE_OUTPUT;
    }
    if (t0 > cfg->tau_max) { t0 = cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    else if (t0 < -cfg->tau_max) { t0 = -cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    if (t1 > cfg->tau_max) { t1 = cfg->tau_max; st = TRAILER_WARN_SATURATED; }
    else if (t1 < -cfg->tau_max) { t1 = -cfg->tau_max; st = TRAILER_WARN_SATURATED; }
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
