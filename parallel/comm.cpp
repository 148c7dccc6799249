#include "parallel/comm.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <stdexcept>

#include "core/error.hpp"

#ifdef FLOESIM_HAVE_MPI
// MPI's C interface only (the C++ bindings are deprecated and need their own library).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace floesim::parallel {

struct Communicator::Impl {
#ifdef FLOESIM_HAVE_MPI
  MPI_Comm comm = MPI_COMM_NULL;
#endif
  bool agreed = false;  // a failure was agreed on (together()); the run is ending
  Communicator::Traffic traffic;
};

namespace {
// Counts one collective call into `traffic` when it goes out of scope.
class Counted {
public:
  Counted(Communicator::Traffic& t, long long bytes) : t_(t), start_(std::chrono::steady_clock::now()) {
    t_.calls += 1;
    t_.bytes += bytes;
  }
  ~Counted() { t_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  Counted(const Counted&) = delete;
  Counted& operator=(const Counted&) = delete;

private:
  Communicator::Traffic& t_;
  std::chrono::steady_clock::time_point start_;
};
}  // namespace

namespace {

// The kinds of failure the command line tells apart (apps/main.cpp's exit codes).
enum class Kind : std::uint8_t { input = 1, run = 2, memory = 3, other = 4 };

struct Described {
  Kind kind = Kind::other;
  std::string message;
};

Described describe(std::exception_ptr failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    return {Kind::input, e.what()};
  } catch (const RunError& e) {
    return {Kind::run, e.what()};
  } catch (const std::bad_alloc&) {
    return {Kind::memory, "out of memory"};
  } catch (const std::exception& e) {
    return {Kind::other, e.what()};
  } catch (...) {
    return {Kind::other, "unknown exception"};
  }
}

[[noreturn]] void throw_described(const Described& d) {
  switch (d.kind) {
    case Kind::input: throw InputError(d.message);
    case Kind::run: throw RunError(d.message);
    case Kind::memory: throw std::bad_alloc();
    case Kind::other: break;
  }
  throw std::runtime_error(d.message);
}

#ifdef FLOESIM_HAVE_MPI
void check(int code, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw RunError(std::string("MPI: ") + what + " failed: " + std::string(text, static_cast<std::size_t>(length)));
}

// MPI's v-collectives take int sizes and offsets: per-rank byte counts laid
// end to end; returns the total. `what` names the collective in the error
// for a total beyond INT_MAX (2 GiB).
std::size_t displacements(const std::vector<std::size_t>& counts, std::vector<int>& sizes, std::vector<int>& offsets,
                          const char* what) {
  sizes.resize(counts.size());
  offsets.resize(counts.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    if (total + counts[r] > static_cast<std::size_t>(INT_MAX))
      throw RunError(std::string("MPI: ") + what + " of more than 2 GiB (" + std::to_string(total + counts[r]) +
                     " bytes) is not supported");
    sizes[r] = static_cast<int>(counts[r]);
    offsets[r] = static_cast<int>(total);
    total += counts[r];
  }
  return total;
}

// Set by mpirun (Open MPI), or by a PMI/PMIx launcher (srun, hydra).
bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}
#endif

}  // namespace

Communicator::Communicator() = default;
Communicator::~Communicator() = default;
Communicator::Communicator(const Communicator&) = default;
Communicator& Communicator::operator=(const Communicator&) = default;

Range share(std::size_t n, int rank, int ranks) {
  const auto p = static_cast<std::size_t>(ranks), r = static_cast<std::size_t>(rank);
  const std::size_t base = n / p, extra = n % p;
  const std::size_t begin = r * base + std::min(r, extra);
  return {begin, begin + base + (r < extra ? 1 : 0)};
}

