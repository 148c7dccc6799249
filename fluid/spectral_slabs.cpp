// A spectral sea in slabs (fluid/spectral.hpp, docs/parallel.md stage six):
// each rank holds its modes; what needs the whole bank is gathered here.
#include "fluid/spectral.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <vector>

#include "core/error.hpp"
#include "fluid/spectral_impl.hpp"

namespace floesim::fluid {

std::size_t SpectralSea::modal_size() const { return 2 * impl_->nc; }

void SpectralSea::gather_modal_state(std::vector<double>& q, std::vector<double>& v) {
  Impl& m = *impl_;
  if (!m.slab) return Sea::gather_modal_state(q, v);
  settle();
  // Each rank's q then v (its modes, row by row) to rank 0 alone, which puts
  // them at their place in the whole bank's layout.
  const auto size = static_cast<std::size_t>(m.ranks.ranks);
  const auto rank = static_cast<std::size_t>(m.ranks.rank);
  auto part_bytes = [&](int r) { return 2 * 2 * sizeof(double) * static_cast<std::size_t>(m.ny) * m.width_of(r); };
  std::vector<std::size_t> send_counts(size, 0), receive_counts(size, 0);
  std::vector<std::byte> send, receive;
  if (rank != 0) {
    send_counts[0] = part_bytes(m.ranks.rank);
    send.resize(send_counts[0]);
    const std::size_t half = send.size() / 2;
    if (half > 0) {
      std::memcpy(send.data(), bank_.q().data(), half);
      std::memcpy(send.data() + half, bank_.v().data(), half);
    }
  } else {
    std::size_t total = 0;
    for (std::size_t r = 1; r < size; ++r) total += receive_counts[r] = part_bytes(static_cast<int>(r));
    receive.resize(total);
  }
  m.ranks.alltoall(send, send_counts, receive, receive_counts);
  q.clear();
  v.clear();
  if (rank != 0) return;
  q.assign(2 * m.nc, 0.0);
  v.assign(2 * m.nc, 0.0);
  const std::byte* at = receive.data();
  for (int r = 0; r < m.ranks.ranks; ++r) {
    const SlabFft2d::Span cols = m.slab->columns_of(r);
    const std::size_t width = m.width_of(r), values = 2 * width * static_cast<std::size_t>(m.ny);
    const double* from_q = r == 0 ? bank_.q().data() : reinterpret_cast<const double*>(at);
    const double* from_v = r == 0 ? bank_.v().data() : from_q + values;
    for (int iy = 0; iy < m.ny; ++iy) {
      const std::size_t to = 2 * (static_cast<std::size_t>(iy) * m.hx + static_cast<std::size_t>(cols.begin));
      const std::size_t from = 2 * static_cast<std::size_t>(iy) * width;
      std::copy(from_q + from, from_q + from + 2 * width, q.begin() + static_cast<std::ptrdiff_t>(to));
      std::copy(from_v + from, from_v + from + 2 * width, v.begin() + static_cast<std::ptrdiff_t>(to));
    }
    if (r != 0) at += part_bytes(r);
  }
}

void SpectralSea::set_modal_state(std::span<const double> q, std::span<const double> v) {
  Impl& m = *impl_;
  if (!m.slab) return Sea::set_modal_state(q, v);
  FLOESIM_ASSERT(q.size() == 2 * m.nc && v.size() == 2 * m.nc);
  settle();  // the state is replaced: the deferred kicks are applied, then overwritten
  m.for_own_modes([&](std::size_t first, std::size_t last, std::size_t mode, std::size_t) {
    std::copy(q.begin() + static_cast<std::ptrdiff_t>(2 * first), q.begin() + static_cast<std::ptrdiff_t>(2 * last),
              bank_.q().begin() + static_cast<std::ptrdiff_t>(2 * mode));
    std::copy(v.begin() + static_cast<std::ptrdiff_t>(2 * first), v.begin() + static_cast<std::ptrdiff_t>(2 * last),
              bank_.v().begin() + static_cast<std::ptrdiff_t>(2 * mode));
  });
  invalidate();
}

SeaEnergy SpectralSea::bank_energy() {
  Impl& m = *impl_;
  if (!m.slab) return Sea::bank_energy();
  // Each mode's terms to rank 0, which sums them in the whole bank's order
  // (row by row, each row's columns in rank order): ModalBank::kinetic() and
  // potential() of the whole bank, to the bit. Then its two sums to every rank.
  const auto size = static_cast<std::size_t>(m.ranks.ranks);
  const auto rank = static_cast<std::size_t>(m.ranks.rank);
  std::vector<double> own(2 * m.modes);
  bank_.energy_terms(std::span<double>(own.data(), m.modes), std::span<double>(own.data() + m.modes, m.modes));
  std::vector<std::size_t> send_counts(size, 0), receive_counts(size, 0);
  std::vector<double> receive;
  if (rank != 0) {
    send_counts[0] = sizeof(double) * own.size();
  } else {
    std::size_t total = 0;
    for (std::size_t r = 1; r < size; ++r) {
      receive_counts[r] = 2 * sizeof(double) * static_cast<std::size_t>(m.ny) * m.width_of(static_cast<int>(r));
      total += receive_counts[r] / sizeof(double);
    }
    receive.resize(total);
  }
  const std::span<const double> send = rank != 0 ? std::span<const double>(own) : std::span<const double>();
  m.ranks.alltoall(std::as_bytes(send), send_counts, std::as_writable_bytes(std::span<double>(receive)), receive_counts);
  std::array<double, 2> sums{0.0, 0.0};
  if (rank == 0) {
    std::vector<const double*> parts(size);
    parts[0] = own.data();
    const double* at = receive.data();
    for (std::size_t r = 1; r < size; ++r) {
      parts[r] = at;
      at += 2 * static_cast<std::size_t>(m.ny) * m.width_of(static_cast<int>(r));
    }
    for (int iy = 0; iy < m.ny; ++iy)
      for (std::size_t r = 0; r < size; ++r) {
        const std::size_t width = m.width_of(static_cast<int>(r)), modes = width * static_cast<std::size_t>(m.ny);
        const double* kinetic = parts[r] + static_cast<std::size_t>(iy) * width;
        const double* potential = kinetic + modes;
        for (std::size_t k = 0; k < width; ++k) {
          sums[0] += kinetic[k];
          sums[1] += potential[k];
        }
      }
  }
  std::vector<std::size_t> counts(size, 0);
  counts[0] = sizeof(sums);
  m.ranks.allgather(std::as_writable_bytes(std::span<double>(sums)), counts);
  return {0.5 * sums[0], 0.5 * sums[1]};
}

SpectralSea::Memory SpectralSea::memory() const {
  const Impl& m = *impl_;
  Memory r;
  r.modes = bank_.modes();
  r.mode_bytes = bank_.mode_bytes() + sizeof(double) * (m.kx.size() + m.ky.size() + m.phi.size()) +
                 m.kick_spec.size() * sizeof(fftw_complex) * m.kick_capacity;
  const std::size_t allocated_real = m.slab ? std::max<std::size_t>(m.real_size, 1) : m.real_size;
  const std::size_t allocated_spec = m.slab ? std::max<std::size_t>(m.spec_size, 1) : m.spec_size;
  r.scratch_bytes = sizeof(double) * allocated_real + sizeof(fftw_complex) * allocated_spec * (m.spec_vy ? 2 : 1) +
                    (m.slab ? m.slab->bytes() : 0) + sizeof(double) * (m.tank_eta.size() + m.tank_rate.size());
  return r;
}

}  // namespace floesim::fluid
