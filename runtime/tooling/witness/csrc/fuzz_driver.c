/*
 * Randomised driver of the generated controllers and forward dynamics, for sanitizer
 * builds (tests/firmware/test_firmware_sanitizers.py):
 *
 *   cc -std=c99 -fsanitize=address,undefined -fno-sanitize-recover=all \
 *      -Igenerated/c generated/c/wmr_*.c runtime/tooling/witness/csrc/fuzz_driver.c -lm
 *   ./a.out SEED STEPS FD_CALLS
 *
 * Every controller runs STEPS steps in each formulation, FD_CALLS calls go to each of
 * wmr_forward_dynamics and wmr_minimal_forward_dynamics. Inputs come from a seeded
 * xorshift64 generator: random valid configurations (re-initialised every 20..400 steps),
 * a random-walk motion with references near it, and now and then huge-but-valid,
 * subnormal, NaN, infinite or absurd inputs, a corrupted configuration for one step, a
 * NULL argument, a state whose magic is wrong, or a corrupted state with its magic intact
 * (one to three flipped bits anywhere else; TDROC: also its ring's head or count set to
 * any int), after which the state is initialised again.
 *
 * Checked on every call (a violation is printed and makes the exit status 1):
 *   - status >= 0: tau finite and within +-tau_max, state->tau == tau, every real in the
 *     state finite; forward dynamics: every output finite;
 *   - status < 0: the state's bytes and tau (or the output) unchanged;
 *   - a known bad input gives its own code (NaN measurement -> WMR_ERR_BAD_MEASUREMENT,
 *     NULL -> WMR_ERR_NULL_POINTER, bad magic -> WMR_ERR_NOT_INITIALISED, a non-finite
 *     argument of the forward dynamics -> WMR_ERR_NONFINITE_INPUT, ...).
 * State, configuration and input arrays are malloc'ed at their exact sizes so that
 * AddressSanitizer sees any access beyond them.
 * Output: one "RESULT ..." line per controller/formulation and per model function.
 */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wmr_asmc.h"
#include "wmr_model.h"
#include "wmr_roc.h"
#include "wmr_tdc.h"
#include "wmr_tdroc.h"

#ifdef WMR_FLOAT32
#define REAL_MAX FLT_MAX
#define REAL_TINY 1.0e-40f /* subnormal */
#else
#define REAL_MAX DBL_MAX
#define REAL_TINY 4.9e-324 /* smallest subnormal */
#endif

static uint64_t rng = 88172645463325252ULL;
static long violations = 0;

static uint64_t next_u64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static double unif(double lo, double hi)
{
    return lo + (hi - lo) * ((double)(next_u64() >> 11) * (1.0 / 9007199254740992.0));
}

static int rint_below(int n)
{
    return (int)(next_u64() % (uint64_t)n);
}

static void violation(const char *what, const char *ctrl, int form, long step, int status)
{
    violations += 1;
    if (violations <= 20) {
        fprintf(stderr, "VIOLATION %s: %s form=%d step=%ld status=%d\n", what, ctrl, form, step,
                status);
    }
}

/* An extreme value: NaN, +-Inf, +-max, huge, subnormal, -0. */
static wmr_real_t extreme(void)
{
    switch (rint_below(9)) {
    case 0: return (wmr_real_t)NAN;
    case 1: return (wmr_real_t)INFINITY;
    case 2: return -(wmr_real_t)INFINITY;
    case 3: return REAL_MAX;
    case 4: return -REAL_MAX;
    case 5: return (wmr_real_t)1.0e9;
    case 6: return (wmr_real_t)-1.0e30;
    case 7: return REAL_TINY;
    default: return (wmr_real_t)-0.0;
    }
}

/* A value that no positive configuration field may take. */
static wmr_real_t not_positive(void)
{
    switch (rint_below(6)) {
    case 0: return (wmr_real_t)0.0;
    case 1: return (wmr_real_t)-0.0;
    case 2: return (wmr_real_t)-unif(1.0e-6, 10.0);
    case 3: return (wmr_real_t)NAN;
    case 4: return (wmr_real_t)INFINITY;
    default: return -(wmr_real_t)INFINITY;
    }
}