HandOver plan_hand_over(std::span<const int> held_by, std::span<const int> wanted_by, int rank, int ranks,
                        std::size_t item_bytes) {
  HandOver plan;
  const auto p = static_cast<std::size_t>(ranks);
  std::vector<std::size_t> sent(p, 0), received(p, 0);
  for (std::size_t i = 0; i < held_by.size(); ++i) {
    if (held_by[i] == wanted_by[i]) continue;
    plan.any = true;
    if (held_by[i] == rank) ++sent[static_cast<std::size_t>(wanted_by[i])];
    if (wanted_by[i] == rank) ++received[static_cast<std::size_t>(held_by[i])];
  }
  // Grouped by rank, floe order within a group: each group's start, then a
  // second pass in floe order places every item.
  std::vector<std::size_t> send_at(p, 0), receive_at(p, 0);
  for (std::size_t r = 1; r < p; ++r) {
    send_at[r] = send_at[r - 1] + sent[r - 1];
    receive_at[r] = receive_at[r - 1] + received[r - 1];
  }
  plan.send.resize(send_at[p - 1] + sent[p - 1]);
  plan.receive.resize(receive_at[p - 1] + received[p - 1]);
  for (std::size_t i = 0; i < held_by.size(); ++i) {
    if (held_by[i] == wanted_by[i]) continue;
    if (held_by[i] == rank) plan.send[send_at[static_cast<std::size_t>(wanted_by[i])]++] = static_cast<std::uint32_t>(i);
    if (wanted_by[i] == rank) plan.receive[receive_at[static_cast<std::size_t>(held_by[i])]++] = static_cast<std::uint32_t>(i);
  }
  plan.send_bytes.resize(p);
  plan.receive_bytes.resize(p);
  for (std::size_t r = 0; r < p; ++r) {
    plan.send_bytes[r] = sent[r] * item_bytes;
    plan.receive_bytes[r] = received[r] * item_bytes;
  }
  return plan;
}

std::vector<std::byte> Communicator::allgather_bytes(std::span<const std::byte> mine,
                                                     std::vector<std::size_t>& counts) const {
  std::vector<std::byte> out;
  allgather_bytes(mine, counts, out);
  return out;
}

std::vector<std::byte> Communicator::allgather_known(std::span<const std::byte> mine,
                                                     const std::vector<std::size_t>& counts) const {
  std::vector<std::byte> out;
  allgather_known(mine, counts, out);
  return out;
}

void Communicator::allgather_bytes(std::span<const std::byte> mine, std::vector<std::size_t>& counts,
                                   std::vector<std::byte>& out) const {
  if (serial() || !impl_) {
    counts.assign(1, mine.size());
    out.assign(mine.begin(), mine.end());
    return;
  }
#ifdef FLOESIM_HAVE_MPI
  std::vector<long long> all_counts(static_cast<std::size_t>(size_));
  {
    Counted counted(impl_->traffic, static_cast<long long>(sizeof(long long)) * size_);
    long long count = static_cast<long long>(mine.size());
    check(MPI_Allgather(&count, 1, MPI_LONG_LONG, all_counts.data(), 1, MPI_LONG_LONG, impl_->comm), "MPI_Allgather");
  }
  counts.assign(all_counts.begin(), all_counts.end());
  allgather_known(mine, counts, out);
#endif
}

void Communicator::allgather_known(std::span<const std::byte> mine, const std::vector<std::size_t>& counts,
                                   std::vector<std::byte>& out) const {
  if (serial() || !impl_) {
    out.assign(mine.begin(), mine.end());
    return;
  }
#ifdef FLOESIM_HAVE_MPI
  std::vector<int> sizes, offsets;
  const std::size_t total = displacements(counts, sizes, offsets, "a gather");
  out.resize(total);  // a buffer kept by the caller: filled only where it grows
  // Every rank knows every count: when all are zero all ranks skip the call alike.
  if (total == 0) return;
  Counted counted(impl_->traffic, static_cast<long long>(total));
  check(MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_BYTE, out.data(), sizes.data(),
                       offsets.data(), MPI_BYTE, impl_->comm),
        "MPI_Allgatherv");
#endif
}

void Communicator::allgather_in_place(std::span<std::byte> all, const std::vector<std::size_t>& counts) const {
  if (serial() || !impl_) return;
#ifdef FLOESIM_HAVE_MPI
  std::vector<int> sizes, offsets;
  const std::size_t total = displacements(counts, sizes, offsets, "a gather");
  FLOESIM_ASSERT(total <= all.size());
  if (total == 0) return;  // all ranks alike, as allgather_known
  Counted counted(impl_->traffic, static_cast<long long>(total - counts[static_cast<std::size_t>(rank_)]));
  check(MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_BYTE, all.data(), sizes.data(), offsets.data(), MPI_BYTE, impl_->comm),
        "MPI_Allgatherv");
#else
  (void)all;
  (void)counts;
#endif
}

void Communicator::alltoall(std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                            std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) const {
  if (serial() || !impl_) {
    std::copy(send.begin(), send.end(), receive.begin());
    return;
  }
#ifdef FLOESIM_HAVE_MPI
  std::vector<int> send_sizes, send_offsets, receive_sizes, receive_offsets;
  const std::size_t sent = displacements(send_counts, send_sizes, send_offsets, "an all-to-all");
  FLOESIM_ASSERT(sent <= send.size());
  (void)sent;
  const std::size_t received = displacements(receive_counts, receive_sizes, receive_offsets, "an all-to-all");
  FLOESIM_ASSERT(received <= receive.size());
  Counted counted(impl_->traffic, static_cast<long long>(received));
  check(MPI_Alltoallv(send.data(), send_sizes.data(), send_offsets.data(), MPI_BYTE, receive.data(),
                      receive_sizes.data(), receive_offsets.data(), MPI_BYTE, impl_->comm),
        "MPI_Alltoallv");
#else
  (void)send_counts;
  (void)receive_counts;
#endif
}

