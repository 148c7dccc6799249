#include "parallel/cell_routes.hpp"

#include <cstring>

#include "core/error.hpp"
#include "parallel/bytes.hpp"

namespace floesim::parallel {

std::vector<int> row_owners(std::span<const int> first_row) {
  std::vector<int> owner;
  for (std::size_t r = 0; r + 1 < first_row.size(); ++r)
    for (int row = first_row[r]; row < first_row[r + 1]; ++row) owner.push_back(static_cast<int>(r));
  return owner;
}

CellRoutes::CellRoutes(std::vector<int> first_row, std::size_t columns)
    : first_row_(std::move(first_row)), columns_(columns) {
  FLOESIM_ASSERT(first_row_.size() >= 2 && columns_ > 0);
  row_owner_ = row_owners(first_row_);
  slot_.assign(row_owner_.size() * columns_, 0);
}

std::vector<std::uint8_t> CellRoutes::interior_rows(int reach) const {
  const int rows = static_cast<int>(row_owner_.size());
  std::vector<std::uint8_t> interior(row_owner_.size(), 0);
  if (reach >= rows) return interior;
  for (int y = 0; y < rows; ++y) {
    bool inside = true;
    for (int d = -reach; d <= reach && inside; ++d) inside = row_owner_[static_cast<std::size_t>(((y + d) % rows + rows) % rows)] == row_owner_[static_cast<std::size_t>(y)];
    interior[static_cast<std::size_t>(y)] = inside ? 1 : 0;
  }
  return interior;
}

void CellRoutes::open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const double> parts,
                      int width) {
  const std::size_t ranks = static_cast<std::size_t>(comm.size()), w = static_cast<std::size_t>(width);
  FLOESIM_ASSERT(ranks + 1 == first_row_.size() && parts.size() == cells.size() * w);
  // This rank's cells grouped by owner, in their order within each group.
  sent_.assign(ranks, 0);
  for (std::uint32_t c : cells) ++sent_[static_cast<std::size_t>(owner(c))];
  std::vector<std::size_t> next(ranks, 0);
  for (std::size_t r = 1; r < ranks; ++r) next[r] = next[r - 1] + sent_[r - 1];
  route_.resize(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) route_[next[static_cast<std::size_t>(owner(cells[k]))]++] = static_cast<std::uint32_t>(k);
  // To each owner: its cells, then their parts.
  const std::size_t cell_bytes = sizeof(std::uint32_t) + w * sizeof(double);
  send_.resize(cells.size() * cell_bytes);
  std::vector<std::size_t> bytes(ranks);
  std::byte* out = send_.data();
  for (std::size_t r = 0, first = 0; r < ranks; first += sent_[r], ++r) {
    bytes[r] = sent_[r] * cell_bytes;
    for (std::size_t j = first; j < first + sent_[r]; ++j) out = put(out, &cells[route_[j]], 1);
    for (std::size_t j = first; j < first + sent_[r]; ++j) out = put(out, &parts[route_[j] * w], w);
  }
  std::vector<std::size_t> receive_bytes;
  comm.alltoall_bytes(send_, bytes, receive_, receive_bytes);
  // The owner's cells, each summed from zero in rank order.
  for (std::uint32_t c : owned_) slot_[c] = 0;
  owned_.clear();
  totals_.clear();
  from_.clear();
  width_ = width;
  received_.assign(ranks, 0);
  const std::byte* in = receive_.data();
  for (std::size_t r = 0; r < ranks; ++r) {
    const std::size_t n = receive_bytes[r] / cell_bytes;
    received_[r] = n;
    const std::byte* part = in + n * sizeof(std::uint32_t);
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint32_t c = at<std::uint32_t>(in, j);
      FLOESIM_ASSERT(owner(c) == comm.rank());
      if (slot_[c] == 0) {
        owned_.push_back(c);
        totals_.resize(totals_.size() + w, 0.0);
        slot_[c] = static_cast<std::uint32_t>(owned_.size());
      }
      const std::size_t s = slot_[c] - 1;
      from_.push_back(static_cast<std::uint32_t>(s));
      for (std::size_t q = 0; q < w; ++q) totals_[s * w + q] += at<double>(part, j * w + q);
    }
    in += receive_bytes[r];
  }
}

void CellRoutes::reply(const Communicator& comm, int w, std::span<double> out) {
  const std::size_t ranks = received_.size();
  FLOESIM_ASSERT(out.size() == route_.size());
  // To each rank, the totals of the cells it sent, in the order it sent them.
  send_.resize(from_.size() * sizeof(double));
  std::vector<std::size_t> bytes(ranks), receive_bytes(ranks);
  std::byte* message = send_.data();
  for (std::size_t k = 0; k < from_.size(); ++k) {
    const double t = total(from_[k], w);
    message = put(message, &t, 1);
  }
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes[r] = received_[r] * sizeof(double);
    receive_bytes[r] = sent_[r] * sizeof(double);
  }
  receive_.resize(route_.size() * sizeof(double));
  comm.alltoall(send_, bytes, receive_, receive_bytes);
  for (std::size_t k = 0; k < route_.size(); ++k) out[route_[k]] = at<double>(receive_.data(), k);
}

double CellRoutes::add(const Communicator& comm, std::span<const double> parts, int width, double extra) {
  const std::size_t ranks = received_.size(), w = static_cast<std::size_t>(width);
  FLOESIM_ASSERT(parts.size() == route_.size() * w);
  // To each owner: `extra`, then the parts of its cells in the order of open().
  send_.resize((ranks + route_.size() * w) * sizeof(double));
  std::vector<std::size_t> bytes(ranks), receive_bytes(ranks);
  std::byte* out = send_.data();
  for (std::size_t r = 0, first = 0; r < ranks; first += sent_[r], ++r) {
    bytes[r] = (1 + sent_[r] * w) * sizeof(double);
    receive_bytes[r] = (1 + received_[r] * w) * sizeof(double);
    out = put(out, &extra, 1);
    for (std::size_t j = first; j < first + sent_[r]; ++j) out = put(out, &parts[route_[j] * w], w);
  }
  std::size_t total_bytes = 0;
  for (std::size_t b : receive_bytes) total_bytes += b;
  receive_.resize(total_bytes);
  comm.alltoall(send_, bytes, receive_, receive_bytes);
  width_ = width;
  totals_.assign(owned_.size() * w, 0.0);
  double sum = 0.0;
  const std::byte* in = receive_.data();
  for (std::size_t r = 0, k = 0; r < ranks; ++r) {
    sum += at<double>(in, 0);
    for (std::size_t j = 0; j < received_[r]; ++j, ++k)
      for (std::size_t q = 0; q < w; ++q) totals_[from_[k] * w + q] += at<double>(in, 1 + j * w + q);
    in += receive_bytes[r];
  }
  return sum;
}

}  // namespace floesim::parallel