/* A value that is valid for a controller input but unusual: |x| <= 1e6, log-uniform. */
static wmr_real_t wild(void)
{
    const double mag = pow(10.0, unif(-30.0, 6.0));
    switch (rint_below(6)) {
    case 0: return REAL_TINY;
    case 1: return (wmr_real_t)0.0;
    case 2: return (wmr_real_t)1.0e6;
    default: return (wmr_real_t)(rint_below(2) ? mag : -mag);
    }
}

static void random_params(wmr_params_t *p)
{
    p->m = (wmr_real_t)(36.0 * unif(0.3, 3.0));
    p->Iz = (wmr_real_t)(5.72 * unif(0.3, 3.0));
    p->K = (wmr_real_t)(0.34 * unif(-3.0, 3.0));
    p->Iw = (wmr_real_t)(0.07 * unif(0.3, 3.0));
    p->r = (wmr_real_t)(0.096 * unif(0.5, 2.0));
    p->b = (wmr_real_t)(0.414 * unif(0.5, 2.0));
    p->d = (wmr_real_t)(0.12 * unif(-2.0, 2.0));
}

/* Fields shared by every controller configuration. */
#define FILL_BASE(c, form)                                                        \
    do {                                                                          \
        int i_;                                                                   \
        random_params(&(c)->nominal);                                             \
        (c)->formulation = (form);                                                \
        for (i_ = 0; i_ < 5; ++i_) {                                              \
            (c)->k1[i_] = (wmr_real_t)unif(0.1, 50.0);                            \
            (c)->k2[i_] = (wmr_real_t)unif(0.1, 50.0);                            \
        }                                                                         \
        (c)->q_pos = (wmr_real_t)unif(0.05, 10.0);                                \
        (c)->q_vel = (wmr_real_t)unif(0.05, 10.0);                                \
        (c)->h = (wmr_real_t)unif(0.001, 0.2);                                    \
        (c)->tau_max = (wmr_real_t)(rint_below(10) ? unif(1.0, 500.0) : 1.0e6);  \
    } while (0)

/* Break one shared field; returns 1 (the config is now invalid). */
#define CORRUPT_BASE(c, which)                                                  \
    do {                                                                        \
        switch (which) {                                                        \
        case 0: (c)->formulation = 2 + rint_below(100); break;                  \
        case 1: (c)->h = not_positive(); break;                                 \
        case 2: (c)->k1[rint_below(5)] = not_positive(); break;                 \
        case 3: (c)->k2[rint_below(5)] = (wmr_real_t)NAN; break;                \
        case 4: (c)->q_pos = (wmr_real_t)0.0; break;                            \
        case 5: (c)->tau_max = not_positive(); break;                           \
        case 6: (c)->nominal.m = not_positive(); break;                         \
        case 7: (c)->nominal.Iz = (c)->nominal.K * (c)->nominal.K / (c)->nominal.m * (wmr_real_t)0.5; break; \
        case 8: (c)->nominal.b = (wmr_real_t)0.0; break;                        \
        default: (c)->nominal.K = (wmr_real_t)NAN; break;                       \
        }                                                                       \
    } while (0)

/* Push one positive field far out (still valid as a number: init may accept it or
 * reject the model, and a step may then overflow and must say so). */
#define STRETCH(c)                                                                    \
    do {                                                                              \
        const wmr_real_t f_ = (wmr_real_t)pow(10.0, unif(-20.0, 20.0));               \
        switch (rint_below(8)) {                                                      \
        case 0: (c)->k1[rint_below(5)] *= f_; break;                                  \
        case 1: (c)->k2[rint_below(5)] *= f_; break;                                  \
        case 2: (c)->q_pos *= f_; break;                                              \
        case 3: (c)->h *= f_; break;                                                  \
        case 4: (c)->nominal.m *= f_; break;                                          \
        case 5: (c)->nominal.Iz *= f_; break;                                         \
        case 6: (c)->nominal.Iw *= f_; break;                                         \
        default: (c)->nominal.r *= f_; break;                                         \
        }                                                                             \
    } while (0)

