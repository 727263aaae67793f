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
