#pragma once
// The ranks of a distributed run and what they say to each other
// (docs/parallel.md). A Communicator is a value passed down to what splits
// work (the Simulation, the run loop); there is no global one. Default
// constructed it is the serial run: rank 0 of 1, and every operation below is
// a copy or nothing. Session::world() gives the ranks `mpirun` started.
//
// Every operation that exchanges data (gathers, sums, broadcast, together)
// is collective: all ranks call it, in the same order, with the same counts
// where a count is an argument. The results do not depend on
// the number of ranks: gathers concatenate the ranks' parts in rank order, so
// a list split in contiguous shares (share()) comes back in its serial order,
// and reductions here are only of integers (exact in any order) and the
// largest of doubles (a max picks one of the values: exact in any order): a
// sum of doubles goes through ExactSum's integer limbs (core/exact_sum.hpp).
//
// Errors: a failure on one rank must stop every rank with the same message
// and exit code. together() runs a piece of work on every rank and then
// agrees: if any rank threw, every rank throws the error of the lowest
// failing rank (same kind: InputError, RunError, out of memory, or another
// exception, and same message). A rank that fails alone inside a collective
// cannot agree (the others wait in the collective): Session::abort_alone()
// ends the whole run then (MPI_Abort), after saying why.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/exact_sum.hpp"

namespace floesim::parallel {

// A contiguous share [begin, end) of n items.
struct Range {
  std::size_t begin = 0, end = 0;
  std::size_t size() const { return end - begin; }
};

// Share `rank` of n items among `ranks`: contiguous, in rank order, sizes
// differing by at most one (the first n % ranks shares take one more).
Range share(std::size_t n, int rank, int ranks);

// Values sent as their bytes: plain data of numbers, which is what
// trivially copyable says, except that Eigen's fixed-size vectors (a Vec2 is
// two doubles held inline) declare their own copy and so are not
// "trivially" copyable to the compiler, though their bytes are their value.
template <class T>
inline constexpr bool kSentAsBytes = std::is_trivially_destructible_v<T> && std::is_standard_layout_v<T>;

class Communicator {
public:
  Communicator();  // the serial run: rank 0 of 1
  ~Communicator();
  Communicator(const Communicator&);
  Communicator& operator=(const Communicator&);

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool serial() const { return size_ == 1; }
  // Rank 0 writes the run file and speaks for the run (docs/parallel.md: Debian's HDF5 is serial).
  bool writer() const { return rank_ == 0; }

  // This rank's share of n items (parallel::share).
  Range share(std::size_t n) const { return parallel::share(n, rank_, size_); }

  // Every rank's `mine` concatenated in rank order, on every rank (T: kSentAsBytes).
  template <class T>
  std::vector<T> allgather(std::span<const T> mine) const {
    static_assert(kSentAsBytes<T>);
    std::vector<std::size_t> counts;
    std::vector<std::byte> all = allgather_bytes({reinterpret_cast<const std::byte*>(mine.data()), mine.size_bytes()}, counts);
    std::vector<T> out(all.size() / sizeof(T));  // T's default, overwritten by the bytes
    if (!all.empty()) std::memcpy(static_cast<void*>(out.data()), all.data(), all.size());
    return out;
  }
  // Each rank holds `values` with its share `mine` of them up to date; on
  // exit every rank's copy equals the owners' values everywhere. Rank r's
  // share is share(values.size(), r, size()).
  // One collective call: every share's size is known to all.
  template <class T>
  void complete_shares(std::vector<T>& values) const {
    static_assert(kSentAsBytes<T>);
    if (serial()) return;
    std::vector<std::size_t> counts(static_cast<std::size_t>(size_));
    for (int r = 0; r < size_; ++r) counts[static_cast<std::size_t>(r)] = parallel::share(values.size(), r, size_).size() * sizeof(T);
    const Range mine = share(values.size());
    const std::vector<std::byte> all = allgather_known(
        {reinterpret_cast<const std::byte*>(values.data() + mine.begin), mine.size() * sizeof(T)}, counts);
    std::memcpy(static_cast<void*>(values.data()), all.data(), all.size());
  }

