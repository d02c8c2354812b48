/* Throughput of independent 256-bit square roots and divisions on one
 * core, in nanoseconds and in FMAs (how many independent 256-bit FMAs
 * the same time issues): what the light loop's correctly rounded roots
 * and quotients cost beside its multiply-adds (docs/PERFORMANCE.md, "What
 * bounds the targets not met"). Build and run lines in docs/benchmarks.md. */
#include <immintrin.h>
#include <stdio.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

/* Keeps twelve independent values in registers across the loop (enough
 * to fill two FMA pipes of latency 4 or more). */
#define KEEP(a, b, c, d, e, f, g, h, p, q, r, s) \
    __asm__ volatile("" : "+x"(a), "+x"(b), "+x"(c), "+x"(d), "+x"(e), "+x"(f), "+x"(g), "+x"(h), \
                     "+x"(p), "+x"(q), "+x"(r), "+x"(s))
#define EACH(op) \
    a = op(a), b = op(b), c = op(c), d = op(d), e = op(e), f = op(f), g = op(g), h = op(h), \
    p = op(p), q = op(q), r = op(r), s = op(s)
#define RECIP(x) _mm256_div_ps(one, x)
#define STEP(x) _mm256_fmadd_ps(x, m, k)

/* Seconds per instruction of `op` on twelve independent chains, best of
 * 5 runs of n iterations (one function per operation, so that each loop
 * holds nothing but the twelve instructions and its counter). */
#define PER_OP(name, op)                                                                        \
    static double name(long n) {                                                                \
        double best = 1e9;                                                                      \
        for (int rep = 0; rep < 5; rep++) {                                                     \
            __m256 a = _mm256_set1_ps(1.5f), b = _mm256_set1_ps(2.5f), c = _mm256_set1_ps(3.5f), \
                   d = _mm256_set1_ps(4.5f), e = _mm256_set1_ps(5.5f), f = _mm256_set1_ps(6.5f), \
                   g = _mm256_set1_ps(7.5f), h = _mm256_set1_ps(8.5f), p = _mm256_set1_ps(1.25f), \
                   q = _mm256_set1_ps(2.25f), r = _mm256_set1_ps(3.25f), s = _mm256_set1_ps(4.25f); \
            /* 1/x and √x stay in [1/8.5, 8.5]; x·m + k stays near x. */                        \
            const __m256 one = _mm256_set1_ps(1.0f), m = _mm256_set1_ps(0.999999f),            \
                         k = _mm256_set1_ps(1e-7f);                                             \
            (void)one, (void)m, (void)k;                                                        \
            double t = now();                                                                   \
            for (long i = 0; i < n; i++) {                                                      \
                EACH(op);                                                                       \
                KEEP(a, b, c, d, e, f, g, h, p, q, r, s);                                       \
            }                                                                                   \
            t = (now() - t) / (12.0 * n);                                                       \
            if (t < best) best = t;                                                             \
        }                                                                                       \
        return best;                                                                            \
    }

PER_OP(sqrt_time, _mm256_sqrt_ps)
PER_OP(div_time, RECIP)
PER_OP(fma_time, STEP)

int main(void) {
    long n = 50000000;
    double fma = fma_time(4 * n), sqrt = sqrt_time(n), div = div_time(n);
    printf("vsqrtps ymm  %.3f ns an instruction, %.1f FMAs' time\n", sqrt * 1e9, sqrt / fma);
    printf("vdivps ymm   %.3f ns an instruction, %.1f FMAs' time\n", div * 1e9, div / fma);
    printf("vfmadd ymm   %.3f ns an instruction\n", fma * 1e9);
    return 0;
}
