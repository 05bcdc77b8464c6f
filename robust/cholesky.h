#pragma once

namespace cwloc {

// The largest system SolveCholesky solves: rotation 3, translation 3, focal length, k.
constexpr int kMaxCholeskySize = 8;

// Solves a y = rhs for a symmetric positive definite n x n matrix a (n <= kMaxCholeskySize,
// element (i, j) at a[i * stride + j]; only the lower triangle is read, so row- and
// column-major storage are the same). False on a non-positive pivot or a non-finite solution,
// which callers treat as a failed step. Plain loops: the pose code's fixed-size Eigen
// decompositions cost seconds of compile time each, and these systems are at most 8 x 8.
bool SolveCholesky(int n, const double* a, int stride, const double* rhs, double* y);

}  // namespace cwloc
