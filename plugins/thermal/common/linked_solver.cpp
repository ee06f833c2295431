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
  if (factored_) {
    const auto& L = ldlt_.matrixL().nestedExpression();  // compressed, column-major, strictly lower
    lp_.assign(L.outerIndexPtr(), L.outerIndexPtr() + n_ + 1);
    li_.assign(L.innerIndexPtr(), L.innerIndexPtr() + L.nonZeros());
    lx_.assign(L.valuePtr(), L.valuePtr() + L.nonZeros());
    const auto& D = ldlt_.vectorD();
    d_.assign(D.data(), D.data() + n_);
    const auto& P = ldlt_.permutationP().indices();
    perm_.resize(n_);
    if (P.size() == n_) {
      for (int i = 0; i < n_; ++i) perm_[i] = P[i];
    } else {
      for (int i = 0; i < n_; ++i) perm_[i] = i;
    }
    y_.assign(n_, 0.0);
  }
  last_values_ = values;
  last_outer_ = outer;
  last_inner_ = inner;
  return factored_;
}

// x = P^-1 L^-T D^-1 L^-1 P b, with (P b)[perm[i]] = b[i].
void LinkedSolver::solve(std::span<double> rhs) {
  double* y = y_.data();
  for (int i = 0; i < n_; ++i) y[perm_[i]] = rhs[i];
  for (int j = 0; j < n_; ++j) {
    const double yj = y[j];
    if (yj != 0.0)
      for (int p = lp_[j]; p < lp_[j + 1]; ++p) y[li_[p]] -= lx_[p] * yj;
  }
  for (int i = 0; i < n_; ++i) y[i] /= d_[i];
  for (int j = n_ - 1; j >= 0; --j) {
    double s = y[j];
    for (int p = lp_[j]; p < lp_[j + 1]; ++p) s -= lx_[p] * y[li_[p]];
    y[j] = s;
  }
  for (int i = 0; i < n_; ++i) rhs[i] = y[perm_[i]];
}

}  // namespace ts::thermal
