#ifndef HAND_MODEL_H
#define HAND_MODEL_H
void hand_kinematics(const double *in, double *out);
void hand_mass_matrix(const double *in, double *M);
void hand_bias_forces(const double *in, double *H);
void hand_forward_dynamics(const double *in, double *qdd);
#endif
