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

CellBox CellBox::of(std::span<const std::uint32_t> cells, int columns, int rows) {
  FLOESIM_ASSERT(columns <= kMaxSide && rows <= kMaxSide);
  CellBox box;
  if (cells.empty()) return box;
  box.first_cell = cells[0];
  const std::uint32_t nx = static_cast<std::uint32_t>(columns);
  const int row0 = static_cast<int>(cells[0] / nx), column0 = static_cast<int>(cells[0] % nx);
  // Each offset from the first cell taken the short way round, in
  // [-floor(n/2), ceil(n/2)): any choice holds the cell, this one keeps the
  // box small. d = x - x0 lies in (-n, n).
  auto offset = [](int d, int n) {
    if (d >= 0) return d >= (n + 1) / 2 ? d - n : d;
    return d + n < (n + 1) / 2 ? d + n : d;
  };
  int row_lo = 0, row_hi = 0, column_lo = 0, column_hi = 0;
  // The row found by a division only when it changes (a floe's cells come
  // sorted, row by row).
  std::uint32_t base = static_cast<std::uint32_t>(row0) * nx;
  for (const std::uint32_t c : cells) {
    if (c < base || c - base >= nx) {
      const int row = static_cast<int>(c / nx);
      base = static_cast<std::uint32_t>(row) * nx;
      const int dy = offset(row - row0, rows);
      row_lo = std::min(row_lo, dy);
      row_hi = std::max(row_hi, dy);
    }
    const int dx = offset(static_cast<int>(c - base) - column0, columns);
    column_lo = std::min(column_lo, dx);
    column_hi = std::max(column_hi, dx);
  }
  box.row_lo = static_cast<std::int16_t>(row_lo);
  box.row_hi = static_cast<std::int16_t>(row_hi);
  box.column_lo = static_cast<std::int16_t>(column_lo);
  box.column_hi = static_cast<std::int16_t>(column_hi);
  return box;
}

CellRoutes::CellRoutes(std::vector<int> first_row, std::size_t columns)
    : first_row_(std::move(first_row)), columns_(columns) {
  FLOESIM_ASSERT(first_row_.size() >= 2 && columns_ > 0);
  row_owner_ = row_owners(first_row_);
  rows_ = row_owner_.size();
  ranks_ = static_cast<int>(first_row_.size()) - 1;
  slot_.assign(rows_ * columns_, 0);
}

CellRoutes CellRoutes::replicated(int ranks, std::size_t columns, std::size_t rows) {
  FLOESIM_ASSERT(ranks >= 1 && columns > 0 && rows > 0);
  CellRoutes routes;
  routes.replicated_ = true;
  routes.ranks_ = ranks;
  routes.columns_ = columns;
  routes.rows_ = rows;
  routes.slot_.assign(rows * columns, 0);
  return routes;
}

std::vector<std::uint8_t> CellRoutes::interior_rows(int reach) const {
  const int rows = static_cast<int>(rows_);
  std::vector<std::uint8_t> interior(rows_, 0);
  if (replicated_ || reach >= rows) return interior;
  for (int y = 0; y < rows; ++y) {
    bool inside = true;
    for (int d = -reach; d <= reach && inside; ++d) inside = row_owner_[static_cast<std::size_t>(((y + d) % rows + rows) % rows)] == row_owner_[static_cast<std::size_t>(y)];
    interior[static_cast<std::size_t>(y)] = inside ? 1 : 0;
  }
  return interior;
}

void CellRoutes::open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const std::uint32_t> first,
                      std::span<const PieceKey> keys, std::span<const double> parts, int width,
                      std::span<const std::uint32_t> alone) {
  // Each cell to its owner alone.
  FLOESIM_ASSERT(!replicated_);
  owner_first_.resize(cells.size() + 1);
  owner_list_.resize(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) {
    owner_first_[k] = static_cast<std::uint32_t>(k);
    owner_list_[k] = owner(cells[k]);
  }
  owner_first_[cells.size()] = static_cast<std::uint32_t>(cells.size());
  to_owners_ = true;
  send_pieces(comm, cells, first, keys, parts, width, owner_first_, owner_list_, alone);
}

