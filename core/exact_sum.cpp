#include "core/exact_sum.hpp"

#include <algorithm>
#include <limits>

namespace floesim {

void ExactSum::add_non_finite(std::uint64_t bits) {
  // Exponent field all ones: a NaN when the fraction is not 0, else +-inf.
  const bool nan = (bits & ((std::uint64_t{1} << 52) - 1)) != 0;
  ++limb_[kLimbs + (nan ? 2 : (bits >> 63 ? 1 : 0))];
}

void ExactSum::normalise() {
  // S = sum_k limb[k] 2^(32 k) is unchanged when 2^32 c leaves limb k and c
  // joins limb k + 1; c = floor(limb[k] / 2^32) (an arithmetic shift) leaves
  // limb k in [0, 2^32). The top limb keeps the sign and what is above.
  for (int k = 0; k + 1 < kLimbs; ++k) {
    const std::int64_t carry = limb_[k] >> kBits;
    limb_[k] &= static_cast<std::int64_t>(kMask);
    limb_[k + 1] += carry;
  }
  pending_ = 0;
}

void ExactSum::add(const ExactSum& other) {
  // Limb by limb. Each operand's limbs are below (pending + 1) 2^33 in size
  // with pending < 2^28, so their sums stay below 2^63.
  for (int w = 0; w < kWords; ++w) limb_[w] += other.limb_[w];
  pending_ += other.pending_ + 1;
  if (pending_ >= kMaxPending) normalise();
}

ExactSum ExactSum::from_limbs(std::span<const std::int64_t> words) {
  ExactSum s;
  std::copy_n(words.begin(), std::min<std::size_t>(words.size(), kWords), s.limb_.begin());
  s.normalise();  // each limb of a sum of 2^30 normalised ones is below 2^62: the carries fit
  return s;
}

bool operator==(const ExactSum& a, const ExactSum& b) {
  ExactSum x = a, y = b;
  x.normalise();
  y.normalise();
  return x.limb_ == y.limb_;
}

double ExactSum::value() const {
  const std::int64_t positive_inf = limb_[kLimbs], negative_inf = limb_[kLimbs + 1], nan = limb_[kLimbs + 2];
  if (nan > 0 || (positive_inf > 0 && negative_inf > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (positive_inf > 0) return std::numeric_limits<double>::infinity();
  if (negative_inf > 0) return -std::numeric_limits<double>::infinity();

  ExactSum a = *this;
  a.normalise();
  // |S| and its sign: after normalisation S < 0 exactly when the top limb is.
  const bool negative = a.limb_[kLimbs - 1] < 0;
  if (negative) {
    for (int k = 0; k < kLimbs; ++k) a.limb_[k] = -a.limb_[k];
    a.normalise();
  }
  const double sign = negative ? -1.0 : 1.0;
  // The top limb starts at bit 2112, beyond the largest finite double's 2097.
  if (a.limb_[kLimbs - 1] != 0) return sign * std::numeric_limits<double>::infinity();
  int k = kLimbs - 2;
  while (k >= 0 && a.limb_[k] == 0) --k;
  if (k < 0) return 0.0;  // an exact zero is +0, as x + (-x) is in IEEE arithmetic
  // T: the place of |S|'s leading bit, in units of 2^-1074.
  const int top = kBits * k + 63 - std::countl_zero(static_cast<std::uint64_t>(a.limb_[k]));
  auto bit = [&](int j) { return (static_cast<std::uint64_t>(a.limb_[j / kBits]) >> (j % kBits)) & 1u; };
  std::uint64_t m = 0;  // the leading 53 bits (all of |S| when it has no more)
  for (int j = top; j >= std::max(top - 52, 0); --j) m = (m << 1) | bit(j);
  if (top <= 52) {
    // |S| < 2^53 units: exact, and its bits are the double's (a subnormal's
    // fraction is |S|; at T = 52 the hidden bit lands on exponent field 1).
    return sign * std::bit_cast<double>(m);
  }
  // |S| = (m + f) 2^r with f in [0, 1): round m to nearest, ties to even.
  // The round bit is bit r - 1, the sticky bits those below it.
  int r = top - 52;
  const int round_at = r - 1;
  bool sticky = (static_cast<std::uint64_t>(a.limb_[round_at / kBits]) & ((std::uint64_t{1} << (round_at % kBits)) - 1)) != 0;
  for (int j = round_at / kBits - 1; j >= 0 && !sticky; --j) sticky = a.limb_[j] != 0;
  if (bit(round_at) && (sticky || (m & 1u))) {
    if (++m == std::uint64_t{1} << 53) {
      m >>= 1;
      ++r;
    }
  }
  // m 2^r units = m 2^(r - 1074): exponent field e = r + 1 (x = m 2^(e - 1075)).
  const auto e = static_cast<std::uint64_t>(r + 1);
  if (e >= 0x7ff) return sign * std::numeric_limits<double>::infinity();
  return sign * std::bit_cast<double>((e << 52) | (m & ((std::uint64_t{1} << 52) - 1)));
}

}  // namespace floesim
