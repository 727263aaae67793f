/*
 * A hand-written TDROC step for Drishti (paper and minimal formulations; double, or float32
 * with -DWMR_FLOAT32), the benchmark's competitor for the generated wmr_tdroc_step: the same
 * configuration struct and the same contract (statuses and their order, the configuration
 * compared bit for bit with the copy _init kept, commit on success), written to be fast by
 * hand. Built with -DHAND_FROZEN (and the `wmr freeze` header on the include path) its
 * functions are named handfz_* and take the compiled-in configuration only, as a frozen
 * generated build does. Not used by the toolchain.
 */
#ifndef HAND_TDROC_H
#define HAND_TDROC_H

#include <stdint.h>

#include "wmr_tdroc.h"

/* -DHAND_FAST: the improved competitor (the same state; handfast_* / handfastfz_*) */
#if defined(HAND_FAST) && defined(HAND_FROZEN)
#define HAND_NAME(x) handfastfz_##x
#elif defined(HAND_FAST)
#define HAND_NAME(x) handfast_##x
#elif defined(HAND_FROZEN)
#define HAND_NAME(x) handfz_##x
#else
#define HAND_NAME(x) hand_##x
#endif

typedef struct {
    long magic;
    uint32_t steps;
    int paper;                      /* formulation: 1 paper, 0 minimal */
#ifndef HAND_FROZEN
    wmr_tdroc_config_t config;      /* the configuration _init validated, compared each step */
#endif
    wmr_real_t p12[5], p22[5];      /* P of (20) */
    /* Mhat kept: paper M-tilde(theta) of (14) as m, K, Iz, Iw and three coefficients; minimal
       S^T M S = [[a11, a12], [a12, a11]] (constant for Drishti) */
    wmr_real_t m, K, Iz, Iw, ca, cb, k5, a11, a12;
    /* (17) kept: 1/span, the blend of u(t-h) and u(t-2h) */
    wmr_real_t inv_span, c1, c2;
    int central;
    /* (25) kept: a^i, and ||Mhat^-1|| / sum_{i<active} a^i per active window length */
    wmr_real_t apow[WMR_MAX_WINDOW];
    wmr_real_t scale[WMR_MAX_WINDOW + 1];
    /* the window's difference norms, newest first from dn[head]: each written twice (head
       and head + WMR_MAX_WINDOW) so the window is contiguous without % or a shift */
    wmr_real_t dn[2 * WMR_MAX_WINDOW];
    int head;
    int omega_count;
    wmr_real_t qdot_prev[5], qdot_prev2[5];
    wmr_real_t tau_prev[2], tau_prev2[2];
    wmr_real_t sin_prev, cos_prev;  /* of theta(t-h): one sin/cos pair per step */
    wmr_real_t H1hat[5];
    wmr_real_t gain, s_norm, u_discarded;
    wmr_real_t tau[2];
} hand_tdroc_state_t;

wmr_status_t HAND_NAME(tdroc_init)(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config);

wmr_status_t HAND_NAME(tdroc_step)(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const wmr_real_t q[5], const wmr_real_t qdot[5], const wmr_real_t q_des[5],
    const wmr_real_t qdot_des[5], const wmr_real_t qddot_des[5], wmr_real_t tau[2]);

#ifdef HAND_FROZEN
extern const wmr_tdroc_config_t HAND_NAME(frozen_config);
#endif

/* wmr_forward_dynamics by hand, with the same checks and status codes (in = params, q,
   qdot, tau; out = qddot); returns the status. */
int HAND_NAME(forward_dynamics_checked)(const wmr_real_t *in, wmr_real_t *qdd);

#endif /* HAND_TDROC_H */
