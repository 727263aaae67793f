/*
 * Hand-written C of the model equations, typed from the paper (with the corrections
 * the derivation proved: (31) with b/2; (14) not symmetric), written the way an expert
 * would: the minimal form M̄ η̇ + H̄ = τ in closed form, then q̈ = S η̇ + Ṡ η.
 * The benchmark's reference point; not used by the toolchain. in = params (m, I, K, Iw,
 * r, b, d) followed by the function's inputs.
 */
#include <math.h>

#include "hand_model.h"

void hand_kinematics(const double *in, double *out)
{
    const double r = in[4], b = in[5], d = in[6];
    const double th = in[9], wr = in[12], wl = in[13];
    const double c = cos(th), s = sin(th);
    const double v = 0.5 * r * (wr + wl), w = r * (wr - wl) / b;  /* (31), (13) */
    out[0] = v * c - d * w * s;
    out[1] = v * s + d * w * c;
    out[2] = w;
}

void hand_mass_matrix(const double *in, double *M)
{
    const double m = in[0], I = in[1], K = in[2], Iw = in[3], r = in[4], b = in[5], d = in[6];
    const double th = in[9], c = cos(th), s = sin(th);
    const double k1 = (m * d * r - K * r) / b * s - 0.5 * m * r * c;
    const double k2 = (K * r - m * d * r) / b * s - 0.5 * m * r * c;
    const double k3 = (K * r - m * d * r) / b * c - 0.5 * m * r * s;
    const double k4 = (m * d * r - K * r) / b * c - 0.5 * m * r * s;
    const double k5 = r * (I - K * d) / b;
    const double M14[25] = {
        m, 0.0, K * s, k1, k2,
        0.0, m, -K * c, k3, k4,
        K * s, -K * c, I, -k5, k5,
        -k1, -k3, k5, Iw, 0.0,
        -k2, -k4, -k5, 0.0, Iw,
    };
    int i;
    for (i = 0; i < 25; ++i) {
        M[i] = M14[i];
    }
}

void hand_bias_forces(const double *in, double *H)
{
    const double m = in[0], K = in[2], r = in[4], b = in[5], d = in[6];
    const double th = in[9], thd = in[14], wr = in[15], wl = in[16];
    const double c = cos(th), s = sin(th);
    const double w = r * (wr - wl) / b;
    const double sq = r * r * (wr * wr - wl * wl) / (2.0 * b);
    H[0] = m * d * w * w * c + m * s * sq;
    H[1] = m * d * w * w * s - m * c * sq;
    H[2] = K * sq;
    H[3] = 0.5 * K * r * thd * thd;
    H[4] = 0.5 * K * r * thd * thd;
}

void hand_forward_dynamics(const double *in, double *qdd)
{
    const double m = in[0], I = in[1], K = in[2], Iw = in[3], r = in[4], b = in[5], d = in[6];
    const double th = in[9], wr = in[15], wl = in[16], tr = in[17], tl = in[18];
    const double c = cos(th), s = sin(th);
    const double ia = I - 2.0 * K * d + m * d * d;  /* yaw inertia about the axle midpoint */
    const double rb = r / b, rb2 = rb * rb;
    const double a11 = Iw + 0.25 * m * r * r + ia * rb2, a12 = 0.25 * m * r * r - ia * rb2;
    const double g = r * rb2 * (K - m * d);
    const double h1 = g * wl * (wl - wr), h2 = g * wr * (wr - wl);
    const double det = a11 * a11 - a12 * a12;
    const double er = (a11 * (tr - h1) - a12 * (tl - h2)) / det;
    const double el = (a11 * (tl - h2) - a12 * (tr - h1)) / det;
    const double v = 0.5 * r * (wr + wl), w = rb * (wr - wl);
    const double vd = 0.5 * r * (er + el), wd = rb * (er - el);
    qdd[0] = vd * c - d * wd * s - v * w * s - d * w * w * c;
    qdd[1] = vd * s + d * wd * c + v * w * c - d * w * w * s;
    qdd[2] = wd;
    qdd[3] = er;
    qdd[4] = el;
}
