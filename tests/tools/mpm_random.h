/* Reproducible pseudo-random numbers for tests: splitmix64 (Steele, Lea and Flood 2014). A
 * fixed seed makes every run test the same particles and points. */
#ifndef MPM_RANDOM_H
#define MPM_RANDOM_H

#include <stdint.h>

/* The splitmix64 finaliser of z + golden gamma: a well-mixed hash of z. */
static inline uint64_t mpm_test_mix(uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/* Next uniform double in [0, 1) of the stream *state. */
static inline double mpm_test_uniform(uint64_t *state) {
  const uint64_t z = mpm_test_mix(*state);
  *state += 0x9e3779b97f4a7c15ull;
  return (double)(z >> 11) * 0x1.0p-53;
}

#endif
