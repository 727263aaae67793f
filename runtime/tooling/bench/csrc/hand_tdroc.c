/*
 * Hand-written TDROC step, paper formulation, double: what an expert would write from the
 * paper for firmware, with the generated step's contract. (17) TDE, (25) gain over the
 * window of Omega's, (22)/(24) law with the boundary layer, all five rows of u = M(q) u_a
 * + H1hat (14), tau = B^T u, saturation, commit on success. Validation: the same statuses
 * in the same order (NULL, not initialised, configuration checked (only when its
 * fingerprint differs from _init's) or changed, inputs, outputs); the MINIMAL formulation
 * is refused (WMR_ERR_BAD_FORMULATION). Typed from the paper, not from generated code;
 * the benchmark checks it against wmr_tdroc_step before timing. Not used by the toolchain.
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "hand_tdroc.h"

#define BOUND 1.0e6

static int pos_at_most(double x, double max) { return isfinite(x) && x > 0.0 && x <= max; }
static int nonneg_at_most(double x, double max) { return isfinite(x) && x >= 0.0 && x <= max; }

static uint32_t fnv_words(uint32_t h, const void *p, size_t n)
{
    const unsigned char *b = (const unsigned char *)p;
    size_t i;
    for (i = 0; i + 4 <= n; i += 4) {
        uint32_t w;
        memcpy(&w, b + i, 4);
        h = (h ^ w) * 16777619u;
    }
    return h;
}

static uint32_t fingerprint(const wmr_tdroc_config_t *c)
{
    uint32_t h = 2166136261u;
    h = fnv_words(h, &c->nominal, sizeof c->nominal);
    h = fnv_words(h, &c->formulation, sizeof c->formulation);
    h = fnv_words(h, c->k1, sizeof c->k1);
    h = fnv_words(h, c->k2, sizeof c->k2);
    h = fnv_words(h, &c->q_pos, sizeof(double));
    h = fnv_words(h, &c->q_vel, sizeof(double));
    h = fnv_words(h, &c->h, sizeof(double));
    h = fnv_words(h, &c->tau_max, sizeof(double));
    h = fnv_words(h, &c->accel_estimator, sizeof(int));
    h = fnv_words(h, &c->rate_window, sizeof(double));
    h = fnv_words(h, &c->eps, sizeof(double));
    h = fnv_words(h, &c->n, sizeof(int));
    h = fnv_words(h, &c->a, sizeof(double));
    h = fnv_words(h, &c->hold_gain, sizeof(int));
    h = fnv_words(h, &c->held_gain, sizeof(double));
    return h;
}

/* P of (20) for A = [[0, 1], [-k1, -k2]], Q = diag(q1, q2): (p12, p22). */
static void lyap(double k1, double k2, double q1, double q2, double *p11, double *p12,
                 double *p22)
{
    *p11 = (k1 * k1 * q2 + k1 * q1 + k2 * k2 * q1) / (2.0 * k1 * k2);
    *p12 = q1 / (2.0 * k1);
    *p22 = (k1 * q2 + q1) / (2.0 * k1 * k2);
}

