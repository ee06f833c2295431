#pragma once
// Loops shared out over the threads only where there is a second thread to
// take a share.
//
// An OpenMP parallel region that runs on one thread (one thread in all,
// `if (false)`, or nested inside the kernel's region that runs the
// contact handlers beside the element blocks) still costs the runtime its closing
// barrier, and GNU libgomp ends every barrier with a futex system call:
// about 1.4 us on a virtual machine, more than many loops of a step take.
// Loops called at every mechanical step therefore run their serial form
// when `team_available` is false. Either form gives the same results: the
// iterations are independent and each is computed the same way.
#ifdef _OPENMP
#include <omp.h>
#endif

namespace ts::sdk {

// True when a parallel region entered here would get more than one thread
// and `worthwhile` (the caller's size rule) holds.
inline bool team_available(bool worthwhile) {
#ifdef _OPENMP
  return worthwhile && omp_get_max_threads() > 1 && omp_get_active_level() < omp_get_max_active_levels();
#else
  (void)worthwhile;
  return false;
#endif
}

// body(i) for i in [0, n): shared out in chunks of `chunk` iterations dealt
// round robin (chunk <= 0: one contiguous range per thread) where a team is
// available and `worthwhile`, else in order on the calling thread.
template <class Body>
void for_each_index(int n, bool worthwhile, int chunk, Body&& body) {
  if (team_available(worthwhile)) {
    if (chunk > 0) {
#pragma omp parallel for schedule(static, chunk)
      for (int i = 0; i < n; ++i) body(i);
    } else {
#pragma omp parallel for schedule(static)
      for (int i = 0; i < n; ++i) body(i);
    }
    return;
  }
  for (int i = 0; i < n; ++i) body(i);
}

}  // namespace ts::sdk
