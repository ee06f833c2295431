#include "solve/rigid_body.hpp"

#include <algorithm>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace ts {

void constrained_rigid_inverse(const double* M, const double* C, double* G) {
  using Mat6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  const Mat6 m = Eigen::Map<const Mat6>(M), c = Eigen::Map<const Mat6>(C);
  Eigen::Map<Mat6> out(G);
  // The usual cases first: C diagonal (no constraint, or symmetry planes,
  // which hold coordinates of q) and M positive definite on the free
  // coordinates: a Cholesky factorisation of that block.
  if (c.isDiagonal(0.0)) {
    // The held coordinates' rows and columns replaced by the free
    // diagonal's mean, so that one 6 x 6 factorisation serves.
    double mean = 0;
    int n = 0;
    for (int i = 0; i < 6; ++i)
      if (!(c(i, i) > 0)) {
        mean += m(i, i);
        ++n;
      }
    if (n > 0 && mean > 0) {
      mean /= n;
      Mat6 a = m;
      for (int i = 0; i < 6; ++i)
        if (c(i, i) > 0) {
          a.row(i).setZero();
          a.col(i).setZero();
          a(i, i) = mean;
        }
      const Eigen::LLT<Mat6> llt(a);
      // Positive definite and not near singular: the factor's smallest
      // diagonal against its largest.
      if (llt.info() == Eigen::Success) {
        const Mat6 factor = llt.matrixL();
        if (factor.diagonal().minCoeff() > 1e-6 * factor.diagonal().maxCoeff()) {
          out = llt.solve(Mat6::Identity());
          for (int i = 0; i < 6; ++i)
            if (c(i, i) > 0) {
              out.row(i).setZero();
              out.col(i).setZero();
            }
          return;
        }
      }
    }
  }
  // The constrained directions: C's eigenvectors of eigenvalues that are
  // not round-off. In that basis, they take no velocity.
  const Eigen::SelfAdjointEigenSolver<Mat6> ec(c);
  const Mat6 Q = ec.eigenvectors();
  const double c_tol = 1e-10 * std::max(1.0, ec.eigenvalues().cwiseAbs().maxCoeff());
  Mat6 mq = Q.transpose() * m * Q;
  for (int i = 0; i < 6; ++i)
    if (ec.eigenvalues()[i] > c_tol) {
      mq.row(i).setZero();
      mq.col(i).setZero();
    }
  // The free block, pseudo-inverted: directions without mass take no
  // velocity.
  const Eigen::SelfAdjointEigenSolver<Mat6> em(mq);
  const double m_tol = 1e-12 * em.eigenvalues().cwiseAbs().maxCoeff();
  Mat6 inv = Mat6::Zero();
  for (int i = 0; i < 6; ++i)
    if (em.eigenvalues()[i] > m_tol) {
      const Vec6 u = em.eigenvectors().col(i);
      inv += u * u.transpose() / em.eigenvalues()[i];
    }
  out = Q * inv * Q.transpose();
}

void best_fit_rotation(const double* H, double* R) {
  using Mat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  const Mat3 h = Eigen::Map<const Mat3>(H);
  const Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // H = U S V^T; R = V D U^T, D = diag(1, 1, det(V U^T)).
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Eigen::Map<Mat3> out(R);
  out = svd.matrixV() * d * svd.matrixU().transpose();
}

}  // namespace ts