  // The same for values owned by any rank: owner[i] (known to all) holds
  // values[i] up to date; on exit every rank's copy holds the owners'
  // values everywhere. One collective call.
  template <class T>
  void complete_owned(std::vector<T>& values, std::span<const int> owner) const {
    static_assert(kSentAsBytes<T>);
    if (serial()) return;
    std::vector<std::size_t> counts(static_cast<std::size_t>(size_), 0);
    std::vector<T> mine;
    for (std::size_t i = 0; i < values.size(); ++i) {
      counts[static_cast<std::size_t>(owner[i])] += sizeof(T);
      if (owner[i] == rank_) mine.push_back(values[i]);
    }
    const std::vector<std::byte> all = allgather_known(std::as_bytes(std::span<const T>(mine)), counts);
    // Rank r's values come in the order of its items.
    std::vector<std::size_t> at(counts.size(), 0);
    for (std::size_t r = 1; r < counts.size(); ++r) at[r] = at[r - 1] + counts[r - 1];
    for (std::size_t i = 0; i < values.size(); ++i) {
      std::size_t& from = at[static_cast<std::size_t>(owner[i])];
      std::memcpy(static_cast<void*>(&values[i]), all.data() + from, sizeof(T));
      from += sizeof(T);
    }
  }

  // Items held by one rank and read by another: values[i] is valid on rank
  // held_by[i] and is wanted on rank wanted_by[i] (both arrays the same on
  // every rank). Each item whose two ranks differ goes from the first to the
  // second, in floe order from each rank (HandOver); values the rank neither
  // holds nor wants are left as they are. One all-to-all, none when no item
  // changes rank (every rank sees that alike).
  template <class T>
  void hand_over(std::vector<T>& values, std::span<const int> held_by, std::span<const int> wanted_by) const;
  // hand_over for several arrays indexed alike (item i is values[i] of
  // each): each item that changes rank carries its values from every array
  // together, in one all-to-all (none when no item changes rank).
  template <class... T>
  void hand_over_each(std::span<const int> held_by, std::span<const int> wanted_by, std::vector<T>&... values) const;

  // Items sent to the ranks that want them, when only the sender knows who
  // does: to[s] lists the items (indices into `values`) this rank sends
  // rank s, which it holds current; each rank writes every item it
  // receives into its `values`. Records of the index (4 B) and the value,
  // one alltoall_bytes (two calls: the sizes, then the records). Returns
  // the items this rank received, by sender in rank order and in each
  // sender's order within.
  template <class T>
  std::vector<std::uint32_t> send_items(std::vector<T>& values,
                                        const std::vector<std::vector<std::uint32_t>>& to) const;

  // Bytes: every rank's `mine` concatenated in rank order; `counts` gets
  // each rank's byte count. Two collective calls (the counts, then the bytes).
  std::vector<std::byte> allgather_bytes(std::span<const std::byte> mine, std::vector<std::size_t>& counts) const;
  // Every rank's message `mine`, each read back by `read` (a function of
  // one message's bytes), in rank order: one allgather_bytes.
  template <class Read>
  auto allgather_parts(std::span<const std::byte> mine, Read read) const {
    std::vector<std::size_t> counts;
    const std::vector<std::byte> all = allgather_bytes(mine, counts);
    std::vector<decltype(read(std::span<const std::byte>{}))> parts;
    parts.reserve(counts.size());
    std::size_t from = 0;
    for (const std::size_t n : counts) {
      parts.push_back(read(std::span<const std::byte>(all.data() + from, n)));
      from += n;
    }
    return parts;
  }
  // The same when every rank's count is known to all (`counts`): one call,
  // none when every count is zero (every rank skips it alike; so a gather
  // of nothing from anyone costs allgather_bytes the counts' call only).
  std::vector<std::byte> allgather_known(std::span<const std::byte> mine, const std::vector<std::size_t>& counts) const;
  // Both into `out`, whose memory is reused (a gather made at every step
  // then allocates, and the system zeroes fresh pages, only when it grows).
  void allgather_bytes(std::span<const std::byte> mine, std::vector<std::size_t>& counts,
                       std::vector<std::byte>& out) const;
  void allgather_known(std::span<const std::byte> mine, const std::vector<std::size_t>& counts,
                       std::vector<std::byte>& out) const;

