#include "linked_solver.hpp"

namespace ts::thermal {

void LinkedSolver::begin(int n) {
  n_ = n;
  trip_.clear();
}

bool LinkedSolver::finish() {
  a_.resize(n_, n_);
  a_.setFromTriplets(trip_.begin(), trip_.end());
  a_.makeCompressed();
  const std::vector<double> values(a_.valuePtr(), a_.valuePtr() + a_.nonZeros());
  const std::vector<int> outer(a_.outerIndexPtr(), a_.outerIndexPtr() + n_ + 1);
  const std::vector<int> inner(a_.innerIndexPtr(), a_.innerIndexPtr() + a_.nonZeros());
  if (factored_ && values == last_values_ && outer == last_outer_ && inner == last_inner_) return true;
  const bool same_pattern = factored_ && outer == last_outer_ && inner == last_inner_;
  if (!same_pattern) ldlt_.analyzePattern(a_);
  ldlt_.factorize(a_);
  ++refactor_count_;
  factored_ = ldlt_.info() == Eigen::Success;
  last_values_ = values;
  last_outer_ = outer;
  last_inner_ = inner;
  return factored_;
}

void LinkedSolver::solve(std::span<double> rhs) {
  Eigen::Map<Eigen::VectorXd> b(rhs.data(), static_cast<Eigen::Index>(rhs.size()));
  x_ = ldlt_.solve(b);
  b = x_;
}

}  // namespace ts::thermal
