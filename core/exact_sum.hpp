#pragma once
// An exact sum of doubles, independent of the order of its terms (a
// "superaccumulator", after Demmel and Nguyen's and ExBLAS's: the whole
// exponent range of the doubles held as one fixed-point integer).
//
// What it is for: a sum over the floes that must give the same bits however
// the floes are split between ranks and in whatever order the ranks' parts
// are combined (docs/parallel.md, "Exact sums"). Floating-point addition is
// not associative; integer addition is. Every finite double is an integer
// multiple of 2^-1074 (the least subnormal) below 2^1024, so
//
//   x = m 2^(e - 1075)   (normal: 2^52 <= m < 2^53, 1 <= e <= 2046; subnormal: m < 2^52, and 2^-1074 m)
//
// is the integer m 2^i, i = max(e - 1, 0), in units of 2^-1074. The
// accumulator holds the integer S = sum x / 2^-1074 exactly, as limbs of
// kBits = 32 bits: S = sum_k limb[k] 2^(32 k), each limb a signed int64.
// Adding x adds the 53-bit m shifted by i into the three limbs from i / 32
// on, each a part below 2^33: 2^29 adds never overflow an int64 limb, and
// every kMaxPending adds the limbs are normalised (carries moved up, each
// limb but the top brought into [0, 2^32)). The order of the adds changes
// the limbs before normalisation, never S, and normalisation gives the same
// limbs for the same S: so value() is a function of the multiset of terms.
//
// value() is S 2^-1074 correctly rounded to the nearest double, ties to
// even (IEEE's default rounding), +-inf when that is 2^1024 or beyond.
//
// Ranks combine accumulators by adding their limbs as integers (an MPI_SUM
// of int64, in any order: parallel::Communicator::sum): limbs() gives the
// normalised limbs (each below 2^32 but the top one), so up to 2^30 of
// them add without overflow; from_limbs() takes such a sum back.
//
// Non-finite terms are counted, not added (they would have no place in S):
// three more int64s after the limbs hold the numbers of +inf, -inf and NaN
// terms, summed by ranks with the limbs. value() is NaN when a NaN was added
// or both infinities were, else +-inf when one was, as the plain sum is.
//
// Cost: an add is a few integer operations on three limbs (no branch on the
// data but the rare non-finite one); an accumulator is 568 bytes (70 words
// and a counter of adds).

#include <array>
#include <bit>
#include <cstdint>
#include <span>

namespace floesim {

class ExactSum {
public:
  static constexpr int kBits = 32;  // bits of S per limb
  // Limb k holds S's bits [32 k, 32 k + 32): the largest finite double's
  // top bit is bit 2097 (limb 65), and one limb more takes the carries of
  // sums up to 2^1056 or so (far beyond 2^1024: any such sum is +-inf).
  static constexpr int kLimbs = 67;
  static constexpr int kCounters = 3;  // numbers of +inf, -inf and NaN terms, after the limbs
  static constexpr int kWords = kLimbs + kCounters;

  ExactSum() = default;
  explicit ExactSum(double x) { add(x); }

  void add(double x) {
    const auto bits = std::bit_cast<std::uint64_t>(x);
    const auto e = static_cast<int>((bits >> 52) & 0x7ff);
    if (e == 0x7ff) return add_non_finite(bits);
    std::uint64_t m = bits & ((std::uint64_t{1} << 52) - 1);
    if (e != 0) m |= std::uint64_t{1} << 52;  // the hidden bit of a normal number
    const int i = e != 0 ? e - 1 : 0;         // x = m 2^i in units of 2^-1074
    const int k = i / kBits, s = i % kBits;
    // m = lo + hi 2^32 (lo < 2^32, hi < 2^21), shifted by s < 32: lo 2^s
    // spans limbs k and k + 1, hi 2^s limbs k + 1 and k + 2.
    const std::uint64_t lo = (m & kMask) << s, hi = (m >> kBits) << s;
    const auto l0 = static_cast<std::int64_t>(lo & kMask);
    const auto l1 = static_cast<std::int64_t>((lo >> kBits) + (hi & kMask));
    const auto l2 = static_cast<std::int64_t>(hi >> kBits);
    if (bits >> 63) {
      limb_[k] -= l0; limb_[k + 1] -= l1; limb_[k + 2] -= l2;
    } else {
      limb_[k] += l0; limb_[k + 1] += l1; limb_[k + 2] += l2;
    }
    if (++pending_ >= kMaxPending) normalise();
  }
  ExactSum& operator+=(double x) { add(x); return *this; }

  // This and `other`: the sum of both sets of terms.
  void add(const ExactSum& other);
  ExactSum& operator+=(const ExactSum& other) { add(other); return *this; }

  // The exact sum rounded to the nearest double (ties to even).
  double value() const;

  // The normalised limbs and the counters (kWords int64s): the sum as data.
  // Equal for equal sums. Adding the words of up to 2^30 accumulators as
  // integers, element by element, gives the words of their sum (from_limbs).
  std::span<const std::int64_t> limbs() {
    normalise();
    return limb_;
  }
  // The accumulator whose words are `words` (kWords of them: limbs() of
  // one accumulator, or their element-wise sum over up to 2^30 of them).
  static ExactSum from_limbs(std::span<const std::int64_t> words);

  // The same sum (the same terms up to order and exact cancellation).
  friend bool operator==(const ExactSum& a, const ExactSum& b);

private:
  static constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;
  // Each add puts below 2^33 into a limb; 2^28 of them stay below 2^61,
  // leaving room for a merge with another accumulator (add(ExactSum)).
  static constexpr std::int64_t kMaxPending = std::int64_t{1} << 28;

  void add_non_finite(std::uint64_t bits);
  // Carries up: every limb but the top one into [0, 2^32), S unchanged.
  void normalise();

  std::array<std::int64_t, kWords> limb_{};
  // Adds since the limbs were last normalised: every limb is below (pending_ + 1) 2^33 in size.
  std::int64_t pending_ = 0;
};

}  // namespace floesim