void Communicator::alltoall_bytes(std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                                  std::vector<std::byte>& receive, std::vector<std::size_t>& receive_counts) const {
  if (serial() || !impl_) {
    receive_counts.assign(1, send.size());
    receive.assign(send.begin(), send.end());
    return;
  }
  // The counts: one long long from every rank to every rank.
  const std::size_t n = static_cast<std::size_t>(size_);
  std::vector<long long> out(n), in(n);
  for (std::size_t r = 0; r < n; ++r) out[r] = static_cast<long long>(send_counts[r]);
  const std::vector<std::size_t> one(n, sizeof(long long));
  alltoall(std::as_bytes(std::span<const long long>(out)), one, std::as_writable_bytes(std::span<long long>(in)), one);
  receive_counts.assign(in.begin(), in.end());
  std::size_t total = 0;
  for (std::size_t c : receive_counts) total += c;
  receive.resize(total);  // a buffer kept by the caller: filled only where it grows
  alltoall(send, send_counts, receive, receive_counts);
}

#ifdef FLOESIM_HAVE_MPI
namespace {
// One integer reduced over the ranks by `op` (MPI_SUM, MPI_MIN), one call.
long long reduce_one(MPI_Comm comm, Communicator::Traffic& traffic, int ranks, long long value, MPI_Op op) {
  Counted counted(traffic, static_cast<long long>(sizeof(long long)) * ranks);
  long long out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_LONG_LONG, op, comm), "MPI_Allreduce");
  return out;
}
}  // namespace
#endif

long long Communicator::sum(long long value) const {
  if (serial() || !impl_) return value;
#ifdef FLOESIM_HAVE_MPI
  return reduce_one(impl_->comm, impl_->traffic, size_, value, MPI_SUM);
#else
  return value;
#endif
}

long long Communicator::min(long long value) const {
  if (serial() || !impl_) return value;
#ifdef FLOESIM_HAVE_MPI
  return reduce_one(impl_->comm, impl_->traffic, size_, value, MPI_MIN);
#else
  return value;
#endif
}

double Communicator::max(double value) const {
  if (serial() || !impl_) return value;
#ifdef FLOESIM_HAVE_MPI
  Counted counted(impl_->traffic, static_cast<long long>(sizeof(double)) * size_);
  double out = 0.0;
  check(MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, impl_->comm), "MPI_Allreduce");
  return out;
#else
  return value;
#endif
}

void Communicator::sum(std::span<ExactSum> sums, std::span<long long> counts) const {
  if (serial() || !impl_) return;
#ifdef FLOESIM_HAVE_MPI
  // Normalised limbs are below 2^32 (the top one and the counters hold
  // small integers): an int64 sum over fewer than 2^30 ranks cannot
  // overflow, and integer addition gives the same words in any order.
  constexpr std::size_t w = ExactSum::kWords;
  std::vector<std::int64_t> words(sums.size() * w + counts.size());
  for (std::size_t j = 0; j < sums.size(); ++j) {
    const std::span<const std::int64_t> limbs = sums[j].limbs();
    std::copy(limbs.begin(), limbs.end(), words.begin() + static_cast<std::ptrdiff_t>(j * w));
  }
  std::copy(counts.begin(), counts.end(), words.begin() + static_cast<std::ptrdiff_t>(sums.size() * w));
  if (words.size() > static_cast<std::size_t>(INT_MAX)) throw RunError("MPI: too many exact sums in one call");
  {
    Counted counted(impl_->traffic, static_cast<long long>(words.size() * sizeof(std::int64_t)) * size_);
    check(MPI_Allreduce(MPI_IN_PLACE, words.data(), static_cast<int>(words.size()), MPI_INT64_T, MPI_SUM, impl_->comm),
          "MPI_Allreduce");
  }
  for (std::size_t j = 0; j < sums.size(); ++j)
    sums[j] = ExactSum::from_limbs(std::span<const std::int64_t>(words.data() + j * w, w));
  std::copy(words.begin() + static_cast<std::ptrdiff_t>(sums.size() * w), words.end(), counts.begin());
#else
  (void)sums;
  (void)counts;
#endif
}

