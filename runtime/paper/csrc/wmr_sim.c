#include "wmr_sim.h"

static void sim_rhs(const wmr_plant_params_t *pp, const sim_friction_t *fr,
                    const wmr_real_t x[7], const wmr_real_t tau[2], wmr_real_t xdot[7])
{
    wmr_real_t t[2];
    int i;
    for (i = 0; i < 2; ++i) {
        const wmr_real_t w = x[5 + i];
        t[i] = tau[i] - fr->viscous * w - fr->coulomb * WMR_TANH(w / fr->coulomb_speed);
    }
    wmr_plant_state_derivative(pp, x, t, xdot);
}

int sim_plant_advance(const wmr_plant_params_t *pp, const sim_friction_t *friction,
                      wmr_real_t x[7], const wmr_real_t tau[2], wmr_real_t dt, int nsub)
{
    wmr_real_t k1[7], k2[7], k3[7], k4[7], y[7];
    int s, i;
    for (s = 0; s < nsub; ++s) {
        sim_rhs(pp, friction, x, tau, k1);
        for (i = 0; i < 7; ++i) y[i] = x[i] + WMR_LIT(0.5) * dt * k1[i];
        sim_rhs(pp, friction, y, tau, k2);
        for (i = 0; i < 7; ++i) y[i] = x[i] + WMR_LIT(0.5) * dt * k2[i];
        sim_rhs(pp, friction, y, tau, k3);
        for (i = 0; i < 7; ++i) y[i] = x[i] + dt * k3[i];
        sim_rhs(pp, friction, y, tau, k4);
        for (i = 0; i < 7; ++i) {
            x[i] += dt / WMR_LIT(6.0) * (k1[i] + WMR_LIT(2.0) * k2[i] + WMR_LIT(2.0) * k3[i] + k4[i]);
            if (!isfinite(x[i])) return -1;
        }
    }
    return 0;
}

/* Slip proxy: wheel i transmits (1 - loss[i]) of its net torque (drive minus friction at the
 * rotor rate) to the ground (the constrained plant); the rest spins the wheel relative to the
 * ground on its own inertia Iw. z = (x[0..6], sigma_r, sigma_l, sigma_r', sigma_l'). */
static void sim_rhs_slip(const wmr_plant_params_t *pp, const sim_friction_t *fr,
                         const wmr_real_t z[11], const wmr_real_t tau[2],
                         const wmr_real_t loss[2], wmr_real_t zdot[11])
{
    wmr_real_t g[2];
    int i;
    for (i = 0; i < 2; ++i) {
        const wmr_real_t w = z[5 + i] + z[9 + i];
        const wmr_real_t net = tau[i] - fr->viscous * w - fr->coulomb * WMR_TANH(w / fr->coulomb_speed);
        g[i] = (WMR_LIT(1.0) - loss[i]) * net;
        zdot[7 + i] = z[9 + i];
        zdot[9 + i] = loss[i] * net / pp->Iw;
    }
    wmr_plant_state_derivative(pp, z, g, zdot);
}

int sim_plant_advance_slip(const wmr_plant_params_t *pp, const sim_friction_t *friction,
                           wmr_real_t x[7], wmr_real_t slip[4], const wmr_real_t tau[2],
                           const wmr_real_t loss[2], wmr_real_t dt, int nsub)
{
    wmr_real_t z[11], k1[11], k2[11], k3[11], k4[11], y[11];
    int s, i;
    for (i = 0; i < 7; ++i) z[i] = x[i];
    for (i = 0; i < 4; ++i) z[7 + i] = slip[i];
    for (s = 0; s < nsub; ++s) {
        sim_rhs_slip(pp, friction, z, tau, loss, k1);
        for (i = 0; i < 11; ++i) y[i] = z[i] + WMR_LIT(0.5) * dt * k1[i];
        sim_rhs_slip(pp, friction, y, tau, loss, k2);
        for (i = 0; i < 11; ++i) y[i] = z[i] + WMR_LIT(0.5) * dt * k2[i];
        sim_rhs_slip(pp, friction, y, tau, loss, k3);
        for (i = 0; i < 11; ++i) y[i] = z[i] + dt * k3[i];
        sim_rhs_slip(pp, friction, y, tau, loss, k4);
        for (i = 0; i < 11; ++i) {
            z[i] += dt / WMR_LIT(6.0) * (k1[i] + WMR_LIT(2.0) * k2[i] + WMR_LIT(2.0) * k3[i] + k4[i]);
            if (!isfinite(z[i])) return -1;
        }
    }
    for (i = 0; i < 7; ++i) x[i] = z[i];
    for (i = 0; i < 4; ++i) slip[i] = z[7 + i];
    return 0;
}
