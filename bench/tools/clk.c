/* The core clock from a chain of dependent integer adds (one cycle each,
 * 4 a loop iteration): what docs/PERFORMANCE.md converts times into cycles
 * with. Build and run lines there. */
#include <stdio.h>
#include <time.h>

int main(void) {
    struct timespec a, b;
    unsigned long x = 1, n = 2000000000UL;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (unsigned long i = 0; i < n; i++) {
        __asm__ volatile("add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0" : "+r"(x));
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    double t = (b.tv_sec - a.tv_sec) + (b.tv_nsec - a.tv_nsec) * 1e-9;
    printf("%.3f GHz (4 dependent adds an iteration)\n", 4.0 * n / t / 1e9);
    return x == 0;
}