static wmr_status_t check_config(const wmr_tdroc_config_t *c)
{
    const wmr_params_t *p = &c->nominal;
    const double lim[7] = {36000.0, 5720.0, 1000.0, 1000.0, 1000.0, 1000.0, 1000.0};
    const double pv[7] = {p->m, p->Iz, p->K, p->Iw, p->r, p->b, p->d};
    int i;
    if (c->formulation != WMR_FORMULATION_PAPER) {
        return WMR_ERR_BAD_FORMULATION;
    }
    if (!isfinite(c->h) || !(c->h >= 1.0e-6) || !(c->h <= 1.0)) {
        return WMR_ERR_BAD_SAMPLE_TIME;
    }
    for (i = 0; i < 5; ++i) {
        if (!pos_at_most(c->k1[i], BOUND) || !pos_at_most(c->k2[i], BOUND)) {
            return WMR_ERR_BAD_GAINS;
        }
    }
    if (!pos_at_most(c->q_pos, BOUND) || !pos_at_most(c->q_vel, BOUND)) {
        return WMR_ERR_BAD_GAINS;
    }
    for (i = 0; i < 5; ++i) {
        double a, b, d;
        lyap(c->k1[i], c->k2[i], c->q_pos, c->q_vel, &a, &b, &d);
        if (!isfinite(a) || !isfinite(b) || !isfinite(d)) {
            return WMR_ERR_BAD_GAINS;
        }
    }
    if (!pos_at_most(c->tau_max, BOUND)) {
        return WMR_ERR_BAD_TORQUE_LIMIT;
    }
    if (!pos_at_most(c->eps, BOUND)) {
        return WMR_ERR_BAD_EPS;
    }
    if (c->accel_estimator < WMR_ACCEL_BACKWARD || c->accel_estimator > WMR_ACCEL_MATCHED
        || !nonneg_at_most(c->rate_window, c->h)) {
        return WMR_ERR_BAD_ESTIMATOR;
    }
    if ((c->hold_gain != 0 && c->hold_gain != 1) || !nonneg_at_most(c->held_gain, BOUND)) {
        return WMR_ERR_BAD_HELD_GAIN;
    }
    if (c->n < 2 || c->n > WMR_MAX_WINDOW) {
        return WMR_ERR_BAD_WINDOW;
    }
    if (!pos_at_most(c->a, 1.0)) {
        return WMR_ERR_BAD_DISCOUNT;
    }
    for (i = 0; i < 7; ++i) {
        if (!isfinite(pv[i]) || fabs(pv[i]) > lim[i]) {
            return WMR_ERR_BAD_NOMINAL;
        }
    }
    {   /* S^T M S positive definite; m, I, Iw > 0; m I - K^2 > 0 */
        const double ia = p->Iz - 2.0 * p->K * p->d + p->m * p->d * p->d;
        const double rb2 = p->r * p->r / (p->b * p->b);
        const double a11 = p->Iw + 0.25 * p->m * p->r * p->r + ia * rb2;
        const double a12 = 0.25 * p->m * p->r * p->r - ia * rb2;
        if (!(p->r > 0.0) || !(p->b > 0.0) || !(a11 > 0.0) || !(a11 * a11 - a12 * a12 > 0.0)
            || !(p->m > 0.0) || !(p->Iz > 0.0) || !(p->Iw > 0.0)
            || !(p->Iz * p->m - p->K * p->K > 0.0)) {
            return WMR_ERR_BAD_NOMINAL;
        }
    }
    return WMR_OK;
}

/* M-tilde(theta) of (14), row-major, from sin and cos of theta. */
static void mass(const wmr_params_t *p, double s, double c, double M[25])
{
    const double m = p->m, K = p->K, r = p->r, b = p->b, d = p->d;
    const double k1 = (m * d * r - K * r) / b * s - 0.5 * m * r * c;
    const double k2 = (K * r - m * d * r) / b * s - 0.5 * m * r * c;
    const double k3 = (K * r - m * d * r) / b * c - 0.5 * m * r * s;
    const double k4 = (m * d * r - K * r) / b * c - 0.5 * m * r * s;
    const double k5 = r * (p->Iz - K * d) / b;
    const double rows[25] = {
        m, 0.0, K * s, k1, k2,
        0.0, m, -K * c, k3, k4,
        K * s, -K * c, p->Iz, -k5, k5,
        -k1, -k3, k5, p->Iw, 0.0,
        -k2, -k4, -k5, 0.0, p->Iw,
    };
    memcpy(M, rows, sizeof rows);
}

