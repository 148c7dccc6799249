#include "fluid/lowest_modes.hpp"

#include <arpack/arpack.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include "core/error.hpp"
#include "fluid/static_correction.hpp"

namespace floesim::fluid {

using Eigen::MatrixXd;
using Eigen::VectorXd;

LowestModes lowest_modes(const MatrixXd& m_sf, const Eigen::SparseMatrix<double>& a_sf,
                         const LowestModesOptions& options) {
  const int n = static_cast<int>(m_sf.rows());
  const int nev = options.count;
  FLOESIM_ASSERT(m_sf.cols() == n && a_sf.rows() == n && a_sf.cols() == n);
  if (!(nev >= 1 && nev <= n - 2))
    throw InputError("fluid: expected between 1 and " + std::to_string(n - 2) + " lowest modes, got " +
                     std::to_string(nev));

  // a_sf^-1 on zero-mean right-hand sides (the pin of g = 0 in fluid/static_correction.hpp).
  const ZeroMeanStiffness stiff(a_sf);

  const int ncv = std::min(n, std::max(2 * nev + 1, nev + 32));
  const int lworkl = ncv * (ncv + 8);
  // A smooth zero-mean start (deterministic; ARPACK forces it into the range of the operator).
  VectorXd resid(n);
  for (int i = 0; i < n; ++i) resid(i) = std::sin(0.7 + 1.3 * i) + 0.5 * std::cos(0.11 * i);
  resid.array() -= resid.mean();
  std::vector<double> v(static_cast<std::size_t>(n) * ncv), workd(3 * static_cast<std::size_t>(n)),
      workl(static_cast<std::size_t>(lworkl));
  a_int iparam[11] = {}, ipntr[14] = {};
  iparam[0] = 1;  // exact shifts
  iparam[2] = options.max_restarts;
  iparam[6] = 2;  // mode 2: OP = inv(B) A, B = a_sf
  a_int ido = 0, info = 1;  // info = 1: resid is the start
  const double tol = options.tolerance;

  LowestModes out;
  VectorXd t(n);
  for (;;) {
    dsaupd_c(&ido, "G", n, "LA", nev, tol, resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(),
             workl.data(), lworkl, &info);
    if (ido == 99) break;
    Eigen::Map<VectorXd> x(workd.data() + ipntr[0] - 1, n), y(workd.data() + ipntr[1] - 1, n);
    if (ido == -1 || ido == 1) {
      // x <- A x = P m_sf P x (ARPACK's mode 2 keeps it), y <- a_sf^-1 A x.
      t = x.array() - x.mean();
      x.noalias() = m_sf * t;
      x.array() -= x.mean();
      stiff.solve(x, t);
      y = t;
      ++out.operator_applications;
    } else if (ido == 2) {
      y = a_sf * x;
    } else {
      throw RunError("fluid: ARPACK asked for an unexpected operation (ido = " + std::to_string(ido) + ")");
    }
  }
  if (info == 1)
    throw RunError("fluid: the Lanczos iteration for the " + std::to_string(nev) + " lowest modes did not converge in " +
                   std::to_string(options.max_restarts) + " restarts (" + std::to_string(iparam[4]) + " converged)");
  if (info != 0) throw RunError("fluid: ARPACK dsaupd failed (info = " + std::to_string(info) + ")");

  std::vector<a_int> select(static_cast<std::size_t>(ncv));
  VectorXd mu(nev);
  MatrixXd z(n, nev);
  a_int einfo = 0;
  dseupd_c(1, "A", select.data(), mu.data(), z.data(), n, 0.0, "G", n, "LA", nev, tol, resid.data(), ncv, v.data(), n,
           iparam, ipntr, workd.data(), workl.data(), lworkl, &einfo);
  if (einfo != 0) throw RunError("fluid: ARPACK dseupd failed (info = " + std::to_string(einfo) + ")");

  // z is a_sf-orthonormal: z^T m_sf z = mu z^T a_sf z = mu, so x = z / sqrt(mu).
  std::vector<int> order(static_cast<std::size_t>(nev));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return mu(a) > mu(b); });
  out.omega.resize(static_cast<std::size_t>(nev));
  out.x.resize(n, nev);
  for (int j = 0; j < nev; ++j) {
    const double m = mu(order[static_cast<std::size_t>(j)]);
    if (!(m > 0.0)) throw RunError("fluid: the added mass m_sf is not positive on a Lanczos mode");
    out.omega[static_cast<std::size_t>(j)] = 1.0 / std::sqrt(m);
    out.x.col(j) = z.col(order[static_cast<std::size_t>(j)]) / std::sqrt(m);
    out.x.col(j).array() -= out.x.col(j).mean();
  }
  return out;
}

}  // namespace floesim::fluid
