#include "parallel/cell_routes.hpp"

#include <algorithm>
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

void CellRoutes::open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const std::uint32_t> first,
                      std::span<const std::uint32_t> keys, std::span<const double> parts, int width) {
  const std::size_t ranks = static_cast<std::size_t>(comm.size()), w = static_cast<std::size_t>(width);
  FLOESIM_ASSERT(ranks + 1 == first_row_.size() && first.size() == cells.size() + 1 && keys.size() == first.back() &&
                 parts.size() == keys.size() * w);
  // This rank's cells grouped by owner, in their order within each group.
  sent_.assign(ranks, 0);
  sent_pieces_.assign(ranks, 0);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const std::size_t r = static_cast<std::size_t>(owner(cells[k]));
    ++sent_[r];
    sent_pieces_[r] += first[k + 1] - first[k];
  }
  std::vector<std::size_t> next(ranks, 0);
  for (std::size_t r = 1; r < ranks; ++r) next[r] = next[r - 1] + sent_[r - 1];
  route_.resize(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) route_[next[static_cast<std::size_t>(owner(cells[k]))]++] = static_cast<std::uint32_t>(k);
  first_.assign(first.begin(), first.end());
  // To each owner: the count of its cells, the cells, their pieces' counts,
  // then the pieces' keys and values.
  std::vector<std::size_t> bytes(ranks);
  std::size_t total_bytes = 0;
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes[r] = sizeof(std::uint64_t) + sent_[r] * 2 * sizeof(std::uint32_t) + sent_pieces_[r] * (sizeof(std::uint32_t) + w * sizeof(double));
    total_bytes += bytes[r];
  }
  send_.resize(total_bytes);
  std::byte* out = send_.data();
  for (std::size_t r = 0, begin = 0; r < ranks; begin += sent_[r], ++r) {
    const std::size_t end = begin + sent_[r];
    const std::uint64_t n = sent_[r];
    out = put(out, &n, 1);
    for (std::size_t j = begin; j < end; ++j) out = put(out, &cells[route_[j]], 1);
    for (std::size_t j = begin; j < end; ++j) {
      const std::uint32_t count = first[route_[j] + 1] - first[route_[j]];
      out = put(out, &count, 1);
    }
    for (std::size_t j = begin; j < end; ++j) out = put(out, &keys[first[route_[j]]], first[route_[j] + 1] - first[route_[j]]);
    for (std::size_t j = begin; j < end; ++j)
      out = put(out, &parts[first[route_[j]] * w], (first[route_[j] + 1] - first[route_[j]]) * w);
  }
  std::vector<std::size_t> receive_bytes;
  comm.alltoall_bytes(send_, bytes, receive_, receive_bytes);
  // The owner's cells, in the order they first arrive, and every piece
  // received with its cell's slot and key.
  for (std::uint32_t c : owned_) slot_[c] = 0;
  owned_.clear();
  from_.clear();
  values_.clear();
  width_ = width;
  received_.assign(ranks, 0);
  received_pieces_.assign(ranks, 0);
  struct Piece {
    std::uint32_t slot, key, index;  // index: in the order received
  };
  std::vector<Piece> pieces;
  const std::byte* in = receive_.data();
  for (std::size_t r = 0; r < ranks; ++r) {
    const std::size_t n = static_cast<std::size_t>(at<std::uint64_t>(in, 0));
    const std::byte* cell = in + sizeof(std::uint64_t);
    const std::byte* count = cell + n * sizeof(std::uint32_t);
    const std::byte* key = count + n * sizeof(std::uint32_t);
    std::size_t m = 0;
    for (std::size_t j = 0; j < n; ++j) m += at<std::uint32_t>(count, j);
    const std::byte* value = key + m * sizeof(std::uint32_t);
    received_[r] = n;
    received_pieces_[r] = m;
    for (std::size_t j = 0, p = 0; j < n; ++j) {
      const std::uint32_t c = at<std::uint32_t>(cell, j);
      FLOESIM_ASSERT(owner(c) == comm.rank());
      if (slot_[c] == 0) {
        owned_.push_back(c);
        slot_[c] = static_cast<std::uint32_t>(owned_.size());
      }
      const std::uint32_t s = slot_[c] - 1;
      from_.push_back(s);
      for (std::uint32_t q = at<std::uint32_t>(count, j); q > 0; --q, ++p)
        pieces.push_back({s, at<std::uint32_t>(key, p), static_cast<std::uint32_t>(pieces.size())});
    }
    const std::size_t before = values_.size();
    values_.resize(before + m * w);
    if (m > 0) std::memcpy(values_.data() + before, value, m * w * sizeof(double));
    in += receive_bytes[r];
  }
  // Each cell's pieces by key; equal keys in the order received (rank
  // order, then the sender's order).
  std::sort(pieces.begin(), pieces.end(), [](const Piece& x, const Piece& y) {
    return x.slot != y.slot ? x.slot < y.slot : x.key != y.key ? x.key < y.key : x.index < y.index;
  });
  order_.resize(pieces.size());
  order_first_.assign(owned_.size() + 1, 0);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    order_[k] = pieces[k].index;
    ++order_first_[pieces[k].slot + 1];
  }
  for (std::size_t j = 0; j < owned_.size(); ++j) order_first_[j + 1] += order_first_[j];
  sum_pieces();
}

