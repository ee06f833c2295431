#include "solve/subnormals.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

#if defined(__x86_64__) || defined(_M_X64)
#include <xmmintrin.h>
#define TS_FLUSH_X86 1
#elif defined(__aarch64__)
#define TS_FLUSH_ARM 1
#endif

namespace ts {
namespace {

#if defined(TS_FLUSH_X86)
constexpr unsigned long long kFlushBits = 0x8040;  // MXCSR FTZ (bit 15) | DAZ (bit 6)
unsigned long long control() { return _mm_getcsr(); }
void set_control(unsigned long long v) { _mm_setcsr(static_cast<unsigned>(v)); }
#elif defined(TS_FLUSH_ARM)
constexpr unsigned long long kFlushBits = 1ull << 24;  // FPCR.FZ
unsigned long long control() { return __builtin_aarch64_get_fpcr(); }
void set_control(unsigned long long v) { __builtin_aarch64_set_fpcr(static_cast<unsigned>(v)); }
#else
constexpr unsigned long long kFlushBits = 0;
unsigned long long control() { return 0; }
void set_control(unsigned long long) {}
#endif

// Sets the flush bits to `bits` (a subset of kFlushBits) on the calling
// thread and on every thread of the team.
void apply_everywhere(unsigned long long bits) {
  auto apply = [bits] { set_control((control() & ~kFlushBits) | bits); };
  apply();
#ifdef _OPENMP
#pragma omp parallel
  apply();
#endif
}

}  // namespace

SubnormalsFlushed::SubnormalsFlushed(bool flush) {
  if (!flush || kFlushBits == 0) return;
  saved_ = control();
  active_ = true;
  apply_everywhere(kFlushBits);
}

SubnormalsFlushed::~SubnormalsFlushed() {
  if (active_ && (saved_ & kFlushBits) != kFlushBits) apply_everywhere(saved_ & kFlushBits);
}

bool subnormals_flushed_here() { return kFlushBits != 0 && (control() & kFlushBits) == kFlushBits; }

}  // namespace ts
