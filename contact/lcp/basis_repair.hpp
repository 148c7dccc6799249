#pragma once
// Repair of a singular complementary start basis for Lemke's warm start
// (lemke.hpp, LemkeOptions::start).
//
// The start basis B has the column e_i where w_i is basic and -M e_j where
// z_j is basic. Ordered (z's, w's) it is block triangular, [[-M_ZZ, 0],
// [-M_NZ, I]], so B is singular exactly when the principal block M_ZZ is. In a
// jam M_ZZ is singular when the guessed set holds redundant contacts (more
// active constraints than the floes' degrees of freedom), or a friction
// unknown without its normal one. The repair keeps basic a maximal set of
// independent columns of M_ZZ, found by a rank-revealing sparse QR
// (Eigen's SparseQR, column pivoting by COLAMD, a column is dependent when
// its diagonal of R is below `tolerance` times the largest column norm), and
// turns the others to their w's. Dropping rows and columns together can in
// principle leave a singular block again (M is not symmetric), so the repair
// is repeated, at most `rounds` times. The result is only a start: Lemke's
// own refactorisation decides whether it is usable.

#include <cstdint>
#include <vector>

#include "contact/lcp/lcp.hpp"

namespace floesim::lcp {

struct BasisRepairOptions {
  double tolerance = 1e-10;
  int rounds = 3;
};

// Returns the repaired flags; `dropped` (optional) receives how many z's were turned to w's.
std::vector<std::uint8_t> repair_basis(const SparseMatrix& M, const std::vector<std::uint8_t>& z_basic,
                                       const BasisRepairOptions& options = {}, long* dropped = nullptr);

}  // namespace floesim::lcp
