/* Throughput and latency of 256-bit FMAs, square roots and divisions on
 * one core (512-bit ones when built with -DZMM and AVX-512): the units the
 * light loop's multiply-adds and its correctly rounded roots and
 * quotients run on (docs/PERFORMANCE.md, "What bounds the targets not
 * met", "Light pairs"). Throughput from twelve independent chains (more
 * than two FMA pipes of latency 4 need), latency from one chain, each
 * loop holding nothing but its operations and its counter; in ns and in
 * cycles of the clock given as the first argument (GHz, from clk.c).
 * Build and run lines in docs/benchmarks.md. */
#include <immintrin.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#ifdef ZMM
#define VEC __m512
#define OP(name) _mm512_##name
#define WIDTH "zmm"
#else
#define VEC __m256
#define OP(name) _mm256_##name
#define WIDTH "ymm"
#endif

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

#define KEEP12(a, b, c, d, e, f, g, h, p, q, r, s)                                              \
    __asm__ volatile("" : "+x"(a), "+x"(b), "+x"(c), "+x"(d), "+x"(e), "+x"(f), "+x"(g), "+x"(h), \
                     "+x"(p), "+x"(q), "+x"(r), "+x"(s))
#define EACH(op)                                                                              \
    a = op(a), b = op(b), c = op(c), d = op(d), e = op(e), f = op(f), g = op(g), h = op(h),   \
    p = op(p), q = op(q), r = op(r), s = op(s)
#define RECIP(x) OP(div_ps)(one, x)
#define STEP(x) OP(fmadd_ps)(x, m, k)
/* 1/x and √x keep x in [1/8.5, 8.5]; x·m + k keeps it near x. */
#define CONSTANTS                                                                             \
    const VEC one = OP(set1_ps)(1.0f), m = OP(set1_ps)(0.999999f),                  \
                 k = OP(set1_ps)(1e-7f);                                                   \
    (void)one, (void)m, (void)k

/* Seconds an instruction of `op` on twelve independent chains, best of 5
 * runs of n iterations. Distinct starting values, so that the compiler
 * cannot merge the chains into one. */
#define THROUGHPUT(name, op)                                                                   \
    static double name(long n) {                                                               \
        double best = 1e9;                                                                     \
        for (int rep = 0; rep < 5; rep++) {                                                    \
            VEC a = OP(set1_ps)(1.5f), b = OP(set1_ps)(2.5f), c = OP(set1_ps)(3.5f), \
                   d = OP(set1_ps)(4.5f), e = OP(set1_ps)(5.5f), f = OP(set1_ps)(6.5f), \
                   g = OP(set1_ps)(7.5f), h = OP(set1_ps)(8.5f), p = OP(set1_ps)(1.25f), \
                   q = OP(set1_ps)(2.25f), r = OP(set1_ps)(3.25f), s = OP(set1_ps)(4.25f); \
            CONSTANTS;                                                                         \
            double t = now();                                                                  \
            for (long i = 0; i < n; i++) {                                                     \
                EACH(op);                                                                      \
                KEEP12(a, b, c, d, e, f, g, h, p, q, r, s);                                    \
            }                                                                                  \
            t = (now() - t) / (12.0 * n);                                                      \
            if (t < best) best = t;                                                            \
        }                                                                                      \
        return best;                                                                           \
    }

/* Seconds an instruction of `op` on one chain (each waits for the last). */
#define LATENCY(name, op)                                                                      \
    static double name(long n) {                                                               \
        double best = 1e9;                                                                     \
        for (int rep = 0; rep < 5; rep++) {                                                    \
            VEC a = OP(set1_ps)(1.5f);                                                   \
            CONSTANTS;                                                                         \
            double t = now();                                                                  \
            for (long i = 0; i < n; i++) {                                                     \
                a = op(a);                                                                     \
                __asm__ volatile("" : "+x"(a));                                                \
            }                                                                                  \
            t = (now() - t) / n;                                                               \
            if (t < best) best = t;                                                            \
        }                                                                                      \
        return best;                                                                           \
    }

THROUGHPUT(fma_throughput, STEP)
THROUGHPUT(sqrt_throughput, OP(sqrt_ps))
THROUGHPUT(div_throughput, RECIP)
LATENCY(fma_latency, STEP)
LATENCY(sqrt_latency, OP(sqrt_ps))
LATENCY(div_latency, RECIP)

int main(int argc, char **argv) {
    double ghz = argc > 1 ? atof(argv[1]) : 0.0;
    long n = 20000000;
    struct {
        const char *name;
        double throughput, latency;
    } rows[] = {
        {"vfmadd " WIDTH, fma_throughput(4 * n), fma_latency(4 * n)},
        {"vsqrtps " WIDTH, sqrt_throughput(n), sqrt_latency(n)},
        {"vdivps " WIDTH, div_throughput(n), div_latency(n)},
    };
    for (int i = 0; i < 3; i++) {
        printf("%-12s one every %.3f ns (%.1f FMAs' time), latency %.2f ns", rows[i].name,
               rows[i].throughput * 1e9, rows[i].throughput / rows[0].throughput,
               rows[i].latency * 1e9);
        if (ghz > 0)
            printf(": %.2f and %.1f cycles", rows[i].throughput * ghz * 1e9, rows[i].latency * ghz * 1e9);
        printf("\n");
    }
    return 0;
}
