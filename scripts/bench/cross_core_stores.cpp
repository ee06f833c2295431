// Cost of updating arrays that the other core has just read, the pattern of
// the explicit loop on two threads: one thread reads the positions and
// velocities (x, v) of both plies of the hemisphere scene (2 x 2 886
// doubles, 721 cache lines), then the other updates them in place as the
// time integration does (v += a f, x += b v), one meeting point between.
// Prints, per way of storing, the update's time and the whole cycle's
// (read + update) in microseconds.
//
// Build and run (two cores):
//   g++ -O2 -march=native -fopenmp scripts/bench/cross_core_stores.cpp -o build/bench/cross_core_stores
//   build/bench/cross_core_stores [cycles]
#include <immintrin.h>
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

constexpr int kN = 2 * 1443 * 2;  // x and v of two plies of 481 nodes, 3 values per node: two arrays of kN / 2
constexpr double kA = 1e-9;

enum Way { Plain, PerArray, Prefetchw, CopyBack, Streaming, ReaderFlushes, kWays };
const char* const kNames[kWays] = {"ordinary stores, one loop",      "one loop per array",
                                   "prefetchw on every line first",  "private copy, memcpy back",
                                   "streaming (non-temporal) stores", "reader flushes its lines after reading"};

void update(Way way, int n, double* x, double* v, const double* f, double* xs, double* vs) {
  switch (way) {
    case Prefetchw:
      for (int i = 0; i < n; i += 8) {
        __builtin_prefetch(x + i, 1);
        __builtin_prefetch(v + i, 1);
      }
      [[fallthrough]];
    case Plain:
    case ReaderFlushes:
      for (int i = 0; i < n; ++i) {
        v[i] += kA * f[i];
        x[i] += kA * v[i];
      }
      break;
    case PerArray:
      for (int i = 0; i < n; ++i) v[i] += kA * f[i];
      for (int i = 0; i < n; ++i) x[i] += kA * v[i];
      break;
    case CopyBack:
      for (int i = 0; i < n; ++i) {
        vs[i] = v[i] + kA * f[i];
        xs[i] = x[i] + kA * vs[i];
      }
      std::memcpy(v, vs, sizeof(double) * n);
      std::memcpy(x, xs, sizeof(double) * n);
      break;
    case Streaming:
      for (int i = 0; i < n; i += 2) {
        const __m128d vn = _mm_add_pd(_mm_load_pd(v + i), _mm_mul_pd(_mm_set1_pd(kA), _mm_load_pd(f + i)));
        const __m128d xn = _mm_add_pd(_mm_load_pd(x + i), _mm_mul_pd(_mm_set1_pd(kA), vn));
        _mm_stream_pd(v + i, vn);
        _mm_stream_pd(x + i, xn);
      }
      _mm_sfence();
      break;
    default:
      break;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int cycles = argc > 1 ? std::atoi(argv[1]) : 100000;
  const int n = kN / 2;
  // aligned_alloc takes a size that is a whole number of alignments.
  auto alloc = [&] { return static_cast<double*>(std::aligned_alloc(64, (sizeof(double) * n + 63) / 64 * 64)); };
  double *x = alloc(), *v = alloc(), *f = alloc(), *xs = alloc(), *vs = alloc();
  for (int i = 0; i < n; ++i) x[i] = 1.0, v[i] = 0.5, f[i] = 0.1;
  double sink = 0;
  for (int w = 0; w < kWays; ++w) {
    const Way way = static_cast<Way>(w);
    double update_s = 0;
    const auto c0 = std::chrono::steady_clock::now();
#pragma omp parallel num_threads(2) reduction(+ : sink)
    {
      const int me = omp_get_thread_num();
      for (int c = 0; c < cycles; ++c) {
        if (me == 1) {
          double s = 0;
          for (int i = 0; i < n; ++i) s += x[i] + v[i];
          sink += s;
          if (way == ReaderFlushes)
            for (int i = 0; i < n; i += 8) {
              _mm_clflushopt(x + i);
              _mm_clflushopt(v + i);
            }
        }
#pragma omp barrier
        if (me == 0) {
          const auto t0 = std::chrono::steady_clock::now();
          update(way, n, x, v, f, xs, vs);
          update_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        }
#pragma omp barrier
      }
    }
    const double cycle_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
    std::printf("%-42s update %6.2f us   cycle %6.2f us\n", kNames[w], update_s / cycles * 1e6, cycle_s / cycles * 1e6);
  }
  // The update alone on one core, no other reader.
  const auto t0 = std::chrono::steady_clock::now();
  for (int c = 0; c < cycles; ++c) update(Plain, n, x, v, f, xs, vs);
  std::printf("%-42s update %6.2f us\n", "alone on one core",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / cycles * 1e6);
  std::printf("(checksum %g)\n", sink + x[0] + v[0]);
}