void CellRoutes::open_shared(const Communicator& comm, std::span<const std::uint32_t> cells,
                             std::span<const std::uint32_t> first, std::span<const PieceKey> keys,
                             std::span<const double> parts, int width, std::span<const std::uint32_t> receivers_first,
                             std::span<const int> receivers, std::span<const std::uint32_t> alone) {
  FLOESIM_ASSERT(receivers_first.size() == cells.size() + 1 && receivers.size() == receivers_first.back());
  to_owners_ = false;
  send_pieces(comm, cells, first, keys, parts, width, receivers_first, receivers, alone);
}

void CellRoutes::send_pieces(const Communicator& comm, std::span<const std::uint32_t> cells,
                             std::span<const std::uint32_t> first, std::span<const PieceKey> keys,
                             std::span<const double> parts, int width, std::span<const std::uint32_t> receivers_first,
                             std::span<const int> receivers, std::span<const std::uint32_t> alone) {
  const std::size_t ranks = static_cast<std::size_t>(comm.size()), w = static_cast<std::size_t>(width);
  FLOESIM_ASSERT(static_cast<int>(ranks) == ranks_ && first.size() == cells.size() + 1 && keys.size() == first.back() &&
                 parts.size() == keys.size() * w);
  // This rank's cells grouped by receiver (a cell in the group of each of
  // its receivers) and its alone cells by owner (replicated: each in the
  // group of every other rank), in their order within each group.
  sent_.assign(ranks, 0);
  sent_pieces_.assign(ranks, 0);
  sent_alone_.assign(ranks, 0);
  for (std::size_t k = 0; k < cells.size(); ++k)
    for (std::uint32_t q = receivers_first[k]; q < receivers_first[k + 1]; ++q) {
      const std::size_t r = static_cast<std::size_t>(receivers[q]);
      ++sent_[r];
      sent_pieces_[r] += first[k + 1] - first[k];
    }
  const std::size_t me = static_cast<std::size_t>(comm.rank());
  if (replicated_) {
    for (std::size_t r = 0; r < ranks; ++r) sent_alone_[r] = r == me ? 0 : alone.size();
  } else {
    for (const std::uint32_t c : alone) ++sent_alone_[static_cast<std::size_t>(owner(c))];
  }
  std::vector<std::size_t> next(ranks, 0);
  for (std::size_t r = 1; r < ranks; ++r) next[r] = next[r - 1] + sent_[r - 1];
  route_.resize(receivers.size());
  for (std::size_t k = 0; k < cells.size(); ++k)
    for (std::uint32_t q = receivers_first[k]; q < receivers_first[k + 1]; ++q)
      route_[next[static_cast<std::size_t>(receivers[q])]++] = static_cast<std::uint32_t>(k);
  // In slabs, the routes answer() comes back along: each cell's to its
  // owner, and the alone cells' (each to its owner).
  rank_ = comm.rank();
  route_to_owner_.assign(route_.size(), 0);
  answers_in_.assign(ranks, 0);
  if (!replicated_) {
    for (std::size_t r = 0, j = 0; r < ranks; ++r)
      for (const std::size_t end = j + sent_[r]; j < end; ++j)
        if (owner(cells[route_[j]]) == static_cast<int>(r)) {
          route_to_owner_[j] = 1;
          ++answers_in_[r];
        }
    for (const std::uint32_t c : alone) ++answers_in_[static_cast<std::size_t>(owner(c))];
  }
  alone_route_.clear();
  alone_count_ = alone.size();
  if (replicated_) {
    for (std::size_t r = 0; r < ranks; ++r)
      for (std::size_t k = 0; k < sent_alone_[r]; ++k) alone_route_.push_back(static_cast<std::uint32_t>(k));
  } else {
    next.assign(ranks, 0);
    for (std::size_t r = 1; r < ranks; ++r) next[r] = next[r - 1] + sent_alone_[r - 1];
    alone_route_.resize(alone.size());
    for (std::size_t k = 0; k < alone.size(); ++k)
      alone_route_[next[static_cast<std::size_t>(owner(alone[k]))]++] = static_cast<std::uint32_t>(k);
  }
  first_.assign(first.begin(), first.end());
  // To each rank: the counts of the cells it receives and of its alone
  // cells, the cells, their pieces' counts, the alone cells, then the
  // pieces' keys and values.
  bytes_.resize(ranks);
  std::size_t total_bytes = 0;
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes_[r] = 2 * sizeof(std::uint64_t) + (sent_[r] * 2 + sent_alone_[r]) * sizeof(std::uint32_t) +
                sent_pieces_[r] * (key_bytes_ + w * sizeof(double));
    total_bytes += bytes_[r];
  }
  send_.resize(total_bytes);
  std::byte* out = send_.data();
  for (std::size_t r = 0, begin = 0, alone_begin = 0; r < ranks; begin += sent_[r], alone_begin += sent_alone_[r], ++r) {
    const std::size_t end = begin + sent_[r];
    const std::uint64_t n[2] = {sent_[r], sent_alone_[r]};
    out = put(out, n, 2);
    for (std::size_t j = begin; j < end; ++j) out = put(out, &cells[route_[j]], 1);
    for (std::size_t j = begin; j < end; ++j) {
      const std::uint32_t count = first[route_[j] + 1] - first[route_[j]];
      out = put(out, &count, 1);
    }
    for (std::size_t j = alone_begin; j < alone_begin + sent_alone_[r]; ++j) out = put(out, &alone[alone_route_[j]], 1);
    for (std::size_t j = begin; j < end; ++j)
      for (std::uint32_t p = first[route_[j]]; p < first[route_[j] + 1]; ++p) {
        if (key_bytes_ == sizeof(PieceKey)) {
          out = put(out, &keys[p], 1);
        } else {
          FLOESIM_ASSERT(keys[p] <= 0xffffffffu);
          const std::uint32_t key = static_cast<std::uint32_t>(keys[p]);
          out = put(out, &key, 1);
        }
      }
    for (std::size_t j = begin; j < end; ++j)
      out = put(out, &parts[first[route_[j]] * w], (first[route_[j] + 1] - first[route_[j]]) * w);
  }
  comm.alltoall_bytes(send_, bytes_, receive_, receive_bytes_);
  // The owner's cells, in the order they first arrive, each received cell's
  // slot and count, the alone cells, and every piece's key and values in the
  // order received.
  for (std::uint32_t c : owned_) slot_[c] = 0;
  owned_.clear();
  alone_owned_.clear();
  from_.clear();
  count_.clear();
  keys_.clear();
  values_.clear();
  width_ = width;
  received_.assign(ranks, 0);
  received_pieces_.assign(ranks, 0);
  received_alone_.assign(ranks, 0);
  answers_out_.assign(ranks, 0);
  const std::byte* in = receive_.data();
  for (std::size_t r = 0; r < ranks; ++r) {
    const std::size_t n = static_cast<std::size_t>(at<std::uint64_t>(in, 0));
    const std::size_t n_alone = static_cast<std::size_t>(at<std::uint64_t>(in, 1));
    const std::byte* cell = in + 2 * sizeof(std::uint64_t);
    const std::byte* count = cell + n * sizeof(std::uint32_t);
    const std::byte* alone_cell = count + n * sizeof(std::uint32_t);
    const std::byte* key = alone_cell + n_alone * sizeof(std::uint32_t);
    std::size_t m = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint32_t c = at<std::uint32_t>(cell, j), q = at<std::uint32_t>(count, j);
      FLOESIM_ASSERT(!to_owners_ || owner(c) == comm.rank());
      if (slot_[c] == 0) {
        owned_.push_back(c);
        slot_[c] = static_cast<std::uint32_t>(owned_.size());
      }
      from_.push_back(slot_[c] - 1);
      count_.push_back(q);
      m += q;
      if (!replicated_ && owner(c) == comm.rank()) ++answers_out_[r];
    }
    if (!replicated_) answers_out_[r] += n_alone;
    for (std::size_t j = 0; j < n_alone; ++j) alone_owned_.push_back(at<std::uint32_t>(alone_cell, j));
    received_[r] = n;
    received_pieces_[r] = m;
    received_alone_[r] = n_alone;
    const std::size_t before = keys_.size();
    keys_.resize(before + m);
    values_.resize((before + m) * w);
    if (m > 0) {
      if (key_bytes_ == sizeof(PieceKey)) {
        std::memcpy(keys_.data() + before, key, m * sizeof(PieceKey));
      } else {
        for (std::size_t p = 0; p < m; ++p) keys_[before + p] = at<std::uint32_t>(key, p);
      }
      std::memcpy(values_.data() + before * w, key + m * key_bytes_, m * w * sizeof(double));
    }
    in += receive_bytes_[r];
  }
  // Each cell's pieces: a bucket by cell in the order received (rank order,
  // then the sender's order), then the senders' runs, each in key order,
  // merged by key (stable: equal keys keep that order). Most cells hold one
  // run, already in order.
  order_first_.assign(owned_.size() + 1, 0);
  for (std::size_t j = 0; j < from_.size(); ++j) order_first_[from_[j] + 1] += count_[j];
  for (std::size_t j = 0; j < owned_.size(); ++j) order_first_[j + 1] += order_first_[j];
  order_.resize(keys_.size());
  {
    std::vector<std::uint32_t> at_cell(order_first_.begin(), order_first_.end() - 1);
    for (std::size_t j = 0, p = 0; j < from_.size(); ++j)
      for (std::uint32_t q = 0; q < count_[j]; ++q, ++p) order_[at_cell[from_[j]]++] = static_cast<std::uint32_t>(p);
  }
  const auto by_key = [this](std::uint32_t x, std::uint32_t y) { return keys_[x] < keys_[y]; };
  for (std::size_t j = 0; j < owned_.size(); ++j) {
    const auto begin = order_.begin() + order_first_[j], end = order_.begin() + order_first_[j + 1];
    if (!std::is_sorted(begin, end, by_key)) std::stable_sort(begin, end, by_key);
  }
  sum_pieces();
}

