/* The same scheme as rbhyst.solve.kernels.run with Chang's method, in plain C, for the
 * kernel benchmark (bench_kernel.py): Chang step, VRM update with the gap and the
 * antiderivative carried per element (seed eqs. 14-17), exact element work, input
 * energy, the trace bound on omega_max and the per-step state save. Reads the arrays
 * written by bench_kernel.py from stdin, runs `repeat` times, prints the best time
 * in seconds and writes the displacement history to stdout after it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { KB, F0, ALPHA, BETA1, BETA2, GAMMA1, GAMMA2, GAMMA3 };
enum { U, F, S, G, K, A, NS };

static int branch_eval(const double *p, double s, double u, double *c, double *kc, double *big) {
    double kb = p[KB], f0 = p[F0];
    *c = kb * u + s * f0;
    *kc = kb;
    *big = u * (0.5 * kb * u + s * f0);
    double b1 = p[BETA1], b2 = p[BETA2];
    if (b1 != 0.0 && b2 != 0.0) {
        double x = b2 * u;
        if (x > 700.0) return 0;
        double em = expm1(x);
        *c += b1 * em;
        *kc += b1 * b2 * (em + 1.0);
        if (fabs(x) < 1e-5)
            *big += b1 * u * x * (0.5 + x / 6.0);
        else
            *big += b1 * (em / b2 - u);
    }
    double g1 = p[GAMMA1], g2 = p[GAMMA2];
    if (g1 != 0.0 && g2 != 0.0) {
        double x = 0.5 * g2 * (u - p[GAMMA3]);
        double t = tanh(x);
        *c += 2.0 * g1 * t;
        *kc += g1 * g2 * (1.0 - t * t);
        double ax = fabs(x), lc;
        if (ax < 0.5) {
            double sh = sinh(0.5 * ax);
            lc = log1p(2.0 * sh * sh);
        } else {
            lc = ax + log1p(exp(-2.0 * ax)) - log(2.0);
        }
        *big += 4.0 * g1 / g2 * lc;
    }
    return 1;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(void) {
    int n, ne, repeat;
    double h;
    if (scanf("%d %d %d %lf", &n, &ne, &repeat, &h) != 4) return 1;
    double minv[3], b1[9], b2[9];
    for (int i = 0; i < 3; i++) scanf("%lf", &minv[i]);
    for (int i = 0; i < 9; i++) scanf("%lf", &b1[i]);
    for (int i = 0; i < 9; i++) scanf("%lf", &b2[i]);
    double *bvec = malloc(sizeof(double) * ne * 3), *mult = malloc(sizeof(double) * ne);
    double *par = malloc(sizeof(double) * ne * 16), *load = malloc(sizeof(double) * (n + 1) * 3);
    double *wgt = malloc(sizeof(double) * ne);
    for (int i = 0; i < ne * 3; i++) scanf("%lf", &bvec[i]);
    for (int i = 0; i < ne; i++) scanf("%lf", &mult[i]);
    for (int i = 0; i < ne * 16; i++) scanf("%lf", &par[i]);
    for (int i = 0; i < (n + 1) * 3; i++) scanf("%lf", &load[i]);
    for (int e = 0; e < ne; e++)
        wgt[e] = bvec[3 * e] * bvec[3 * e] * minv[0] + bvec[3 * e + 1] * bvec[3 * e + 1] * minv[1]
               + bvec[3 * e + 2] * bvec[3 * e + 2] * minv[2];
    double *out = malloc(sizeof(double) * (n + 1) * 3);
    double *es = malloc(sizeof(double) * ne * NS), *en = malloc(sizeof(double) * ne * NS);
    double *es_save = malloc(sizeof(double) * ne * NS), *kpeak = malloc(sizeof(double) * ne);
    double best = 1e30, e_hyst = 0.0, e_in = 0.0, lam_max = 0.0;
    for (int rep = 0; rep < repeat; rep++) {
        double d[3] = {0, 0, 0}, v[3] = {0, 0, 0}, a[3], d1[3], v1[3], a1[3], r[3];
        double d_save[3], v_save[3], a_save[3];
        for (int i = 0; i < 3; i++) a[i] = minv[i] * load[i];
        memset(es, 0, sizeof(double) * ne * NS);
        e_hyst = 0.0;
        e_in = 0.0;
        lam_max = 0.0;
        double t0 = now();
        for (int j = 0; j < n; j++) {
            memcpy(d_save, d, sizeof d);
            memcpy(v_save, v, sizeof v);
            memcpy(a_save, a, sizeof a);
            memcpy(es_save, es, sizeof(double) * ne * NS);
            const double *p1 = load + 3 * (j + 1), *p0 = load + 3 * j;
            for (int i = 0; i < 3; i++)
                d1[i] = d[i] + h * (b1[3 * i] * v[0] + b1[3 * i + 1] * v[1] + b1[3 * i + 2] * v[2])
                      + h * h * (b2[3 * i] * a[0] + b2[3 * i + 1] * a[1] + b2[3 * i + 2] * a[2]);
            r[0] = r[1] = r[2] = 0.0;
            double work = 0.0;
            for (int e = 0; e < ne; e++) {
                const double *b = bvec + 3 * e;
                double *st = es + NS * e, *sn = en + NS * e;
                double u = b[0] * d1[0] + b[1] * d1[1] + b[2] * d1[2];
                double du = u - st[U];
                if (du == 0.0) {
                    memcpy(sn, st, sizeof(double) * NS);
                    kpeak[e] = st[K];
                    continue;
                }
                double s = du > 0.0 ? 1.0 : -1.0;
                const double *p = par + 16 * e + (s > 0.0 ? 0 : 8);
                double alpha = p[ALPHA], g, kstart, a_start, c, kc, big;
                if (s != st[S]) {
                    if (!branch_eval(p, s, st[U], &c, &kc, &a_start)) return 2;
                    g = c - st[F];
                    kstart = kc + s * alpha * g;
                } else {
                    g = st[G];
                    kstart = st[K];
                    a_start = st[A];
                }
                double decay = exp(-alpha * fabs(du));
                if (!branch_eval(p, s, u, &c, &kc, &big)) return 2;
                double gn = g * decay, f = c - gn, k = kc + s * alpha * gn;
                double w = big - a_start + s * g * (decay - 1.0) / alpha;
                sn[U] = u; sn[F] = f; sn[S] = s; sn[G] = gn; sn[K] = k; sn[A] = big;
                kpeak[e] = kstart > k ? kstart : k;
                work += mult[e] * w;
                r[0] += mult[e] * b[0] * f;
                r[1] += mult[e] * b[1] * f;
                r[2] += mult[e] * b[2] * f;
            }
            double lam = 0.0;
            for (int e = 0; e < ne; e++) lam += mult[e] * (kpeak[e] > 0.0 ? kpeak[e] : 0.0) * wgt[e];
            if (lam > lam_max) lam_max = lam;
            for (int i = 0; i < 3; i++) {
                a1[i] = minv[i] * (p1[i] - r[i]);
                v1[i] = v[i] + 0.5 * h * (a[i] + a1[i]);
                e_in += 0.5 * (p0[i] + p1[i]) * (d1[i] - d[i]);
                d[i] = d1[i];
                v[i] = v1[i];
                a[i] = a1[i];
            }
            e_hyst += work;
            memcpy(es, en, sizeof(double) * ne * NS);
            if (!(isfinite(d[0]) && isfinite(d[1]) && isfinite(d[2]))) return 3;
            out[3 * (j + 1)] = d[0];
            out[3 * (j + 1) + 1] = d[1];
            out[3 * (j + 1) + 2] = d[2];
        }
        double dt = now() - t0;
        if (dt < best) best = dt;
        (void)d_save; (void)v_save; (void)a_save;
    }
    printf("%.9f %.17g %.17g %.17g\n", best, e_in, e_hyst, sqrt(lam_max) * h);
    for (int j = 1; j <= n; j++) printf("%.17g %.17g %.17g\n", out[3 * j], out[3 * j + 1], out[3 * j + 2]);
    return 0;
}
