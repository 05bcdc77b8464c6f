#pragma once

#include <Eigen/Core>

namespace cwloc {

// Real solutions of three quadrics in three unknowns,
//   c(k,0) x^2 + c(k,1) xy + c(k,2) xz + c(k,3) y^2 + c(k,4) yz + c(k,5) z^2
//     + c(k,6) x + c(k,7) y + c(k,8) z + c(k,9) = 0,   k = 0, 1, 2.
// A generic system has 8 complex solutions (Bezout). Solved by a hidden-variable resultant:
// with z hidden, the equations are solved linearly for x^2, xy, y^2; three consequences of
// x (xy) = y (x^2) and x (y^2) = y (xy), reduced with those rules, are linear forms in (x, y, 1)
// whose 3x3 determinant is a degree-8 polynomial in z. Its real roots are isolated between the
// roots of its derivatives and refined by safeguarded Newton steps; x, y follow from the null
// vector of the 3x3 matrix, and Newton steps on the original equations polish each solution.
// The hidden variable is the one whose elimination is best conditioned; if none is (a
// solution at infinity), the system is solved in fixed, generic rotated and shifted coordinates.
// (The same structure as Kukelova et al., "Efficient Intersection of Three Quadrics and
// Applications in Computer Vision", CVPR 2016; our own derivation.)
//
// Writes the real solutions to the columns of *solutions and returns their number (0..8).
int SolveThreeQuadrics(const Eigen::Matrix<double, 3, 10>& coeffs,
                       Eigen::Matrix<double, 3, 8>* solutions);

}  // namespace cwloc
