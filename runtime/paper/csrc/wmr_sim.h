/* Runtime (not firmware) helper: advance the simulated robot between control samples. */
#ifndef WMR_SIM_H
#define WMR_SIM_H

#include "wmr_plant.h"

/* Wheel friction unknown to the controllers: viscous plus smoothed Coulomb,
 * tau_f = -(viscous * w + coulomb * tanh(w / coulomb_speed)) per wheel. */
typedef struct {
    wmr_real_t viscous;
    wmr_real_t coulomb;
    wmr_real_t coulomb_speed;
} sim_friction_t;

/* Fixed-step RK4 of the plant x = (q, wheel rates) over nsub steps of dt with the torque
 * held (zero-order hold). Returns 0, or -1 if the state became non-finite. */
int sim_plant_advance(const wmr_plant_params_t *pp, const sim_friction_t *friction,
                      wmr_real_t x[7], const wmr_real_t tau[2], wmr_real_t dt, int nsub);

/* The same with wheel slip (runtime/paper/faults.py, traction loss): wheel i passes
 * (1 - loss[i]) of its net torque to the ground, the rest spins it relative to the ground on
 * its inertia Iw. slip = (sigma_r, sigma_l, rate_r, rate_l): the wheels' angles and rates
 * relative to rolling, which an encoder on the wheel adds to x[3..6]. x[3], x[4] stay the
 * rolling angles. Returns 0, or -1 if the state became non-finite (x, slip then untouched). */
int sim_plant_advance_slip(const wmr_plant_params_t *pp, const sim_friction_t *friction,
                           wmr_real_t x[7], wmr_real_t slip[4], const wmr_real_t tau[2],
                           const wmr_real_t loss[2], wmr_real_t dt, int nsub);

#endif