static void extra_tdc(wmr_tdc_config_t *c)
{
    c->accel_estimator = rint_below(3);
    c->rate_window = c->h * (wmr_real_t)unif(0.0, 1.0);
}
static void extra_tdroc(wmr_tdroc_config_t *c)
{
    c->accel_estimator = rint_below(3);
    c->rate_window = c->h * (wmr_real_t)unif(0.0, 1.0);
    c->hold_gain = 0;
    c->held_gain = (wmr_real_t)0.0;
    c->eps = (wmr_real_t)unif(0.01, 2.0);
    c->n = 2 + rint_below(WMR_MAX_WINDOW - 1);
    c->a = rint_below(5) ? (wmr_real_t)unif(0.05, 1.0) : (wmr_real_t)1.0;
}
static void extra_roc(wmr_roc_config_t *c)
{
    c->eps = (wmr_real_t)unif(0.01, 2.0);
    c->alpha = (wmr_real_t)unif(0.0, 0.99);
    c->phi = (wmr_real_t)unif(0.0, 20.0);
}
static void extra_asmc(wmr_asmc_config_t *c)
{
    c->eps = (wmr_real_t)unif(0.01, 2.0);
    c->gamma = (wmr_real_t)unif(0.0, 10.0);
    c->gain0 = (wmr_real_t)unif(0.0, 5.0);
}
static void corrupt_tdc(wmr_tdc_config_t *c) { c->accel_estimator = rint_below(2) ? 3 : -1; }
static void corrupt_tdroc(wmr_tdroc_config_t *c)
{
    switch (rint_below(4)) {
    case 0: c->eps = not_positive(); break;
    case 1: c->n = rint_below(2) ? 1 : WMR_MAX_WINDOW + 1 + rint_below(100); break;
    case 2: c->a = rint_below(2) ? (wmr_real_t)0.0 : (wmr_real_t)1.5; break;
    default: c->accel_estimator = 7; break;
    }
}
static void corrupt_roc(wmr_roc_config_t *c)
{
    switch (rint_below(3)) {
    case 0: c->alpha = (wmr_real_t)1.0; break;
    case 1: c->phi = (wmr_real_t)-1.0; break;
    default: c->eps = (wmr_real_t)NAN; break;
    }
}
static void corrupt_asmc(wmr_asmc_config_t *c)
{
    switch (rint_below(3)) {
    case 0: c->gamma = (wmr_real_t)-1.0; break;
    case 1: c->gain0 = (wmr_real_t)-0.5; break;
    default: c->eps = (wmr_real_t)0.0; break;
    }
}

static int all_finite(const wmr_real_t *x, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (!isfinite(x[i])) {
            return 0;
        }
    }
    return 1;
}

#define COMMON_STATE_FINITE(s)                                                               \
    (all_finite((s)->p12, 5) && all_finite((s)->p22, 5) && all_finite((s)->q_prev, 5)        \
     && all_finite((s)->qdot_prev, 5) && all_finite((s)->qdot_prev2, 5)                      \
     && all_finite((s)->u_prev, 5) && all_finite((s)->H1hat, 5) && isfinite((s)->gain)       \
     && isfinite((s)->s_norm) && isfinite((s)->u_discarded) && all_finite((s)->tau, 2))

static int state_finite_tdc(const wmr_tdc_state_t *s) { return COMMON_STATE_FINITE(s); }
static int state_finite_roc(const wmr_roc_state_t *s) { return COMMON_STATE_FINITE(s); }
static int state_finite_asmc(const wmr_asmc_state_t *s) { return COMMON_STATE_FINITE(s); }
static int state_finite_tdroc(const wmr_tdroc_state_t *s)
{
    return COMMON_STATE_FINITE(s) && all_finite(s->omega_ring, 2 * WMR_MAX_WINDOW)
        && isfinite(s->minv_norm);
}

/* A corrupted state, magic intact: 1..3 random bits flipped outside magic. corrupt_state_X
   returns the status the step must give (0: any documented one). */
