/* Test plant for the initial-position engines (initpos, polarity, pulse3): a standing IPMSM fed
 * by an ideal inverter, in double.
 *  - State: the rotor-frame flux linkage psi_dq; the rotor does not move.
 *  - Currents: linear machine i_d = (psi_d - psi_pm) / Ld, i_q = psi_q / Lq; saturating machine
 *    from the closed-form current(psi) of machines.md (sun_i_of_psi in estim_test.h), so no map
 *    inversion is needed and the plant is independent of the firmware's bilinear map.
 *  - Voltage: phase-to-midpoint (d - 0.5) vdc, Clarke (the common mode drops out: line-to-
 *    neutral), Park at the rotor angle; dpsi/dt = u - Rs i(psi), RK4 with PLANT_SUB substeps.
 *  - Delay: the duties returned at call k act on [k+1, k+2]: plant_run advances [k, k+1] with
 *    the duties of call k-1 and only then makes the new duties pending.
 *  - Noise (optional): Gaussian, sigma per alpha and beta sample, seeded LCG + Box-Muller. */
#ifndef IP_PLANT_H
#define IP_PLANT_H
#include "estim_test.h"

#include "mc/initpos.h"

#define PLANT_SUB 16
#define SUN_IRATED 13.29   /* per-unit base of Table 7.1 [A] */
#define VDC 300.0

typedef struct {
    int sat;                 /* 0: constant Ld, Lq; 1: saturating analytic model */
    double th;               /* rotor angle [rad] */
    double psi[2];
    double ld, lq, psi_pm, rs, ts;
    mc_abc_t pending;        /* duties acting on the interval being simulated */
    double noise;            /* [A] rms per component */
    uint64_t rng;
    double i_phase_peak;     /* max |phase current| seen [A] */
    int calls;
    int no_delay;            /* negative control: apply the duties in the same period */
} plant_t;

static inline void plant_i(const plant_t *p, const double psi[2], double i[2])
{
    if (p->sat) {
        double j[4];
        sun_i_of_psi(psi[0], psi[1], i, j);
    } else {
        i[0] = (psi[0] - p->psi_pm) / p->ld;
        i[1] = psi[1] / p->lq;
    }
}

static inline void plant_init(plant_t *p, int sat, double th_deg)
{
    memset(p, 0, sizeof *p);
    p->sat = sat;
    p->th = th_deg * DEG;
    p->ld = SUN_LD;
    p->lq = SUN_LQ;
    p->psi_pm = SUN_PSI;
    p->rs = SUN_RS;
    p->ts = SUN_TS;
    p->rng = 12345u;
    if (sat) {
        sun_psi_of_i(0.0, 0.0, p->psi);
    } else {
        p->psi[0] = SUN_PSI;
        p->psi[1] = 0.0;
    }
}

static inline double gauss(uint64_t *st)
{
    double u1 = urand(st, 1e-12, 1.0), u2 = urand(st, 0.0, 1.0);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * PI_D * u2);
}

static inline void plant_iab(const plant_t *p, double iab[2])
{
    double i[2];
    plant_i(p, p->psi, i);
    dpark_inv(i, p->th, iab);
}

static inline mc_ab_t plant_sample(plant_t *p)
{
    double iab[2];
    plant_iab(p, iab);
    mc_ab_t s;
    double na = 0.0, nb = 0.0;
    if (p->noise > 0.0) {
        na = p->noise * gauss(&p->rng);
        nb = p->noise * gauss(&p->rng);
    }
    s.alpha = (float)(iab[0] + na);
    s.beta = (float)(iab[1] + nb);
    return s;
}

static inline void plant_deriv(const plant_t *p, const double psi[2], const double udq[2],
                               double dpsi[2])
{
    double i[2];
    plant_i(p, psi, i);
    dpsi[0] = udq[0] - p->rs * i[0];
    dpsi[1] = udq[1] - p->rs * i[1];
}

/* one period with duties d */
static inline void plant_advance(plant_t *p, mc_abc_t d, double vdc)
{
    double va = (d.a - 0.5) * vdc, vb = (d.b - 0.5) * vdc, vc = (d.c - 0.5) * vdc;
    double uab[2] = {(2.0 / 3.0) * (va - 0.5 * (vb + vc)), (vb - vc) / sqrt(3.0)}, udq[2];
    dpark(uab, p->th, udq);
    double h = p->ts / PLANT_SUB;
    for (int s = 0; s < PLANT_SUB; ++s) {
        double k1[2], k2[2], k3[2], k4[2], t[2];
        plant_deriv(p, p->psi, udq, k1);
        t[0] = p->psi[0] + 0.5 * h * k1[0];
        t[1] = p->psi[1] + 0.5 * h * k1[1];
        plant_deriv(p, t, udq, k2);
        t[0] = p->psi[0] + 0.5 * h * k2[0];
        t[1] = p->psi[1] + 0.5 * h * k2[1];
        plant_deriv(p, t, udq, k3);
        t[0] = p->psi[0] + h * k3[0];
        t[1] = p->psi[1] + h * k3[1];
        plant_deriv(p, t, udq, k4);
        p->psi[0] += h / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
        p->psi[1] += h / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
        double iab[2];
        plant_iab(p, iab);
        double ia = iab[0], ib = -0.5 * iab[0] + 0.5 * sqrt(3.0) * iab[1];
        double ic = -ia - ib;
        p->i_phase_peak = fmax(p->i_phase_peak, fmax(fabs(ia), fmax(fabs(ib), fabs(ic))));
    }
}

typedef mc_ip_status_t (*ip_step_fn)(void *eng, mc_ab_t i, float vdc, mc_abc_t *d);

/* Drive an engine until it leaves RUNNING (or max_calls); returns the number of calls. */
static inline int plant_run(plant_t *p, ip_step_fn f, void *eng, int max_calls,
                            mc_ip_status_t *st_out)
{
    mc_ip_status_t st = MC_IP_RUNNING;
    int n = 0;
    while (n < max_calls && st == MC_IP_RUNNING) {
        mc_ab_t i = plant_sample(p);
        mc_abc_t d;
        st = f(eng, i, (float)VDC, &d);
        if (p->no_delay) {
            plant_advance(p, d, VDC);
        } else {
            plant_advance(p, p->pending, VDC);   /* [k, k+1]: duties of call k-1 */
            p->pending = d;
        }
        ++n;
    }
    p->calls += n;
    *st_out = st;
    return n;
}

/* |a - b| modulo pi, in degrees */
static inline double err_mod_pi_deg(double a, double b)
{
    double e = remainder(a - b, PI_D);
    return fabs(e) / DEG;
}

static inline double err_mod_2pi_deg(double a, double b) { return fabs(wrapd(a - b)) / DEG; }

#endif
