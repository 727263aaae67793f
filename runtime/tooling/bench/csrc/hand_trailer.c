/*
 * Hand-written forward dynamics of the shipped trailer robot (modeling/robots/trailer:
 * a differential drive towing a two-wheeled cart on a revolute hitch), double, or float32
 * with -DHAND_FLOAT32: the benchmark's competitor for the generated
 * trailer_forward_dynamics and trailer_minimal_forward_dynamics, written to be fast under
 * their contract. Derived by hand from the robot's kinetic energy in base parameters
 * (generated/trailer/MODEL.md) and its wheel constraints, not from generated code; the
 * benchmark checks it against ours on every input set before timing it. Not used by the
 * toolchain.
 *
 * Contract (the generated functions'): in = the flat inputs in the spec's order (the 15
 * base parameters, q, then qdot or the wheel rates, tau); returns 0 (TRAILER_OK) and writes
 * out, or without writing: -2 (TRAILER_ERR_NONFINITE_INPUT) if an input it reads is NaN or
 * infinite, -3 (TRAILER_ERR_BAD_PARAMS) if a radius or an inertia J is not positive or the
 * reduced mass matrix is not positive definite, -4 (TRAILER_ERR_NONFINITE_OUTPUT) if a
 * result is not finite.
 *
 * The derivation (Maggi's equations in the quasi-velocities u = (v, w), the tractor's
 * forward speed and yaw rate; psi = theta_tractor - theta_cart, c = cos psi, s = sin psi):
 *   v = (r_R phi_R + r_L phi_L) / 2,  w = (r_R phi_R - r_L phi_L) / (2 HB);
 *   the hitch, A behind the drive axle, moves at tc = v c + A w s along the cart and
 *   nc = v s - A w c across it; the cart's no-side-slip at its axle (LC behind the hitch)
 *   gives thetadot_cart = nc / LC; its wheels (CB either side) roll at
 *   (tc +- CB thetadot_cart) / r_cart.
 *   T on the constraints is a quadratic form in u whose coefficients depend on psi only
 *   (the robot is invariant under planar rigid motions), so Mbar_u = [[Mvv, Mvw], [Mvw,
 *   Mww]] and the bias b_u = S^T (M Sdot u + H) need sin and cos of psi only; theta's
 *   sin and cos only rotate the tractor's acceleration into the world frame.
 *   With P = K2 c - K1 s and G = K1 c + K2 s (K1 = K_theta_cart_x_tractor, K2 =
 *   K_theta_cart_x_tractor_2, K3, K4 the tractor's), the velocity-product accelerations
 *   at u_dot = 0 (thetaddot_cart0 = psidot tc / LC, the cart wheels' (psidot (A w c - v s)
 *   +- CB thetaddot_cart0) / r_cart), and the generalised forces they leave
 *     f_xy = P thetaddot_cart0 + K3 w^2 + G thetadot_cart^2      (along the heading)
 *     f_th = -K3 v w + A G thetaddot_cart0 - A P thetadot_cart^2
 *     f_c  = -G v w + J_c thetaddot_cart0 + A P w^2
 *   the bias is b_v = f_xy + alpha f_c + sum gamma J_w phiddot0, b_w = f_th + beta f_c +
 *   sum delta J_w phiddot0 (alpha, beta, gamma, delta: the columns of S in u).
 *   u_dot = Mbar_u^-1 (S_u^T B tau - b_u); eta_dot and qddot follow from S and Sdot u.
 *   The positive-definiteness guard is checked on Mbar_u = G_u^-T Mbar G_u^-1, which is
 *   positive definite exactly when the wheel-rate Mbar is (G_u invertible: radii > 0).
 */
#include <math.h>

#ifdef HAND_FLOAT32
typedef float real;
#define L(x) x##f
#define HSIN(x) sinf(x)
#define HCOS(x) cosf(x)
#define HAND_NAME(x) handf32_trailer_##x
#else
typedef double real;
#define L(x) x
#define HSIN(x) sin(x)
#define HCOS(x) cos(x)
#define HAND_NAME(x) hand_trailer_##x
#endif

#include "hand_trailer_geometry.h"