static void flip_bits(unsigned char *bytes, size_t size, size_t magic_at)
{
    int k, flips = 1 + rint_below(3);
    for (k = 0; k < flips; ++k) {
        size_t at;
        do {
            at = (size_t)rint_below((int)size);
        } while (at >= magic_at && at < magic_at + sizeof(long));
        bytes[at] ^= (unsigned char)(1u << rint_below(8));
    }
}
#define DEFINE_CORRUPT_STATE(X)                                                                 \
    static int corrupt_state_##X(wmr_##X##_state_t *s)                                          \
    {                                                                                           \
        flip_bits((unsigned char *)s, sizeof(*s), offsetof(wmr_##X##_state_t, magic));         \
        return 0;                                                                               \
    }
DEFINE_CORRUPT_STATE(tdc)
DEFINE_CORRUPT_STATE(roc)
DEFINE_CORRUPT_STATE(asmc)
static int random_int(void)
{
    switch (rint_below(4)) {
    case 0: return rint_below(2 * WMR_MAX_WINDOW + 4) - 2;  /* near the range */
    case 1: return rint_below(2) ? INT_MAX : INT_MIN;
    default: return (int)(uint32_t)next_u64();
    }
}
static int corrupt_state_tdroc(wmr_tdroc_state_t *s)
{
    if (rint_below(2)) {
        flip_bits((unsigned char *)s, sizeof(*s), offsetof(wmr_tdroc_state_t, magic));
    } else if (rint_below(2)) {
        s->omega_head = random_int();
    } else {
        s->omega_count = random_int();
    }
    /* an index out of its range: the step must refuse the state (with this status, or
       CONFIG_CHANGED if a flipped bit is also in the kept configuration, compared first) */
    if (s->omega_head < 0 || s->omega_head >= WMR_MAX_WINDOW || s->omega_count < 0
        || s->omega_count > WMR_MAX_WINDOW + 1) {
        return WMR_ERR_NOT_INITIALISED;
    }
    return 0;
}

/* The motion the controller sees: a random walk with references near it. */
typedef struct {
    wmr_real_t *q, *qdot, *q_des, *qdot_des, *qddot_des; /* malloc'ed, 5 each */
} inputs_t;

static wmr_real_t *alloc_real(int n)
{
    wmr_real_t *p = (wmr_real_t *)malloc((size_t)n * sizeof(wmr_real_t));
    if (p == 0) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
    return p;
}

static void *alloc_bytes(size_t n)
{
    void *p = malloc(n);
    if (p == 0) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
    return p;
}

static void walk(inputs_t *in, double h)
{
    int i;
    for (i = 0; i < 5; ++i) {
        double qd = (double)in->qdot[i] + unif(-0.2, 0.2);
        double q = (double)in->q[i] + qd * h;
        if (fabs(q) > 1.0e4 || !isfinite(q)) {
            q = unif(-1.0, 1.0);
        }
        if (fabs(qd) > 50.0 || !isfinite(qd)) {
            qd = unif(-1.0, 1.0);
        }
        in->q[i] = (wmr_real_t)q;
        in->qdot[i] = (wmr_real_t)qd;
        in->q_des[i] = (wmr_real_t)(q + unif(-0.2, 0.2));
        in->qdot_des[i] = (wmr_real_t)(qd + unif(-0.5, 0.5));
        in->qddot_des[i] = (wmr_real_t)unif(-5.0, 5.0);
    }
}

typedef struct {
    long steps, ok, saturated, errors, nonfinite_output, reinits, bad_inits, bad_config, bad_input,
        wild_input, null_calls, magic_calls, stretched, stretched_rejected, corrupt_calls,
        corrupt_refused;
} stats_t;

/* One runner per controller; X is the name, e.g. tdroc. */
#define DEFINE_RUNNER(X)                                                                        \
    static void run_##X(int form, long steps, stats_t *st)                                      \
    {                                                                                           \
        wmr_##X##_config_t *cfg = (wmr_##X##_config_t *)alloc_bytes(sizeof(*cfg));              \
        wmr_##X##_config_t *bad = (wmr_##X##_config_t *)alloc_bytes(sizeof(*bad));              \
        wmr_##X##_state_t *state = (wmr_##X##_state_t *)alloc_bytes(sizeof(*state));            \
        wmr_##X##_state_t *before = (wmr_##X##_state_t *)alloc_bytes(sizeof(*before));          \
        wmr_real_t *tau = alloc_real(2);                                                        \
        inputs_t in;                                                                            \
        long k, until_reinit = 0;                                                               \
        int i;                                                                                  \
        in.q = alloc_real(5);                                                                   \
        in.qdot = alloc_real(5);                                                                \
        in.q_des = alloc_real(5);                                                               \
        in.qdot_des = alloc_real(5);                                                            \
        in.qddot_des = alloc_real(5);                                                           \
        for (i = 0; i < 5; ++i) {                                                               \
            in.q[i] = in.qdot[i] = (wmr_real_t)0.0;                                             \
        }                                                                                       \
        memset(state, 0x5a, sizeof(*state));                                                    \
        for (k = 0; k < steps; ++k) {                                                           \
            int status, expected = 1, mode, corrupted = 0;                                      \
            const wmr_##X##_config_t *use = cfg;                                                \
            const wmr_real_t *args[5];                                                          \
            wmr_##X##_state_t *target = state;                                                  \
            wmr_real_t *tau_arg = tau;                                                          \
            wmr_real_t saved = (wmr_real_t)0.0;                                                 \
            int saved_which = -1, saved_index = 0;                                              \
            if (until_reinit-- <= 0) {                                                          \
                /* A new random configuration; now and then an invalid one first. */            \
                if (rint_below(20) == 0) {                                                      \
                    FILL_BASE(cfg, form);                                                       \
                    extra_##X(cfg);                                                             \
                    if (rint_below(2)) {                                                        \
                        CORRUPT_BASE(cfg, rint_below(10));                                      \
                    } else {                                                                    \
                        corrupt_##X(cfg);                                                       \
                    }                                                                           \
                    memcpy(before, state, sizeof(*state));                                      \
                    status = wmr_##X##_init(state, cfg);                                        \
                    if (status >= 0 || memcmp(before, state, sizeof(*state)) != 0) {            \
                        violation("init accepted a bad config or wrote the state", #X, form, k, \
                                  status);                                                      \
                    }                                                                           \
                    st->bad_inits += 1;                                                         \
                }                                                                               \
                FILL_BASE(cfg, form);                                                           \
                extra_##X(cfg);                                                                 \
                if (rint_below(8) == 0) {                                                       \
                    STRETCH(cfg);                                                               \
                    st->stretched += 1;                                                         \
                    memcpy(before, state, sizeof(*state));                                      \
                    status = wmr_##X##_init(state, cfg);                                        \
                    if (status != WMR_OK) {                                                     \
                        st->stretched_rejected += 1;                                            \
                        if (memcmp(before, state, sizeof(*state)) != 0) {                       \
                            violation("init failed but wrote the state", #X, form, k, status);  \
                        }                                                                       \
                        FILL_BASE(cfg, form);                                                   \
                        extra_##X(cfg);                                                         \
                    }                                                                           \
                }                                                                               \
                status = wmr_##X##_init(state, cfg);                                            \
                if (status != WMR_OK) {                                                         \
                    violation("init rejected a valid config", #X, form, k, status);             \
                }                                                                               \
                until_reinit = 20 + rint_below(380);                                            \
                st->reinits += 1;                                                               \
            }                                                                                   \
            walk(&in, (double)cfg->h);                                                          \
            args[0] = in.q;                                                                     \
            args[1] = in.qdot;                                                                  \
            args[2] = in.q_des;                                                                 \
            args[3] = in.qdot_des;                                                              \
            args[4] = in.qddot_des;                                                             \
            mode = rint_below(1000);                                                            \
            if (mode < 30) { /* wild but valid values */                                        \
                for (i = 0; i < 5; ++i) {                                                       \
                    wmr_real_t *v = (wmr_real_t *)args[rint_below(5)];                          \
                    v[rint_below(5)] = wild();                                                  \
                }                                                                               \
                st->wild_input += 1;                                                            \
            } else if (mode < 60) { /* one invalid entry */                                     \
                wmr_real_t x = extreme();                                                       \
                saved_which = rint_below(5);                                                    \
                saved_index = rint_below(5);                                                    \
                saved = args[saved_which][saved_index];                                         \
                ((wmr_real_t *)args[saved_which])[saved_index] = x;                             \
                if (!isfinite(x) || fabs((double)x) > 1.0e6) {                                  \
                    expected = saved_which < 2 ? WMR_ERR_BAD_MEASUREMENT : WMR_ERR_BAD_REFERENCE; \
                }                                                                               \
                st->bad_input += 1;                                                             \
            } else if (mode < 75) { /* a corrupted configuration for this step only */          \
                memcpy(bad, cfg, sizeof(*cfg));                                                 \
                if (rint_below(2)) {                                                            \
                    CORRUPT_BASE(bad, rint_below(10));                                          \
                } else {                                                                        \
                    corrupt_##X(bad);                                                           \
                }                                                                               \
                use = bad;                                                                      \
                expected = 0; /* some error: the exact code depends on the field */            \
                st->bad_config += 1;                                                            \
            } else if (mode < 80) { /* a NULL argument */                                       \
                int which = rint_below(8);                                                      \
                if (which == 0) target = 0;                                                     \
                else if (which == 1) use = 0;                                                   \
                else if (which == 7) tau_arg = 0;                                               \
                else args[which - 2] = 0;                                                       \
                expected = WMR_ERR_NULL_POINTER;                                                \
                st->null_calls += 1;                                                            \
            } else if (mode < 85) { /* wrong magic */                                           \
                state->magic ^= 0x10;                                                           \
                expected = WMR_ERR_NOT_INITIALISED;                                             \
                st->magic_calls += 1;                                                           \
            } else if (mode < 95) { /* a corrupted state, magic intact; then a new _init */   \
                corrupted = 1;                                                                  \
                expected = corrupt_state_##X(state);                                            \
                st->corrupt_calls += 1;                                                         \
                until_reinit = 0;                                                               \
            }                                                                                   \
            memcpy(before, state, sizeof(*state));                                              \
            tau[0] = (wmr_real_t)1234.5;                                                        \
            tau[1] = (wmr_real_t)-678.25;                                                       \
            status = wmr_##X##_step(target, use, args[0], args[1], args[2], args[3], args[4],   \
                                    tau_arg);                                                   \
            st->steps += 1;                                                                     \
            if (expected == WMR_ERR_NOT_INITIALISED) {                                          \
                state->magic ^= 0x10;                                                           \
                before->magic ^= 0x10;                                                          \
            }                                                                                   \
            if (status < 0) {                                                                   \
                st->errors += 1;                                                                \
                if (status == WMR_ERR_NONFINITE_OUTPUT) st->nonfinite_output += 1;              \
                if (memcmp(before, state, sizeof(*state)) != 0) {                               \
                    violation("error status but the state changed", #X, form, k, status);       \
                }                                                                               \
                if (tau[0] != (wmr_real_t)1234.5 || tau[1] != (wmr_real_t)-678.25) {            \
                    violation("error status but tau changed", #X, form, k, status);             \
                }                                                                               \
                /* a corrupted state must fail; its kept configuration is compared first */ \
                if (expected < 0 && status != expected && !corrupted) {                         \
                    violation("wrong error code", #X, form, k, status);                         \
                }                                                                               \
                st->corrupt_refused += corrupted && status == WMR_ERR_NOT_INITIALISED;          \
            } else if (corrupted) {                                                             \
                /* whatever the corrupted reals made of it: documented, finite, clipped */      \
                if (expected < 0 || (status != WMR_OK && status != WMR_WARN_SATURATED)          \
                    || !isfinite(tau[0]) || !isfinite(tau[1])                                   \
                    || fabs((double)tau[0]) > (double)cfg->tau_max                              \
                    || fabs((double)tau[1]) > (double)cfg->tau_max) {                           \
                    violation("corrupted state: bad success", #X, form, k, status);             \
                }                                                                               \
                st->ok += 1;                                                                    \
            } else {                                                                            \
                if (expected <= 0) {                                                            \
                    violation("bad input accepted", #X, form, k, status);                       \
                }                                                                               \
                if (status != WMR_OK && status != WMR_WARN_SATURATED) {                         \
                    violation("unknown status", #X, form, k, status);                           \
                }                                                                               \
                st->ok += 1;                                                                    \
                st->saturated += status == WMR_WARN_SATURATED;                                  \
                if (!isfinite(tau[0]) || !isfinite(tau[1]) || fabs((double)tau[0]) > (double)cfg->tau_max \
                    || fabs((double)tau[1]) > (double)cfg->tau_max) {                           \
                    violation("tau not finite or beyond tau_max", #X, form, k, status);         \
                }                                                                               \
                if (state->tau[0] != tau[0] || state->tau[1] != tau[1]                          \
                    || !state_finite_##X(state)) {                                              \
                    violation("state not finite after success", #X, form, k, status);           \
                }                                                                               \
            }                                                                                   \
            if (saved_which >= 0) {                                                             \
                ((wmr_real_t *)args[saved_which])[saved_index] = saved;                         \
            }                                                                                   \
            if (mode < 30) { /* back to a plausible motion after wild values */                 \
                for (i = 0; i < 5; ++i) in.q[i] = in.qdot[i] = (wmr_real_t)0.0;                 \
            }                                                                                   \
        }                                                                                       \
        free(cfg);                                                                              \
        free(bad);                                                                              \
        free(state);                                                                            \
        free(before);                                                                           \
        free(tau);                                                                              \
        free(in.q);                                                                             \
        free(in.qdot);                                                                          \
        free(in.q_des);                                                                         \
        free(in.qdot_des);                                                                      \
        free(in.qddot_des);                                                                     \
    }

DEFINE_RUNNER(tdc)
DEFINE_RUNNER(tdroc)
DEFINE_RUNNER(roc)
DEFINE_RUNNER(asmc)

/* A parameter: mostly a plausible robot scaled by up to 1e+-3, sometimes extreme. */
static wmr_real_t fd_param(double nominal)
{
    const int pick = rint_below(100);
    if (pick < 90) {
        return (wmr_real_t)(nominal * pow(10.0, unif(-3.0, 3.0)));
    }
    if (pick < 93) {
        return (wmr_real_t)0.0;
    }
    if (pick < 96) {
        return (wmr_real_t)(-nominal);
    }
    return extreme();
}

static wmr_real_t fd_value(double range)
{
    return rint_below(50) ? (wmr_real_t)unif(-range, range) : extreme();
}

static void run_forward_dynamics(int minimal, long calls, stats_t *st)
{
    const char *name = minimal ? "minimal_forward_dynamics" : "forward_dynamics";
    const int n_rates = minimal ? 2 : 5, n_out = minimal ? 2 : 5;
    wmr_params_t *p = (wmr_params_t *)alloc_bytes(sizeof(*p));
    wmr_real_t *q = alloc_real(5), *rates = alloc_real(n_rates), *tau = alloc_real(2);
    wmr_real_t *out = alloc_real(n_out);
    long k;
    int i;
    for (k = 0; k < calls; ++k) {
        int status, nonfinite_read;
        p->m = fd_param(36.0);
        p->Iz = fd_param(5.72);
        p->K = rint_below(2) ? fd_param(0.34) : -fd_param(0.34);
        p->Iw = fd_param(0.07);
        p->r = fd_param(0.096);
        p->b = fd_param(0.414);
        p->d = rint_below(2) ? fd_param(0.12) : -fd_param(0.12);
        for (i = 0; i < 5; ++i) q[i] = fd_value(10.0);
        for (i = 0; i < n_rates; ++i) rates[i] = fd_value(rint_below(10) ? 20.0 : 1.0e6);
        for (i = 0; i < 2; ++i) tau[i] = fd_value(rint_below(10) ? 50.0 : 1.0e6);
        for (i = 0; i < n_out; ++i) out[i] = (wmr_real_t)42.0;
        nonfinite_read = !isfinite(p->m) || !isfinite(p->Iz) || !isfinite(p->K)
            || !isfinite(p->Iw) || !isfinite(p->r) || !isfinite(p->b) || !isfinite(p->d)
            || !isfinite(tau[0]) || !isfinite(tau[1]);
        if (minimal) {
            nonfinite_read = nonfinite_read || !isfinite(rates[0]) || !isfinite(rates[1]);
            status = wmr_minimal_forward_dynamics(p, q, rates, tau, out);
        } else {
            nonfinite_read = nonfinite_read || !isfinite(q[2]) || !isfinite(rates[3])
                || !isfinite(rates[4]);
            status = wmr_forward_dynamics(p, q, rates, tau, out);
        }
        st->steps += 1;
        if (status == WMR_OK) {
            st->ok += 1;
            if (!all_finite(out, n_out)) {
                violation("WMR_OK with a non-finite output", name, 0, k, status);
            }
        } else {
            st->errors += 1;
            if (status == WMR_ERR_NONFINITE_OUTPUT) st->nonfinite_output += 1;
            if (status != WMR_ERR_NONFINITE_INPUT && status != WMR_ERR_BAD_PARAMS
                && status != WMR_ERR_NONFINITE_OUTPUT) {
                violation("unexpected status", name, 0, k, status);
            }
            for (i = 0; i < n_out; ++i) {
                if (out[i] != (wmr_real_t)42.0) {
                    violation("error status but the output changed", name, 0, k, status);
                    break;
                }
            }
        }
        if (nonfinite_read && status != WMR_ERR_NONFINITE_INPUT) {
            violation("non-finite input not reported", name, 0, k, status);
        }
    }
    printf("RESULT %s model calls=%ld ok=%ld errors=%ld nonfinite_output=%ld\n", name,
           st->steps, st->ok, st->errors, st->nonfinite_output);
    free(p);
    free(q);
    free(rates);
    free(tau);
    free(out);
}

int main(int argc, char **argv)
{
    long steps = argc > 2 ? atol(argv[2]) : 100000;
    long fd_calls = argc > 3 ? atol(argv[3]) : 100000;
    int form;
    rng = argc > 1 ? strtoull(argv[1], 0, 10) : 1;
    if (rng == 0) {
        rng = 88172645463325252ULL; /* xorshift must not start at 0 */
    }
    for (form = 0; form < 2; ++form) {
        const char *fname = form == WMR_FORMULATION_PAPER ? "paper" : "minimal";
#define RUN(X)                                                                                  \
        do {                                                                                    \
            stats_t st;                                                                         \
            memset(&st, 0, sizeof(st));                                                         \
            run_##X(form, steps, &st);                                                          \
            printf("RESULT %s %s steps=%ld ok=%ld saturated=%ld errors=%ld nonfinite_output=%ld " \
                   "reinits=%ld bad_inits=%ld bad_config=%ld bad_input=%ld wild_input=%ld "     \
                   "null_calls=%ld magic_calls=%ld stretched=%ld stretched_rejected=%ld "      \
                   "corrupt_calls=%ld corrupt_refused=%ld\n",                                   \
                   #X, fname, st.steps, st.ok, st.saturated, st.errors, st.nonfinite_output,   \
                   st.reinits, st.bad_inits, st.bad_config, st.bad_input, st.wild_input,       \
                   st.null_calls, st.magic_calls, st.stretched, st.stretched_rejected,         \
                   st.corrupt_calls, st.corrupt_refused);                                      \
        } while (0)
        RUN(tdc);
        RUN(tdroc);
        RUN(roc);
        RUN(asmc);
#undef RUN
    }
    {
        stats_t st;
        memset(&st, 0, sizeof(st));
        run_forward_dynamics(0, fd_calls, &st);
        memset(&st, 0, sizeof(st));
        run_forward_dynamics(1, fd_calls, &st);
    }
    printf("VIOLATIONS %ld\n", violations);
    return violations == 0 ? 0 : 1;
}
