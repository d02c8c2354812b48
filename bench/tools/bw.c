/* Memory bandwidth of this machine: best of 10 passes over 64 MB arrays
 * (read with a vectorized sum, copy, write), with OMP_NUM_THREADS threads.
 * Cited in docs/PERFORMANCE.md; build and run lines there. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <omp.h>
#define N (64*1024*1024/4)  /* 64 MB per array of floats */
static double now(){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+t.tv_nsec*1e-9;}
int main(){
  float *a=aligned_alloc(64,N*4),*b=aligned_alloc(64,N*4);
  #pragma omp parallel for
  for(long i=0;i<N;i++){a[i]=i*1e-3f;b[i]=0;}
  double best_r=1e9,best_c=1e9,best_w=1e9; volatile float sink=0;
  for(int rep=0;rep<10;rep++){
    double t=now(); float s=0;
    #pragma omp parallel for reduction(+:s)
    for(long i=0;i<N;i++) s+=a[i];
    t=now()-t; sink+=s; if(t<best_r)best_r=t;
    t=now();
    #pragma omp parallel for
    for(long i=0;i<N;i++) b[i]=a[i];
    t=now()-t; if(t<best_c)best_c=t;
    t=now();
    #pragma omp parallel for
    for(long i=0;i<N;i++) b[i]=1.0f;
    t=now()-t; if(t<best_w)best_w=t;
  }
  printf("threads %d: read %.1f GB/s, copy %.1f GB/s (read+write), write %.1f GB/s\n", omp_get_max_threads(),
    N*4/best_r/1e9, 2.0*N*4/best_c/1e9, N*4/best_w/1e9);
  return 0;
}
