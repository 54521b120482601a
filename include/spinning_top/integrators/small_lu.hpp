// LU with partial pivoting of a small fixed-size matrix (the low-rank Newton's coupling matrices
// of radau5 and radau9: 6 x 6 and 10 x 10), in plain loops that the compiler unrolls. Eigen's
// PartialPivLU runs its blocked, run-time-sized kernels (partial_lu_impl, triangular_solve_vector,
// gemv) on such matrices: a quarter of radau9's CPU at 1 kHz on stiff friction went to them
// (perf, toy top, k = 1e3). Same algorithm (Golub & Van Loan, Matrix Computations, alg. 3.4.1:
// the row of the largest |pivot|), so the same stability; the results differ in rounding only.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <utility>

namespace spinning_top {

template <int N>
class SmallLu {
 public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;

  SmallLu() {
    for (int k = 0; k < N; ++k) row_of_[k] = k;  // the identity's factors, until compute()
  }

  /// Factors P a = L U (L unit lower, stored below U's diagonal). A zero pivot is kept: solve()
  /// then returns non-finite values, which the Newton iterations treat as a failure.
  void compute(const Matrix& a) {
    lu_ = a;
    for (int k = 0; k < N; ++k) {
      int pivot_row = k;
      double largest = std::abs(lu_(k, k));
      for (int i = k + 1; i < N; ++i) {
        if (std::abs(lu_(i, k)) > largest) {
          largest = std::abs(lu_(i, k));
          pivot_row = i;
        }
      }
      row_of_[k] = pivot_row;
      if (pivot_row != k) lu_.row(k).swap(lu_.row(pivot_row));
      const double pivot = lu_(k, k);
      if (pivot == 0.0) continue;
      for (int i = k + 1; i < N; ++i) {
        const double l = lu_(i, k) / pivot;
        lu_(i, k) = l;
        for (int j = k + 1; j < N; ++j) lu_(i, j) -= l * lu_(k, j);
      }
    }
  }

  /// x with a x = b.
  Vector solve(Vector b) const {
    for (int k = 0; k < N; ++k)
      if (row_of_[k] != k) std::swap(b[k], b[row_of_[k]]);
    for (int k = 0; k < N; ++k)
      for (int i = k + 1; i < N; ++i) b[i] -= lu_(i, k) * b[k];
    for (int k = N - 1; k >= 0; --k) {
      double sum = b[k];
      for (int j = k + 1; j < N; ++j) sum -= lu_(k, j) * b[j];
      b[k] = sum / lu_(k, k);
    }
    return b;
  }

 private:
  Matrix lu_ = Matrix::Identity();
  int row_of_[N];  // row k was swapped with row_of_[k] at step k
};

}  // namespace spinning_top
