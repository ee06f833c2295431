#pragma once
// Subnormal numbers flushed to zero while a run computes.
//
// Where a disturbance spreads into a part at rest (a bending wave, a tool
// arriving), explicit dynamics leaves values ahead of the front that
// shrink by many orders of magnitude per step until they fall below
// 2.2e-308, the smallest normal double. Arithmetic on such subnormal
// values takes the processor's slow path: on the mechanics benchmark's
// plate with its pulled edge rising (bending waves), one thread spends
// about 15 % more time per element-cycle with subnormals kept. Flushing
// replaces only values below 2.2e-308 by zero (on that plate the energies
// at the end are the same bits either way), and it is the same on every
// thread, so results stay identical for any thread count.
//
// SubnormalsFlushed sets the mode on the calling thread and on every thread
// of the OpenMP team (the threads of later parallel regions: the runtime
// keeps its threads, and threads it creates later take the mode of the
// thread that creates them), and puts back what was there before when it
// goes out of scope. x86-64: the FTZ and DAZ bits of MXCSR (results flushed
// to zero, subnormal operands read as zero); AArch64: FPCR.FZ. Elsewhere
// it does nothing and active() is false.
namespace ts {

class SubnormalsFlushed {
 public:
  explicit SubnormalsFlushed(bool flush);
  ~SubnormalsFlushed();
  SubnormalsFlushed(const SubnormalsFlushed&) = delete;
  SubnormalsFlushed& operator=(const SubnormalsFlushed&) = delete;
  // Whether this guard flushes (false where asked not to, or where the
  // processor has no such mode here).
  bool active() const { return active_; }
  // The mode in words, as summary.json and the log give it.
  const char* mode() const { return active_ ? "flushed to zero" : "kept"; }

 private:
  bool active_ = false;
  unsigned long long saved_ = 0;  // the calling thread's control bits before
};

// Whether subnormals are flushed on the calling thread now.
bool subnormals_flushed_here();

}  // namespace ts