  // Bytes, in place: `all` holds the ranks' parts in rank order, counts[r]
  // bytes for rank r (known to all); this rank's part is in place on entry,
  // every rank's on exit. One collective call (none when every count is zero).
  void allgather_in_place(std::span<std::byte> all, const std::vector<std::size_t>& counts) const;

  // Bytes from every rank to every rank (a transpose): `send` holds this
  // rank's parts for ranks 0..N-1 in order, send_counts[s] bytes for rank s;
  // `receive` gets the parts from ranks 0..N-1 in order, receive_counts[s]
  // bytes from rank s. Both sides know every count. One collective call.
  void alltoall(std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) const;
  // The same when the receiving side does not know its counts: they are
  // exchanged first (receive_counts gets receive_counts[s] bytes from rank
  // s), and `receive` is resized to their total (its memory reused, as in
  // allgather_bytes). Two collective calls.
  void alltoall_bytes(std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                      std::vector<std::byte>& receive, std::vector<std::size_t>& receive_counts) const;

  // The sum of one integer over the ranks (in rank order; exact).
  long long sum(long long value) const;
  // The least of one integer over the ranks.
  long long min(long long value) const;
  // The largest of one double over the ranks (exact: one of the values,
  // whichever order the ranks are combined in). One call.
  double max(double value) const;
  // Exact sums over the ranks: on exit each of `sums` holds the sum of every
  // rank's terms (its own and the others' accumulators merged), and each of
  // `counts` the sum of every rank's; the same on every rank, and the same
  // bits whatever the number of ranks and whichever rank added which term.
  // One collective call: an integer sum of the accumulators' limbs
  // (ExactSum::limbs(), 70 int64s each) and the counts.
  void sum(std::span<ExactSum> sums, std::span<long long> counts = {}) const;
  // True on every rank when it is true on any.
  bool any(bool value) const { return sum(value ? 1 : 0) > 0; }
  // The same bytes on every rank as on `root`.
  std::vector<std::byte> broadcast(std::span<const std::byte> bytes, int root) const;

  // What this rank has said and heard since the start (zero when serial):
  // collective calls, bytes received, and the wall time inside them (the
  // transfer and the wait for the slowest rank).
  struct Traffic {
    long long calls = 0, bytes = 0;
    double seconds = 0.0;
  };
  Traffic traffic() const;

  // Runs f() on every rank and agrees on failure as said above. Returns
  // normally on every rank only when f() returned on every rank.
  template <class F>
  void together(F&& f) const {
    std::exception_ptr failure;
    try {
      f();
    } catch (...) {
      failure = std::current_exception();
    }
    agree(failure);
  }
  // together(f), and in the same collective call whether flag() is true on
  // any rank (flag() runs on each rank after f() returned there): true on
  // every rank when it is true on any. One call instead of two (a step's
  // agreement on failures and on stopping).
  template <class F, class G>
  bool together_any(F&& f, G&& flag) const {
    std::exception_ptr failure;
    bool value = false;
    try {
      f();
      value = flag();
    } catch (...) {
      failure = std::current_exception();
    }
    return agree(failure, value);
  }
  // The agreement of together(), for a failure caught by the caller (null:
  // none here); returns whether `value` is true on any rank.
  bool agree(std::exception_ptr failure, bool value = false) const;
  // True once the ranks have agreed on a failure (the error being thrown is the run's, on every rank).
  bool failure_agreed() const;

