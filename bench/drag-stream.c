/* The drag-only update of `scg bench drag` written as a plain C loop over the same data
 * (positions and velocities as packed xyz triples, two drag factors per particle: 112 bytes
 * read and written per particle-step), to measure what the machine's memory streams:
 *
 *   gcc -O3 -march=native -fopenmp bench/drag-stream.c -o /tmp/drag-stream
 *   OMP_NUM_THREADS=2 /tmp/drag-stream 1000000 300     # particles, steps
 *
 * Prints particle-steps/s and the bandwidth they imply. The flow is a planar vortex-like
 * linear field; the arithmetic is not scg's to the bit, only its memory traffic is.
 */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <omp.h>
int main(int argc,char**argv){
  long n=atol(argv[1]); int steps=atoi(argv[2]);
  double *x=aligned_alloc(64,n*3*8),*v=aligned_alloc(64,n*3*8),*g=aligned_alloc(64,n*2*8);
  for(long i=0;i<3*n;i++){x[i]=i*1e-9;v[i]=1.0;} for(long i=0;i<2*n;i++) g[i]=0.5;
  double dt=1e-5;
  struct timespec t0,t1; clock_gettime(CLOCK_MONOTONIC,&t0);
  for(int s=0;s<steps;s++){
    #pragma omp parallel for schedule(static)
    for(long i=0;i<n;i++){
      double gain=g[2*i], relax=g[2*i+1];
      for(int k=0;k<3;k++){ double xm=x[3*i+k]+v[3*i+k]*0.5*dt; double u=-xm*31.4; double dv=v[3*i+k]-u; x[3*i+k]+=u*dt+dv*relax; v[3*i+k]-=dv*gain; }
    }
  }
  clock_gettime(CLOCK_MONOTONIC,&t1);
  double t=(t1.tv_sec-t0.tv_sec)+(t1.tv_nsec-t0.tv_nsec)*1e-9;
  printf("n=%ld: %.3e particle-steps/s, %.1f GB/s (112 B each)\n",n,n*(double)steps/t,n*(double)steps/t*112e-9);
  return x[5]>1e300;
}