void CellRoutes::open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const double> parts,
                      int width) {
  std::vector<std::uint32_t> first(cells.size() + 1), keys(cells.size(), 0);
  for (std::size_t k = 0; k <= cells.size(); ++k) first[k] = static_cast<std::uint32_t>(k);
  open(comm, cells, first, keys, parts, width);
}

void CellRoutes::sum_pieces() {
  // From zero, in key order: the serial loop's additions when the keys are
  // its order.
  const std::size_t w = static_cast<std::size_t>(width_);
  totals_.resize(owned_.size() * w);
  for (std::size_t j = 0; j < owned_.size(); ++j)
    for (std::size_t q = 0; q < w; ++q) {
      double t = 0.0;
      for (std::uint32_t k = order_first_[j]; k < order_first_[j + 1]; ++k) t += values_[order_[k] * w + q];
      totals_[j * w + q] = t;
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
  FLOESIM_ASSERT(parts.size() == first_.back() * w);
  // To each owner: `extra`, then the values of its cells' pieces in the
  // order of open().
  std::size_t send_total = 0, receive_total = 0;
  std::vector<std::size_t> bytes(ranks), receive_bytes(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes[r] = (1 + sent_pieces_[r] * w) * sizeof(double);
    receive_bytes[r] = (1 + received_pieces_[r] * w) * sizeof(double);
    send_total += bytes[r];
    receive_total += receive_bytes[r];
  }
  send_.resize(send_total);
  std::byte* out = send_.data();
  for (std::size_t r = 0, begin = 0; r < ranks; begin += sent_[r], ++r) {
    out = put(out, &extra, 1);
    for (std::size_t j = begin; j < begin + sent_[r]; ++j)
      out = put(out, &parts[first_[route_[j]] * w], (first_[route_[j] + 1] - first_[route_[j]]) * w);
  }
  receive_.resize(receive_total);
  comm.alltoall(send_, bytes, receive_, receive_bytes);
  width_ = width;
  values_.resize((receive_total / sizeof(double) - ranks));
  double sum = 0.0;
  const std::byte* in = receive_.data();
  for (std::size_t r = 0, at_value = 0; r < ranks; ++r) {
    sum += at<double>(in, 0);
    const std::size_t m = received_pieces_[r] * w;
    if (m > 0) std::memcpy(values_.data() + at_value, in + sizeof(double), m * sizeof(double));
    at_value += m;
    in += receive_bytes[r];
  }
  sum_pieces();
  return sum;
}

}  // namespace floesim::parallel