/* ||M-tilde^-1||_F at theta = 0 (Gauss-Jordan with partial pivoting; init only). */
static double minv_norm(const wmr_params_t *p)
{
    double a[5][10];
    double M[25], sum = 0.0;
    int i, j, k;
    mass(p, 0.0, 1.0, M);
    for (i = 0; i < 5; ++i) {
        for (j = 0; j < 10; ++j) {
            a[i][j] = j < 5 ? M[5 * i + j] : (j - 5 == i ? 1.0 : 0.0);
        }
    }
    for (k = 0; k < 5; ++k) {
        int piv = k;
        for (i = k + 1; i < 5; ++i) {
            if (fabs(a[i][k]) > fabs(a[piv][k])) {
                piv = i;
            }
        }
        for (j = 0; j < 10; ++j) {
            const double t = a[k][j];
            a[k][j] = a[piv][j];
            a[piv][j] = t;
        }
        for (j = 9; j >= k; --j) {
            a[k][j] /= a[k][k];
        }
        for (i = 0; i < 5; ++i) {
            if (i != k) {
                const double f = a[i][k];
                for (j = k; j < 10; ++j) {
                    a[i][j] -= f * a[k][j];
                }
            }
        }
    }
    for (i = 0; i < 5; ++i) {
        for (j = 5; j < 10; ++j) {
            sum += a[i][j] * a[i][j];
        }
    }
    return sqrt(sum);
}

wmr_status_t hand_tdroc_init(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config)
{
    wmr_status_t st;
    double wi = 1.0, wsum = 0.0;
    int i;
    if (state == NULL || config == NULL) {
        return WMR_ERR_NULL_POINTER;
    }
    st = check_config(config);
    if (st != WMR_OK) {
        return st;
    }
    memset(state, 0, sizeof *state);
    state->magic = WMR_STATE_MAGIC;
    state->config_fp = fingerprint(config);
    for (i = 0; i < 5; ++i) {
        double p11;
        lyap(config->k1[i], config->k2[i], config->q_pos, config->q_vel, &p11, &state->p12[i],
             &state->p22[i]);
    }
    state->minv_norm = minv_norm(&config->nominal);
    for (i = 0; i < config->n; ++i) {
        state->w_full[i] = wi;
        wsum += wi;
        wi *= config->a;
    }
    for (i = 0; i < config->n; ++i) {
        state->w_full[i] /= wsum;
    }
    return WMR_OK;
}

static int bad(const double *x)
{
    int i;
    for (i = 0; i < 5; ++i) {
        if (!isfinite(x[i]) || fabs(x[i]) > BOUND) {
            return 1;
        }
    }
    return 0;
}