  struct Impl;  // MPI's communicator, in comm.cpp

private:
  std::shared_ptr<Impl> impl_;  // null: serial
  int rank_ = 0, size_ = 1;
  friend class Session;
};

// The plan of Communicator::hand_over for one rank (plain data, so that
// simulated ranks can be tested in one process): the items this rank sends,
// grouped by receiving rank in rank order and in floe order within each,
// those it receives, grouped by sending rank alike, and the byte counts.
struct HandOver {
  std::vector<std::uint32_t> send, receive;
  std::vector<std::size_t> send_bytes, receive_bytes;  // per rank
  bool any = false;  // some item changes rank (on any rank: the same everywhere)
};
HandOver plan_hand_over(std::span<const int> held_by, std::span<const int> wanted_by, int rank, int ranks,
                        std::size_t item_bytes);

template <class T>
void Communicator::hand_over(std::vector<T>& values, std::span<const int> held_by,
                             std::span<const int> wanted_by) const {
  hand_over_each(held_by, wanted_by, values);
}

template <class... T>
void Communicator::hand_over_each(std::span<const int> held_by, std::span<const int> wanted_by,
                                  std::vector<T>&... values) const {
  static_assert((kSentAsBytes<T> && ...));
  if (serial()) return;
  constexpr std::size_t item = (sizeof(T) + ... + std::size_t{0});
  const HandOver plan = plan_hand_over(held_by, wanted_by, rank_, size_, item);
  if (!plan.any) return;
  // An item's record: its value from each array, in the arrays' order.
  std::vector<std::byte> out(plan.send.size() * item), in(plan.receive.size() * item);
  std::byte* to = out.data();
  for (const std::uint32_t i : plan.send)
    ((std::memcpy(to, static_cast<const void*>(&values[i]), sizeof(T)), to += sizeof(T)), ...);
  alltoall(out, plan.send_bytes, in, plan.receive_bytes);
  const std::byte* from = in.data();
  for (const std::uint32_t i : plan.receive)
    ((std::memcpy(static_cast<void*>(&values[i]), from, sizeof(T)), from += sizeof(T)), ...);
}

template <class T>
std::vector<std::uint32_t> Communicator::send_items(std::vector<T>& values,
                                                    const std::vector<std::vector<std::uint32_t>>& to) const {
  static_assert(kSentAsBytes<T>);
  if (serial()) return {};
  constexpr std::size_t record = sizeof(std::uint32_t) + sizeof(T);
  std::vector<std::size_t> send_bytes(static_cast<std::size_t>(size_), 0);
  std::size_t total = 0;
  for (std::size_t s = 0; s < to.size(); ++s) total += to[s].size();
  std::vector<std::byte> out(total * record);
  std::byte* at = out.data();
  for (std::size_t s = 0; s < to.size(); ++s) {
    send_bytes[s] = to[s].size() * record;
    for (const std::uint32_t i : to[s]) {
      std::memcpy(at, &i, sizeof(i));
      std::memcpy(at + sizeof(i), static_cast<const void*>(&values[i]), sizeof(T));
      at += record;
    }
  }
  std::vector<std::byte> in;
  std::vector<std::size_t> receive_bytes;
  alltoall_bytes(out, send_bytes, in, receive_bytes);
  std::vector<std::uint32_t> received(in.size() / record);
  for (std::size_t k = 0; k < received.size(); ++k) {
    const std::byte* from = in.data() + k * record;
    std::memcpy(&received[k], from, sizeof(std::uint32_t));
    std::memcpy(static_cast<void*>(&values[received[k]]), from + sizeof(std::uint32_t), sizeof(T));
  }
  return received;
}

// The MPI environment of a process: MPI_Init when the process was started
// by mpirun (or another launcher that sets the PMI/PMIx variables), else
// nothing (a serial run needs no MPI library at run time). One per process,
// owned by main's command; MPI_Finalize on destruction.
class Session {
public:
  Session();
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const Communicator& world() const { return world_; }
  // True when floesim was built with MPI (FLOESIM_MPI).
  static bool built_with_mpi();
  // Ranks on this node (for the default threads per rank): 1 when serial.
  int local_ranks() const { return local_ranks_; }

  // For an exception that the ranks did not agree on (world().failure_agreed()
  // is false) in a run of several ranks: prints "floesim: rank R: MESSAGE" on
  // stderr and ends every rank with `exit_code` (MPI_Abort). Returns when
  // the run is serial or the failure was agreed.
  void abort_alone(std::exception_ptr failure, int exit_code) const;

private:
  Communicator world_;
  bool initialised_ = false;
  int local_ranks_ = 1;
};

}  // namespace floesim::parallel
