#pragma once
// Status: how a plugin reports an error to the kernel. Nothing is thrown
// across the plugin boundary; every call that can fail returns a Status.
#include <exception>
#include <string>
#include <utility>

namespace ts::sdk {

struct Status {
  bool ok = true;
  std::string message;  // one line, names the offending parameter or entity

  static Status success() { return {}; }
  static Status failure(std::string msg) { return {false, std::move(msg)}; }
  explicit operator bool() const { return ok; }
};

// Runs f() and converts anything it throws into a failed Status, so that a
// plugin never lets an exception reach the kernel.
template <class F>
Status guarded(F&& f) noexcept {
  try {
    return f();
  } catch (const std::exception& e) {
    return Status::failure(e.what());
  } catch (...) {
    return Status::failure("unknown error inside plugin");
  }
}

}  // namespace ts::sdk