enum { OK = 0, NONFINITE_INPUT = -2, BAD_PARAMS = -3, NONFINITE_OUTPUT = -4 };
enum { J_C, J_CL, J_CR, J_L, J_R, J_TH, J_X, K1, K2, K3, K4, R_CL, R_CR, R_L, R_R, NPAR };

/* NaN or infinite iff x - x is NaN: the sum below is NaN iff one of them is. */
#define BAD(x) ((x) - (x))

/* What the two functions share: the tractor's speeds and accelerations, S's columns in u
   (thetadot_cart = alpha v + beta w, the cart wheels' gamma v + delta w), and the
   velocity-product accelerations. */
typedef struct {
    real v, w, vd, wd, alpha, beta, gr, gl, dr, dl, thc0, cr0, cl0, irr, irl;
} trailer_solution;

/* The status; on success (OK) the solution in *o. Always inlined: o stays in registers. */
static inline __attribute__((always_inline)) int solve(
    const real *par, real th, real thc_angle, real phr, real phl, real taur, real taul,
    trailer_solution *o)
{
    const real Jc = par[J_C], Jcl = par[J_CL], Jcr = par[J_CR], Jl = par[J_L], Jr = par[J_R];
    const real Jth = par[J_TH], Jx = par[J_X], k1 = par[K1], k2 = par[K2], k3 = par[K3];
    const real k4 = par[K4], rcl = par[R_CL], rcr = par[R_CR], rl = par[R_L], rr = par[R_R];
    real psi, c, s, v, w, irr, irl, ircr, ircl, alpha, beta, tc, nc, thc, psid, gr, gl, dr, dl;
    real P, G, jr, jl, mvv, mww, mvw, det, thc0, dtc, cr0, cl0, fxy, fth, fc, fcr, fcl, bv, bw;
    real Fv, Fw, inv;
    if (isnan(BAD(Jc) + BAD(Jcl) + BAD(Jcr) + BAD(Jl) + BAD(Jr) + BAD(Jth) + BAD(Jx) + BAD(k1)
              + BAD(k2) + BAD(k3) + BAD(k4) + BAD(rcl) + BAD(rcr) + BAD(rl) + BAD(rr)
              + BAD(th) + BAD(thc_angle) + BAD(phr) + BAD(phl) + BAD(taur) + BAD(taul))) {
        return NONFINITE_INPUT;
    }
    if (!(rcl > L(0.0)) || !(rcr > L(0.0)) || !(rl > L(0.0)) || !(rr > L(0.0))
        || !(Jc > L(0.0)) || !(Jcl > L(0.0)) || !(Jcr > L(0.0)) || !(Jl > L(0.0))
        || !(Jr > L(0.0)) || !(Jth > L(0.0)) || !(Jx > L(0.0))) {
        return BAD_PARAMS;
    }
    psi = th - thc_angle;
    c = HCOS(psi);
    s = HSIN(psi);
    irr = L(1.0) / rr;
    irl = L(1.0) / rl;
    ircr = L(1.0) / rcr;
    ircl = L(1.0) / rcl;
    v = L(0.5) * (rr * phr + rl * phl);
    w = (rr * phr - rl * phl) * (L(0.5) / HB);
    alpha = s * (L(1.0) / LC);
    beta = c * (-A / LC);
    gr = (c + CB * alpha) * ircr;
    gl = (c - CB * alpha) * ircl;
    dr = (A * s + CB * beta) * ircr;
    dl = (A * s - CB * beta) * ircl;
    tc = v * c + A * w * s;
    nc = v * s - A * w * c;
    thc = nc * (L(1.0) / LC);
    psid = w - thc;
    P = k2 * c - k1 * s;
    G = k1 * c + k2 * s;
    /* Mbar in u */
    jr = Jr * irr * irr;
    jl = Jl * irl * irl;
    mvv = Jx + Jc * alpha * alpha + jr + jl + Jcr * gr * gr + Jcl * gl * gl + L(2.0) * P * alpha;
    mww = Jth + Jc * beta * beta + HB * HB * (jr + jl) + Jcr * dr * dr + Jcl * dl * dl
          + L(2.0) * A * G * beta;
    mvw = Jc * alpha * beta + HB * (jr - jl) + Jcr * gr * dr + Jcl * gl * dl + P * beta
          + A * G * alpha + k4;
    det = mvv * mww - mvw * mvw;
    if (!(mvv > L(0.0)) || !(det > L(0.0))) {
        return BAD_PARAMS;
    }
    /* velocity-product accelerations (u_dot = 0) and the forces they leave */
    thc0 = psid * tc * (L(1.0) / LC);
    dtc = psid * (A * w * c - v * s);
    cr0 = (dtc + CB * thc0) * ircr;
    cl0 = (dtc - CB * thc0) * ircl;
    fxy = P * thc0 + k3 * w * w + G * thc * thc;
    fth = -k3 * v * w + A * (G * thc0 - P * thc * thc);
    fc = -G * v * w + Jc * thc0 + A * P * w * w;
    fcr = Jcr * cr0;
    fcl = Jcl * cl0;
    bv = fxy + alpha * fc + gr * fcr + gl * fcl;
    bw = fth + beta * fc + dr * fcr + dl * fcl;
    /* S_u^T B tau - b_u, solved */
    Fv = taur * irr + taul * irl - bv;
    Fw = HB * (taur * irr - taul * irl) - bw;
    inv = L(1.0) / det;
    o->vd = (mww * Fv - mvw * Fw) * inv;
    o->wd = (mvv * Fw - mvw * Fv) * inv;
    o->v = v;
    o->w = w;
    o->alpha = alpha;
    o->beta = beta;
    o->gr = gr;
    o->gl = gl;
    o->dr = dr;
    o->dl = dl;
    o->thc0 = thc0;
    o->cr0 = cr0;
    o->cl0 = cl0;
    o->irr = irr;
    o->irl = irl;
    return OK;
}

