#pragma once

namespace cwloc {

// The chi-square quantile of 3 degrees of freedom at 95 %: a 3D Gaussian error e lies in the
// ellipsoid e^T S^-1 e <= it with probability 0.95 (pose covariances and their coverage).
inline constexpr double kChiSquare3Dof95 = 7.814727903251178;

}  // namespace cwloc