wmr_status_t hand_tdroc_step(hand_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const double q[5], const double qdot[5], const double q_des[5], const double qdot_des[5],
    const double qddot_des[5], double tau[2])
{
    const wmr_params_t *p;
    double H1[5], row[5], ua[5], s[5], e[5], ed[5], M[25], u[5];
    double gain = 0.0, sn, k, sth, cth, t0, t1, udisc;
    wmr_status_t st = WMR_OK;
    int count, i, j;
    if (state == NULL || config == NULL || q == NULL || qdot == NULL || q_des == NULL
        || qdot_des == NULL || qddot_des == NULL || tau == NULL) {
        return WMR_ERR_NULL_POINTER;
    }
    if (state->magic != WMR_STATE_MAGIC) {
        return WMR_ERR_NOT_INITIALISED;
    }
    if (fingerprint(config) != state->config_fp) {
        st = check_config(config);
        return st != WMR_OK ? st : WMR_ERR_CONFIG_CHANGED;
    }
    if (bad(q) || bad(qdot)) {
        return WMR_ERR_BAD_MEASUREMENT;
    }
    if (bad(q_des) || bad(qdot_des) || bad(qddot_des)) {
        return WMR_ERR_BAD_REFERENCE;
    }
    p = &config->nominal;
    count = state->omega_count;
    /* (17): H1hat = u(t-h) - M(q(t-h)) qddot(t-h), qddot by a difference quotient. */
    if (state->steps >= 2u) {
        const int central = config->accel_estimator == WMR_ACCEL_CENTRAL;
        const double inv = 1.0 / (central ? 2.0 * config->h : config->h);
        const double c2 = config->accel_estimator == WMR_ACCEL_MATCHED
            ? config->rate_window / (2.0 * config->h) : 0.0;
        const double *then = central ? state->qdot_prev2 : state->qdot_prev;
        double qdd[5];
        for (i = 0; i < 5; ++i) {
            qdd[i] = (qdot[i] - then[i]) * inv;
        }
        mass(p, state->sin_prev, state->cos_prev, M);
        for (i = 0; i < 5; ++i) {
            double acc = i < 3 ? 0.0
                : (1.0 - c2) * state->tau_prev[i - 3] + c2 * state->tau_prev2[i - 3];
            for (j = 0; j < 5; ++j) {
                acc -= M[5 * i + j] * qdd[j];
            }
            H1[i] = acc;
            row[i] = acc;
        }
        if (count <= WMR_MAX_WINDOW) {
            count += 1;
        }
    } else {
        for (i = 0; i < 5; ++i) {
            H1[i] = 0.0;
            row[i] = 0.0;
        }
    }
    /* (25): k-hat = ||M^-1||_F sum_i w_i ||Omega(i) - Omega(i+1)||. */
    if (config->hold_gain) {
        gain = config->held_gain;
    } else if (count >= 2) {
        const int active = count - 1 < config->n ? count - 1 : config->n;
        const int pushed = state->steps >= 2u;
        double w[WMR_MAX_WINDOW], sum = 0.0;
        if (active == config->n) {
            memcpy(w, state->w_full, sizeof w);
        } else {
            double wi = 1.0, ws = 0.0;
            for (i = 0; i < active; ++i) {
                w[i] = wi;
                ws += wi;
                wi *= config->a;
            }
            for (i = 0; i < active; ++i) {
                w[i] /= ws;
            }
        }
        for (i = 0; i < active; ++i) {
            /* rows i and i+1 of the window after this step's push */
            const double *newer = pushed
                ? (i == 0 ? row : state->omega[(state->head + i - 1) % (WMR_MAX_WINDOW + 1)])
                : state->omega[(state->head + i) % (WMR_MAX_WINDOW + 1)];
            const double *older = state->omega[(state->head + i + 1 - pushed)
                                               % (WMR_MAX_WINDOW + 1)];
            double n2 = 0.0;
            for (j = 0; j < 5; ++j) {
                const double dlt = newer[j] - older[j];
                n2 += dlt * dlt;
            }
            sum += w[i] * sqrt(n2);
        }
        gain = state->minv_norm * sum;
        gain = gain <= BOUND ? gain : BOUND;
    }
    /* (18), (22), (24): u_a = qddot_d + K1 e + K2 edot + k s / max(||s||, eps). */
    sn = 0.0;
    for (i = 0; i < 5; ++i) {
        e[i] = q_des[i] - q[i];
        ed[i] = qdot_des[i] - qdot[i];
        s[i] = state->p12[i] * e[i] + state->p22[i] * ed[i];
        sn += s[i] * s[i];
    }
    sn = sqrt(sn);
    k = gain / (sn > config->eps ? sn : config->eps);
    for (i = 0; i < 5; ++i) {
        ua[i] = qddot_des[i] + config->k1[i] * e[i] + config->k2[i] * ed[i] + k * s[i];
    }
    sth = sin(q[2]);
    cth = cos(q[2]);
    mass(p, sth, cth, M);
    for (i = 0; i < 5; ++i) {
        double acc = H1[i];
        for (j = 0; j < 5; ++j) {
            acc += M[5 * i + j] * ua[j];
        }
        u[i] = acc;
    }
    t0 = u[3];
    t1 = u[4];
    udisc = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!isfinite(t0) || !isfinite(t1) || !isfinite(gain) || !isfinite(sn) || !isfinite(udisc)) {
        return WMR_ERR_NONFINITE_OUTPUT;
    }
    st = WMR_OK;
    if (t0 > config->tau_max) { t0 = config->tau_max; st = WMR_WARN_SATURATED; }
    else if (t0 < -config->tau_max) { t0 = -config->tau_max; st = WMR_WARN_SATURATED; }
    if (t1 > config->tau_max) { t1 = config->tau_max; st = WMR_WARN_SATURATED; }
    else if (t1 < -config->tau_max) { t1 = -config->tau_max; st = WMR_WARN_SATURATED; }
    /* Commit. */
    if (state->steps >= 2u) {
        const int head = (state->head + WMR_MAX_WINDOW) % (WMR_MAX_WINDOW + 1);
        memcpy(state->omega[head], row, sizeof row);
        state->head = head;
        state->omega_count = count;
    }
    memcpy(state->H1hat, H1, sizeof H1);
    memcpy(state->q_prev, q, 5 * sizeof(double));
    memcpy(state->qdot_prev2, state->qdot_prev, 5 * sizeof(double));
    memcpy(state->qdot_prev, qdot, 5 * sizeof(double));
    state->tau_prev2[0] = state->tau_prev[0];
    state->tau_prev2[1] = state->tau_prev[1];
    state->tau_prev[0] = t0;
    state->tau_prev[1] = t1;
    state->sin_prev = sth;
    state->cos_prev = cth;
    state->gain = gain;
    state->s_norm = sn;
    state->u_discarded = udisc;
    state->tau[0] = t0;
    state->tau[1] = t1;
    if (state->steps < 4294967295u) {
        state->steps += 1u;
    }
    tau[0] = t0;
    tau[1] = t1;
    return st;
}