std::vector<std::byte> Communicator::broadcast(std::span<const std::byte> bytes, int root) const {
  if (serial() || !impl_) return {bytes.begin(), bytes.end()};
#ifdef FLOESIM_HAVE_MPI
  long long count = static_cast<long long>(bytes.size());
  Counted counted(impl_->traffic, 0);
  check(MPI_Bcast(&count, 1, MPI_LONG_LONG, root, impl_->comm), "MPI_Bcast");
  impl_->traffic.bytes += count;
  if (count > INT_MAX) throw RunError("MPI: a broadcast of more than 2 GiB is not supported");
  std::vector<std::byte> out(static_cast<std::size_t>(count));
  if (rank_ == root) std::copy(bytes.begin(), bytes.end(), out.begin());
  check(MPI_Bcast(out.data(), static_cast<int>(count), MPI_BYTE, root, impl_->comm), "MPI_Bcast");
  return out;
#else
  return {};
#endif
}

bool Communicator::agree(std::exception_ptr failure, bool value) const {
  if (serial() || !impl_) {
    if (failure) std::rethrow_exception(failure);
    return value;
  }
#ifdef FLOESIM_HAVE_MPI
  // The lowest failing rank speaks: min over (rank if failed, else size);
  // and the value is true on some rank when min over (value ? 0 : 1) is 0.
  int mine[2] = {failure ? rank_ : size_, value ? 0 : 1}, least[2] = {size_, 1};
  {
    Counted counted(impl_->traffic, static_cast<long long>(sizeof(mine)) * size_);
    check(MPI_Allreduce(mine, least, 2, MPI_INT, MPI_MIN, impl_->comm), "MPI_Allreduce");
  }
  const int first = least[0];
  if (first == size_) return least[1] == 0;
  std::vector<std::byte> said;
  if (rank_ == first) {
    const Described d = describe(failure);
    said.push_back(static_cast<std::byte>(d.kind));
    const auto* text = reinterpret_cast<const std::byte*>(d.message.data());
    said.insert(said.end(), text, text + d.message.size());
  }
  said = broadcast(said, first);
  impl_->agreed = true;
  if (rank_ == first) std::rethrow_exception(failure);  // the original, with its full type
  Described d;
  d.kind = static_cast<Kind>(said.at(0));
  d.message.assign(reinterpret_cast<const char*>(said.data()) + 1, said.size() - 1);
  throw_described(d);
#else
  if (failure) std::rethrow_exception(failure);
  return value;
#endif
}

bool Communicator::failure_agreed() const { return impl_ && impl_->agreed; }

Communicator::Traffic Communicator::traffic() const { return impl_ ? impl_->traffic : Traffic{}; }

Session::Session() {
#ifdef FLOESIM_HAVE_MPI
  if (!launched_by_mpi()) return;
  // A rank waiting in a collective yields its core instead of spinning
  // (Open MPI's default spins): on cores shared with other work, or with
  // more ranks than cores, a spinning rank takes the slices the rank it waits
  // for needs (the passive OpenMP waits of apps/main.cpp, for MPI). Unless
  // the user chose (OMPI_MCA_mpi_yield_when_idle=0 for dedicated cores).
  setenv("OMPI_MCA_mpi_yield_when_idle", "1", 0);
  // Only the main thread calls MPI (OpenMP loops do not).
  int provided = 0;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  initialised_ = true;
  auto impl = std::make_shared<Communicator::Impl>();
  impl->comm = MPI_COMM_WORLD;
  // Errors come back as codes (check() turns them into RunError), not an abort.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &world_.rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &world_.size_);
  world_.impl_ = std::move(impl);
  MPI_Comm node;
  if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) == MPI_SUCCESS) {
    MPI_Comm_size(node, &local_ranks_);
    MPI_Comm_free(&node);
  }
#endif
}

Session::~Session() {
#ifdef FLOESIM_HAVE_MPI
  if (initialised_) MPI_Finalize();
#endif
}

bool Session::built_with_mpi() {
#ifdef FLOESIM_HAVE_MPI
  return true;
#else
  return false;
#endif
}

void Session::abort_alone(std::exception_ptr failure, int exit_code) const {
  if (world_.serial() || !initialised_ || world_.failure_agreed()) return;
#ifdef FLOESIM_HAVE_MPI
  std::fprintf(stderr, "floesim: rank %d of %d failed alone, ending every rank: %s\n", world_.rank(), world_.size(),
               describe(failure).message.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, exit_code);
#else
  (void)failure;
  (void)exit_code;
#endif
}

}  // namespace floesim::parallel
