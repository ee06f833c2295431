#pragma once
// One sparse symmetric system for every value coupled by ply/ply links.
// Used by the split splitters (rods only) and by layered3d (everything).
#include <Eigen/Sparse>
#include <span>
#include <vector>

namespace ts::thermal {

class LinkedSolver {
 public:
  // Starts a new assembly of an n x n system.
  void begin(int n);
  void add(int i, int j, double v) { trip_.emplace_back(i, j, v); }
  // Finishes the assembly; refactors only when the matrix changed.
  // Returns false when the factorisation fails.
  bool finish();
  // Solves in place.
  void solve(std::span<double> rhs);
  int refactorizations() const { return refactor_count_; }

 private:
  int n_ = 0;
  std::vector<Eigen::Triplet<double>> trip_;
  Eigen::SparseMatrix<double> a_;
  std::vector<double> last_values_;
  std::vector<int> last_outer_, last_inner_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  // The factors as flat arrays (P A P^-1 = L D L^T, L unit lower, stored
  // without its diagonal, column by column) for an allocation-free solve.
  std::vector<int> perm_, lp_, li_;
  std::vector<double> lx_, d_, y_;
  bool factored_ = false;
  int refactor_count_ = 0;
};

}  // namespace ts::thermal
