/* Runtime (not firmware) helper: advance a generated robot's plant between control samples.
 *
 * Compiled once per robot with its C prefix (runtime/sim/plant.py):
 *   -DSIM_PREFIX=<prefix> -DSIM_PREFIX_UPPER=<PREFIX> -DSIM_PLANT_H="<prefix>_plant.h"
 * The plant is the generated <prefix>_plant_state_derivative, x = (q, the driven wheels'
 * rates): SIM_NX = <PREFIX>_PLANT_STATE_DERIVATIVE_X_SIZE values, SIM_NU inputs. */
#ifndef SIM_PLANT_RK4_H
#define SIM_PLANT_RK4_H

#include SIM_PLANT_H

#define SIM_CAT2(a, b) a##b
#define SIM_CAT(a, b) SIM_CAT2(a, b)
#define SIM_REAL SIM_CAT(SIM_PREFIX, _real_t)
#define SIM_PARAMS SIM_CAT(SIM_PREFIX, _plant_params_t)
#define SIM_NX SIM_CAT(SIM_PREFIX_UPPER, _PLANT_STATE_DERIVATIVE_X_SIZE)
#define SIM_NU SIM_CAT(SIM_PREFIX_UPPER, _PLANT_STATE_DERIVATIVE_TAU_SIZE)

/* Wheel friction unknown to the controllers: viscous plus smoothed Coulomb,
 * tau_f = -(viscous * w + coulomb * tanh(w / coulomb_speed)) per driven wheel. */
typedef struct {
    SIM_REAL viscous;
    SIM_REAL coulomb;
    SIM_REAL coulomb_speed;
} sim_friction_t;

/* Fixed-step RK4 of the plant x (SIM_NX values) over nsub steps of dt with the torque held
 * (zero-order hold). Returns 0, or -1 if the state became non-finite. */
int sim_plant_advance(const SIM_PARAMS *pp, const sim_friction_t *friction, SIM_REAL *x,
                      const SIM_REAL *tau, SIM_REAL dt, int nsub);

/* The same with wheel slip (runtime/experiment/faults.py, traction loss): driven wheel i passes
 * (1 - loss[i]) of its net torque to the ground, the rest spins it relative to the ground on
 * its spin inertia spin_inertia[i]. slip = (the SIM_NU slip angles, then their rates): the
 * wheels' angles and rates relative to rolling, which an encoder on the wheel adds to the
 * rolling ones in x. Returns 0, or -1 if the state became non-finite (x, slip then
 * untouched). */
int sim_plant_advance_slip(const SIM_PARAMS *pp, const sim_friction_t *friction,
                           const SIM_REAL *spin_inertia, SIM_REAL *x, SIM_REAL *slip,
                           const SIM_REAL *tau, const SIM_REAL *loss, SIM_REAL dt, int nsub);

#endif
