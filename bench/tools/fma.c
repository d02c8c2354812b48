/* Throughput of independent 256-bit FMAs (10 chains per thread), with
 * OMP_NUM_THREADS threads: the FP peak docs/PERFORMANCE.md compares the
 * shading pass with. Build and run lines there. */
#include <stdio.h>
#include <time.h>
#include <immintrin.h>
#include <omp.h>
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+t.tv_nsec*1e-9;}
int main(){
  double best=1e9; long iters=200000000;
  for(int rep=0;rep<5;rep++){
    double t=now(); float out=0;
    #pragma omp parallel reduction(+:out)
    {
      __m256 a0=_mm256_set1_ps(1.0f),a1=a0,a2=a0,a3=a0,a4=a0,a5=a0,a6=a0,a7=a0,a8=a0,a9=a0;
      __m256 m=_mm256_set1_ps(0.999999f), c=_mm256_set1_ps(1e-7f);
      for(long i=0;i<iters;i++){
        a0=_mm256_fmadd_ps(a0,m,c);a1=_mm256_fmadd_ps(a1,m,c);a2=_mm256_fmadd_ps(a2,m,c);a3=_mm256_fmadd_ps(a3,m,c);a4=_mm256_fmadd_ps(a4,m,c);
        a5=_mm256_fmadd_ps(a5,m,c);a6=_mm256_fmadd_ps(a6,m,c);a7=_mm256_fmadd_ps(a7,m,c);a8=_mm256_fmadd_ps(a8,m,c);a9=_mm256_fmadd_ps(a9,m,c);
      }
      __m256 s=_mm256_add_ps(_mm256_add_ps(_mm256_add_ps(a0,a1),_mm256_add_ps(a2,a3)),_mm256_add_ps(_mm256_add_ps(a4,a5),_mm256_add_ps(_mm256_add_ps(a6,a7),_mm256_add_ps(a8,a9))));
      float o[8]; _mm256_storeu_ps(o,s); out+=o[0];
    }
    t=now()-t; if(t<best)best=t;
    if(out==12345)printf("x");
  }
  int n=omp_get_max_threads();
  printf("threads %d: %.2f G vfmadd256/s total (%.2f per core), %.0f GFLOP/s\n", n, n*iters*10/best/1e9, iters*10/best/1e9, n*iters*10*16/best/1e9);
}
