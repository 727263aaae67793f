/*
 * A hand-written TDROC step (paper formulation, double), the benchmark's reference for
 * the generated wmr_tdroc_step: same configuration struct, same contract (statuses and
 * their order, error detail not included, commit on success). Not used by the toolchain.
 */
#ifndef HAND_TDROC_H
#define HAND_TDROC_H

#include <stdint.h>

#include "wmr_tdroc.h"

typedef struct {
    long magic;
    uint32_t steps;
    uint32_t config_fp;
    double p12[5], p22[5];
    double minv_norm;
    double w_full[WMR_MAX_WINDOW]; /* normalised weights of the full window (at init) */
    double q_prev[5], qdot_prev[5], qdot_prev2[5];
    double tau_prev[2], tau_prev2[2]; /* u(t-h) = B tau(t-h), u(t-2h) = B tau(t-2h) */
    double sin_prev, cos_prev;        /* of theta(t-h): one sin/cos pair per step */
    double omega[WMR_MAX_WINDOW + 1][5]; /* ring buffer of Omega, newest at head */
    int head;
    int omega_count;
    double H1hat[5];
    double gain, s_norm, u_discarded;
    double tau[2];
} hand_tdroc_state_t;

wmr_status_t hand_tdroc_init(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config);

wmr_status_t hand_tdroc_step(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const double q[5], const double qdot[5], const double q_des[5], const double qdot_des[5],
    const double qddot_des[5], double tau[2]);

/* wmr_forward_dynamics by hand, with the same checks and status codes (in = params, q,
   qdot, tau; out = qddot); returns the status. */
int hand_forward_dynamics_checked(const double *in, double *qdd);

#endif /* HAND_TDROC_H */
