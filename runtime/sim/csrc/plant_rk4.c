/* See plant_rk4.h: RK4 of a generated plant with wheel friction and the slip proxy, for any
 * robot (the prefix comes from the compiler's -D flags). */
#include "plant_rk4.h"

#define SIM_NQ (SIM_NX - SIM_NU)
#define SIM_NZ (SIM_NX + 2 * SIM_NU) /* x, then the slip angles and rates */
#define SIM_LIT(x) SIM_CAT(SIM_PREFIX_UPPER, _LIT)(x)
#define SIM_TANH(x) SIM_CAT(SIM_PREFIX_UPPER, _TANH)(x)
#define SIM_DERIVATIVE SIM_CAT(SIM_PREFIX, _plant_state_derivative)

static void sim_rhs(const SIM_PARAMS *pp, const sim_friction_t *fr, const SIM_REAL *x,
                    const SIM_REAL *tau, SIM_REAL *xdot)
{
    SIM_REAL t[SIM_NU];
    int i;
    for (i = 0; i < SIM_NU; ++i) {
        const SIM_REAL w = x[SIM_NQ + i];
        t[i] = tau[i] - fr->viscous * w - fr->coulomb * SIM_TANH(w / fr->coulomb_speed);
    }
    SIM_DERIVATIVE(pp, x, t, xdot);
}

int sim_plant_advance(const SIM_PARAMS *pp, const sim_friction_t *friction, SIM_REAL *x,
                      const SIM_REAL *tau, SIM_REAL dt, int nsub)
{
    SIM_REAL k1[SIM_NX], k2[SIM_NX], k3[SIM_NX], k4[SIM_NX], y[SIM_NX];
    int s, i;
    for (s = 0; s < nsub; ++s) {
        sim_rhs(pp, friction, x, tau, k1);
        for (i = 0; i < SIM_NX; ++i) y[i] = x[i] + SIM_LIT(0.5) * dt * k1[i];
        sim_rhs(pp, friction, y, tau, k2);
        for (i = 0; i < SIM_NX; ++i) y[i] = x[i] + SIM_LIT(0.5) * dt * k2[i];
        sim_rhs(pp, friction, y, tau, k3);
        for (i = 0; i < SIM_NX; ++i) y[i] = x[i] + dt * k3[i];
        sim_rhs(pp, friction, y, tau, k4);
        for (i = 0; i < SIM_NX; ++i) {
            x[i] += dt / SIM_LIT(6.0) * (k1[i] + SIM_LIT(2.0) * k2[i] + SIM_LIT(2.0) * k3[i] + k4[i]);
            if (!isfinite(x[i])) return -1;
        }
    }
    return 0;
}

/* Slip proxy: wheel i transmits (1 - loss[i]) of its net torque (drive minus friction at the
 * rotor rate) to the ground (the constrained plant); the rest spins the wheel relative to the
 * ground on its own spin inertia. z = (x, slip angles, slip rates). */
static void sim_rhs_slip(const SIM_PARAMS *pp, const sim_friction_t *fr,
                         const SIM_REAL *spin_inertia, const SIM_REAL *z, const SIM_REAL *tau,
                         const SIM_REAL *loss, SIM_REAL *zdot)
{
    SIM_REAL g[SIM_NU];
    int i;
    for (i = 0; i < SIM_NU; ++i) {
        const SIM_REAL w = z[SIM_NQ + i] + z[SIM_NX + SIM_NU + i];
        const SIM_REAL net = tau[i] - fr->viscous * w - fr->coulomb * SIM_TANH(w / fr->coulomb_speed);
        g[i] = (SIM_LIT(1.0) - loss[i]) * net;
        zdot[SIM_NX + i] = z[SIM_NX + SIM_NU + i];
        zdot[SIM_NX + SIM_NU + i] = loss[i] * net / spin_inertia[i];
    }
    SIM_DERIVATIVE(pp, z, g, zdot);
}

int sim_plant_advance_slip(const SIM_PARAMS *pp, const sim_friction_t *friction,
                           const SIM_REAL *spin_inertia, SIM_REAL *x, SIM_REAL *slip,
                           const SIM_REAL *tau, const SIM_REAL *loss, SIM_REAL dt, int nsub)
{
    SIM_REAL z[SIM_NZ], k1[SIM_NZ], k2[SIM_NZ], k3[SIM_NZ], k4[SIM_NZ], y[SIM_NZ];
    int s, i;
    for (i = 0; i < SIM_NX; ++i) z[i] = x[i];
    for (i = 0; i < 2 * SIM_NU; ++i) z[SIM_NX + i] = slip[i];
    for (s = 0; s < nsub; ++s) {
        sim_rhs_slip(pp, friction, spin_inertia, z, tau, loss, k1);
        for (i = 0; i < SIM_NZ; ++i) y[i] = z[i] + SIM_LIT(0.5) * dt * k1[i];
        sim_rhs_slip(pp, friction, spin_inertia, y, tau, loss, k2);
        for (i = 0; i < SIM_NZ; ++i) y[i] = z[i] + SIM_LIT(0.5) * dt * k2[i];
        sim_rhs_slip(pp, friction, spin_inertia, y, tau, loss, k3);
        for (i = 0; i < SIM_NZ; ++i) y[i] = z[i] + dt * k3[i];
        sim_rhs_slip(pp, friction, spin_inertia, y, tau, loss, k4);
        for (i = 0; i < SIM_NZ; ++i) {
            z[i] += dt / SIM_LIT(6.0) * (k1[i] + SIM_LIT(2.0) * k2[i] + SIM_LIT(2.0) * k3[i] + k4[i]);
            if (!isfinite(z[i])) return -1;
        }
    }
    for (i = 0; i < SIM_NX; ++i) x[i] = z[i];
    for (i = 0; i < 2 * SIM_NU; ++i) slip[i] = z[SIM_NX + i];
    return 0;
}