void CellRoutes::open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const double> parts,
                      int width) {
  std::vector<std::uint32_t> first(cells.size() + 1);
  std::vector<PieceKey> keys(cells.size(), 0);
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
  FLOESIM_ASSERT(to_owners_ && out.size() == route_.size());
  // To each rank, the totals of the cells it sent, in the order it sent them.
  send_.resize(from_.size() * sizeof(double));
  bytes_.resize(ranks);
  receive_bytes_.resize(ranks);
  std::byte* message = send_.data();
  for (std::size_t k = 0; k < from_.size(); ++k) {
    const double t = total(from_[k], w);
    message = put(message, &t, 1);
  }
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes_[r] = received_[r] * sizeof(double);
    receive_bytes_[r] = sent_[r] * sizeof(double);
  }
  receive_.resize(route_.size() * sizeof(double));
  comm.alltoall(send_, bytes_, receive_, receive_bytes_);
  for (std::size_t k = 0; k < route_.size(); ++k) out[route_[k]] = at<double>(receive_.data(), k);
}

double CellRoutes::add(const Communicator& comm, std::span<const double> parts, int width, double extra,
                       std::span<const double> alone_totals) {
  const std::size_t ranks = received_.size(), w = static_cast<std::size_t>(width);
  FLOESIM_ASSERT(parts.size() == first_.back() * w && alone_totals.size() == alone_count_);
  // To each owner: `extra`, the values of its cells' pieces in the order of
  // open(), then the totals of its alone cells.
  std::size_t send_total = 0, receive_total = 0;
  bytes_.resize(ranks);
  receive_bytes_.resize(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes_[r] = (1 + sent_pieces_[r] * w + sent_alone_[r]) * sizeof(double);
    receive_bytes_[r] = (1 + received_pieces_[r] * w + received_alone_[r]) * sizeof(double);
    send_total += bytes_[r];
    receive_total += receive_bytes_[r];
  }
  send_.resize(send_total);
  std::byte* out = send_.data();
  for (std::size_t r = 0, begin = 0, alone_begin = 0; r < ranks; begin += sent_[r], alone_begin += sent_alone_[r], ++r) {
    out = put(out, &extra, 1);
    for (std::size_t j = begin; j < begin + sent_[r]; ++j)
      out = put(out, &parts[first_[route_[j]] * w], (first_[route_[j] + 1] - first_[route_[j]]) * w);
    for (std::size_t j = alone_begin; j < alone_begin + sent_alone_[r]; ++j) out = put(out, &alone_totals[alone_route_[j]], 1);
  }
  receive_.resize(receive_total);
  comm.alltoall(send_, bytes_, receive_, receive_bytes_);
  width_ = width;
  values_.resize(keys_.size() * w);
  alone_totals_.resize(alone_owned_.size());
  double sum = 0.0;
  const std::byte* in = receive_.data();
  for (std::size_t r = 0, at_value = 0, at_alone = 0; r < ranks; ++r) {
    sum += at<double>(in, 0);
    const std::size_t m = received_pieces_[r] * w, a = received_alone_[r];
    if (m > 0) std::memcpy(values_.data() + at_value, in + sizeof(double), m * sizeof(double));
    if (a > 0) std::memcpy(alone_totals_.data() + at_alone, in + (1 + m) * sizeof(double), a * sizeof(double));
    at_value += m;
    at_alone += a;
    in += receive_bytes_[r];
  }
  sum_pieces();
  return sum;
}