/* trailer_forward_dynamics: in = 15 parameters, q[8], qdot[8], tau[2]; out = qddot[8]. */
int HAND_NAME(forward_dynamics)(const real *in, real *out)
{
    const real *q = in + NPAR, *qdot = in + NPAR + 8, *tau = in + NPAR + 16;
    trailer_solution o;
    real ct, st, ax, an, r[8];
    int status = solve(in, q[2], q[3], qdot[4], qdot[5], tau[0], tau[1], &o);
    if (status != OK) {
        return status;
    }
    ct = HCOS(q[2]);
    st = HSIN(q[2]);
    ax = o.vd;           /* the axle's acceleration along the heading */
    an = o.v * o.w;      /* and across it */
    r[0] = ax * ct - an * st;
    r[1] = ax * st + an * ct;
    r[2] = o.wd;
    r[3] = o.alpha * o.vd + o.beta * o.wd + o.thc0;
    r[4] = (o.vd + HB * o.wd) * o.irr;
    r[5] = (o.vd - HB * o.wd) * o.irl;
    r[6] = o.gr * o.vd + o.dr * o.wd + o.cr0;
    r[7] = o.gl * o.vd + o.dl * o.wd + o.cl0;
    if (isnan(BAD(r[0]) + BAD(r[1]) + BAD(r[2]) + BAD(r[3]) + BAD(r[4]) + BAD(r[5]) + BAD(r[6])
              + BAD(r[7]))) {
        return NONFINITE_OUTPUT;
    }
    out[0] = r[0];
    out[1] = r[1];
    out[2] = r[2];
    out[3] = r[3];
    out[4] = r[4];
    out[5] = r[5];
    out[6] = r[6];
    out[7] = r[7];
    return OK;
}

/* trailer_minimal_forward_dynamics: in = 15 parameters, q[8], wheel_rates[2], tau[2];
   out = wheel_accels[2]. */
int HAND_NAME(minimal_forward_dynamics)(const real *in, real *out)
{
    const real *q = in + NPAR, *rates = in + NPAR + 8, *tau = in + NPAR + 10;
    trailer_solution o;
    real er, el;
    int status = solve(in, q[2], q[3], rates[0], rates[1], tau[0], tau[1], &o);
    if (status != OK) {
        return status;
    }
    er = (o.vd + HB * o.wd) * o.irr;
    el = (o.vd - HB * o.wd) * o.irl;
    if (isnan(BAD(er) + BAD(el))) {
        return NONFINITE_OUTPUT;
    }
    out[0] = er;
    out[1] = el;
    return OK;
}