int hand_forward_dynamics_checked(const double *in, double *qdd)
{
    const double m = in[0], I = in[1], K = in[2], Iw = in[3], r = in[4], b = in[5], d = in[6];
    const double th = in[9], wr = in[15], wl = in[16], tr = in[17], tl = in[18];
    double c, s, ia, rb, rb2, a11, a12, det, g, h1, h2, er, el, v, w, vd, wd;
    double out[5];
    int i;
    if (!isfinite(m) || !isfinite(I) || !isfinite(K) || !isfinite(Iw) || !isfinite(r)
        || !isfinite(b) || !isfinite(d) || !isfinite(th) || !isfinite(wr) || !isfinite(wl)
        || !isfinite(tr) || !isfinite(tl)) {
        return WMR_ERR_NONFINITE_INPUT;
    }
    ia = I - 2.0 * K * d + m * d * d;
    rb = r / b;
    rb2 = rb * rb;
    a11 = Iw + 0.25 * m * r * r + ia * rb2;
    a12 = 0.25 * m * r * r - ia * rb2;
    det = a11 * a11 - a12 * a12;
    if (!(r > 0.0) || !(b > 0.0) || !(a11 > 0.0) || !(det > 0.0)) {
        return WMR_ERR_BAD_PARAMS;
    }
    c = cos(th);
    s = sin(th);
    g = r * rb2 * (K - m * d);
    h1 = g * wl * (wl - wr);
    h2 = g * wr * (wr - wl);
    er = (a11 * (tr - h1) - a12 * (tl - h2)) / det;
    el = (a11 * (tl - h2) - a12 * (tr - h1)) / det;
    v = 0.5 * r * (wr + wl);
    w = rb * (wr - wl);
    vd = 0.5 * r * (er + el);
    wd = rb * (er - el);
    out[0] = vd * c - d * wd * s - v * w * s - d * w * w * c;
    out[1] = vd * s + d * wd * c + v * w * c - d * w * w * s;
    out[2] = wd;
    out[3] = er;
    out[4] = el;
    for (i = 0; i < 5; ++i) {
        if (!isfinite(out[i])) {
            return WMR_ERR_NONFINITE_OUTPUT;
        }
    }
    for (i = 0; i < 5; ++i) {
        qdd[i] = out[i];
    }
    return WMR_OK;
}
