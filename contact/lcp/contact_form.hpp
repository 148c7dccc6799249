#pragma once
// The contact form of the Stewart–Trinkle LCP of 2D frictional contact
// (contact/impulse.hpp): per contact k the impulses r_k = (lambda_k, beta_k),
// beta = beta+ - beta-, and the relative velocities u = W r + b, with W and b
// read from the rows and columns k (normal) and m + 2k (+T) of M and q. The
// -T row and column are the +T ones negated, and the alpha rows only encode
// Coulomb's law, so (W, b) and mu are the whole problem:
//   0 <= lambda  _|_  u_n >= 0,   |beta| <= mu lambda,
//   u_t = 0 where |beta| < mu lambda,  beta = -sign(u_t) mu lambda where u_t != 0.
// Shared by the contact-wise Gauss–Seidel (coulomb_gs.hpp) and the contact
// Newton method (contact_newton.hpp).

#include <array>
#include <cstddef>
#include <vector>

#include "contact/lcp/lcp.hpp"

namespace floesim::lcp {

struct FrictionLayout {
  std::size_t contacts = 0;  // m; 0: not a Stewart–Trinkle LCP
  double friction = 0.0;     // mu
};

// W and b in the order (n_0, t_0, n_1, t_1, ...), and W's 2x2 diagonal blocks.
struct ContactForm {
  SparseMatrix W;
  Vector b;
  std::vector<std::array<double, 4>> block;  // W_kk: nn, nt, tn, tt
};

// Throws RunError (naming `who`) unless the LCP has 4m unknowns for m = layout.contacts >= 1.
ContactForm contact_form(const Lcp& lcp, const FrictionLayout& layout, const char* who);

// The LCP's unknowns z = (lambda, beta+, beta-, alpha = |u_t|) of the impulses r and velocities u.
Vector lcp_point(const Vector& r, const Vector& u);

// The impulses r of an LCP point z (lambda clipped at 0).
Vector contact_impulses(const Vector& z, std::size_t contacts);

}  // namespace floesim::lcp
