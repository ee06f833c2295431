#pragma once
// Vector code paths for the hot loops of plugins.
//
// TS_VECTOR_CLONES before a function compiles it several times on x86-64
// Linux: for the baseline instruction set (SSE2) and for wider ones (GCC:
// x86-64-v3, AVX2 and FMA, and x86-64-v4, AVX-512; Clang: AVX2); the
// loader picks the version the processor runs (an ifunc), so one build
// runs everywhere and uses the widest vectors it can. (Clang 14 picks a
// clone by feature names only: with GCC's `arch=` levels it always ran the
// baseline.) The SDK's CMake target compiles with -ffp-contract=off, so
// that no a * b + c is contracted into an FMA, and elementwise vector
// arithmetic rounds as the scalar one: all versions give the same bits.
// Write such loops without calls and without branches the compiler cannot
// turn into selects, and mark them `#pragma omp simd` (the SDK's CMake
// target adds -fopenmp-simd).
#if defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define TS_VECTOR_CLONES __attribute__((target_clones("default", "avx2")))
#elif defined(__GNUC__) && defined(__x86_64__) && defined(__linux__)
#define TS_VECTOR_CLONES __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#else
#define TS_VECTOR_CLONES
#endif