void CellRoutes::answer(const Communicator& comm, std::span<const double> slab, std::span<double> out,
                        std::span<double> alone_out) {
  const std::size_t ranks = received_.size();
  FLOESIM_ASSERT(!replicated_ && comm.rank() == rank_ && out.size() + 1 == first_.size() &&
                 alone_out.size() == alone_count_);
  const std::size_t me = static_cast<std::size_t>(rank_);
  const std::size_t base = static_cast<std::size_t>(first_row_[me]) * columns_;
  FLOESIM_ASSERT(slab.size() == static_cast<std::size_t>(first_row_[me + 1] - first_row_[me]) * columns_);
  // Every cell of the open comes back once: it named its owner exactly once
  // among its receivers (distinct), an alone cell went to its owner.
  FLOESIM_ASSERT(static_cast<std::size_t>(std::count(route_to_owner_.begin(), route_to_owner_.end(), 1)) == out.size());
  // To each rank, in the order it sent them: the values of the cells of its
  // open it sent here that this rank owns, then of its alone cells here.
  std::size_t send_total = 0, receive_total = 0;
  bytes_.resize(ranks);
  receive_bytes_.resize(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    bytes_[r] = answers_out_[r] * sizeof(double);
    receive_bytes_[r] = answers_in_[r] * sizeof(double);
    send_total += bytes_[r];
    receive_total += receive_bytes_[r];
  }
  send_.resize(send_total);
  std::byte* message = send_.data();
  for (std::size_t r = 0, j = 0, a = 0; r < ranks; ++r) {
    for (const std::size_t end = j + received_[r]; j < end; ++j) {
      const std::uint32_t c = owned_[from_[j]];
      if (owner(c) == rank_) message = put(message, &slab[c - base], 1);
    }
    for (const std::size_t end = a + received_alone_[r]; a < end; ++a) message = put(message, &slab[alone_owned_[a] - base], 1);
  }
  receive_.resize(receive_total);
  comm.alltoall(send_, bytes_, receive_, receive_bytes_);
  // Back along this rank's routes, rank by rank as sent.
  std::size_t v = 0;
  for (std::size_t r = 0, j = 0, a = 0; r < ranks; ++r) {
    for (const std::size_t end = j + sent_[r]; j < end; ++j)
      if (route_to_owner_[j]) out[route_[j]] = at<double>(receive_.data(), v++);
    for (const std::size_t end = a + sent_alone_[r]; a < end; ++a) alone_out[alone_route_[a]] = at<double>(receive_.data(), v++);
  }
  FLOESIM_ASSERT(v * sizeof(double) == receive_total);
}

std::size_t CellRoutes::received_from_others() const {
  std::size_t bytes = 0;
  for (std::size_t r = 0; r < receive_bytes_.size(); ++r)
    if (static_cast<int>(r) != rank_) bytes += receive_bytes_[r];
  return bytes;
}

}  // namespace floesim::parallel
