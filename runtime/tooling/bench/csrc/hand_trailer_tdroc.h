/*
 * A hand-written TDROC step for the shipped trailer robot (a differential-drive tractor
 * towing a two-wheeled cart on a revolute hitch; minimal formulation, the only one
 * generated for it; double, or float32 with -DTRAILER_FLOAT32), the benchmark's competitor
 * for the generated trailer_tdroc_step: the same configuration struct and the same
 * contract (statuses and their order, the configuration compared bit for bit with the copy
 * _init kept, commit on success), written to be fast by hand. Built with -DHAND_FROZEN (and
 * the `wmr freeze` header trailer_tdroc_frozen.h on the include path) its functions are
 * named handfz_* and take the compiled-in configuration only, as a frozen generated build
 * does. The names are those of hand_tdroc.h (Drishti's), so one harness serves both robots.
 * Not used by the toolchain.
 */
#ifndef HAND_TRAILER_TDROC_H
#define HAND_TRAILER_TDROC_H

#include <stdint.h>

#include "trailer_tdroc.h"

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
#ifndef HAND_FROZEN
    trailer_tdroc_config_t config;  /* the configuration _init validated, compared each step */
#endif
    /* P of (20) for the two driven wheels (coordinates 4 and 5) */
    trailer_real_t p12[2], p22[2];
    /* Mhat(q) = S^T M S in wheel rates, entries (11, 12, 22), is m0 + mc cos 2psi + ms sin 2psi
       (psi the hitch angle): the nine coefficients depend on the nominal parameters only */
    trailer_real_t m0[3], mc[3], ms[3];
    /* (17) kept: 1/span, the blend of u(t-h) and u(t-2h), the estimator */
    trailer_real_t inv_span, c1, c2;
    int central;
    /* (25) kept: a^i, and 1 / sum_{i<active} a^i per active window length */
    trailer_real_t apow[TRAILER_MAX_WINDOW];
    trailer_real_t inv_wsum[TRAILER_MAX_WINDOW + 1];
    /* the window's difference norms, newest first from dn[head]: each written twice (head
       and head + TRAILER_MAX_WINDOW) so the window is contiguous without % or a shift */
    trailer_real_t dn[2 * TRAILER_MAX_WINDOW];
    int head;
    int omega_count;
    /* the history (17) reads: the wheel rates, the torques applied, and Mhat(q(t-h)) itself
       (this step's Mhat is the next step's: no second sin/cos pair, no second Mhat) */
    trailer_real_t qdot_prev[2], qdot_prev2[2];
    trailer_real_t tau_prev[2], tau_prev2[2];
    trailer_real_t m_prev[3];
    trailer_real_t H1hat[2];
    trailer_real_t gain, s_norm;
    trailer_real_t tau[2];
} hand_tdroc_state_t;

trailer_status_t HAND_NAME(tdroc_init)(hand_tdroc_state_t *state,
    const trailer_tdroc_config_t *config);

trailer_status_t HAND_NAME(tdroc_step)(hand_tdroc_state_t *state,
    const trailer_tdroc_config_t *config, const trailer_real_t q[8], const trailer_real_t qdot[8],
    const trailer_real_t q_des[8], const trailer_real_t qdot_des[8],
    const trailer_real_t qddot_des[8], trailer_real_t tau[2]);

#ifdef HAND_FROZEN
extern const trailer_tdroc_config_t HAND_NAME(frozen_config);
#endif

#endif /* HAND_TRAILER_TDROC_H */
