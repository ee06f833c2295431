#pragma once
#include <stdexcept>
#include <string>
#include <vector>

namespace ts {

// A problem with the user's input: reported as one line, "<pointer>: <what>",
// exit status 2, before anything runs.
class JobError : public std::runtime_error {
 public:
  JobError(std::string pointer, const std::string& what)
      : std::runtime_error(pointer.empty() ? what : pointer + ": " + what), pointer_(std::move(pointer)) {}
  const std::string& pointer() const { return pointer_; }

 private:
  std::string pointer_;
};

// A failure while running (NaN, unstable step, plugin evaluation error):
// exit status 3 after the computed frames are kept.
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "did you mean 'x'?" (empty when nothing is close) and "a, b, c".
std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates);
std::string join(const std::vector<std::string>& items, const std::string& sep = ", ");

}  // namespace ts
