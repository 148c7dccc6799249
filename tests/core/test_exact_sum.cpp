// ExactSum (core/exact_sum.hpp): the exact sum of doubles, correctly
// rounded, the same bits in any order and however the terms are split.
#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "core/exact_sum.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("core");

namespace {
// Doubles over the whole exponent range, subnormals included, either sign:
// a random fraction and a random exponent field in [0, 2046].
std::vector<double> wide_doubles(std::size_t n, std::uint64_t seed, int lowest_field = 0, int highest_field = 2046) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> field(lowest_field, highest_field);
  std::vector<double> x(n);
  for (double& v : x) {
    const std::uint64_t bits = (rng() & ((std::uint64_t{1} << 52) - 1)) |
                               (static_cast<std::uint64_t>(field(rng)) << 52) | (rng() & (std::uint64_t{1} << 63));
    v = std::bit_cast<double>(bits);
  }
  return x;
}

double exact(const std::vector<double>& x) {
  ExactSum s;
  for (double v : x) s.add(v);
  return s.value();
}

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }
}  // namespace

TEST_CASE("exact sum: a sum of two doubles is IEEE's correctly rounded a + b, subnormals and ties included") {
  // IEEE addition of two doubles is the exact sum rounded to nearest, ties
  // to even: the reference for every exponent gap, overflow excepted.
  std::vector<double> a = wide_doubles(20000, 1, 0, 2000), b = wide_doubles(20000, 2, 0, 2000);
  // Close exponents too, where cancellation and ties are common.
  const std::vector<double> c = wide_doubles(20000, 3, 1000, 1060), d = wide_doubles(20000, 4, 1000, 1060);
  a.insert(a.end(), c.begin(), c.end());
  b.insert(b.end(), d.begin(), d.end());
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ExactSum s(a[i]);
    s.add(b[i]);
    if (!same_bits(s.value(), a[i] + b[i]) && !(a[i] + b[i] == 0.0 && s.value() == 0.0)) ++differ;
  }
  CHECK(differ == 0);
}

TEST_CASE("exact sum: ties round to even, and a bit below the tie decides") {
  const double ulp_half = std::ldexp(1.0, -53);  // half an ulp of 1
  CHECK(same_bits(exact({1.0, ulp_half}), 1.0));                              // tie, 1 is even
  CHECK(same_bits(exact({1.0, ulp_half, std::ldexp(1.0, -1074)}), std::nextafter(1.0, 2.0)));  // just above the tie
  CHECK(same_bits(exact({1.0, ulp_half, -std::ldexp(1.0, -1074)}), 1.0));    // just below
  const double odd = std::nextafter(1.0, 2.0);                                 // 1 + 2^-52: odd
  CHECK(same_bits(exact({odd, ulp_half}), std::nextafter(odd, 2.0)));          // tie, up to even
  CHECK(same_bits(exact({-odd, -ulp_half}), -std::nextafter(odd, 2.0)));
  CHECK(same_bits(exact({9007199254740992.0, 1.0}), 9007199254740992.0));      // 2^53 + 1: tie, down
  CHECK(same_bits(exact({9007199254740992.0, 3.0}), 9007199254740996.0));      // 2^53 + 3: tie, up
  // A tie decided by terms far apart: 2^100 + 2^47 (half an ulp of 2^100) + 2^-1000.
  CHECK(same_bits(exact({std::ldexp(1.0, 100), std::ldexp(1.0, 47), std::ldexp(1.0, -1000)}),
                  std::nextafter(std::ldexp(1.0, 100), INFINITY)));
  // Rounding up that carries into the exponent: (2 - 2^-52) + 2^-53 -> 2.
  CHECK(same_bits(exact({std::nextafter(2.0, 0.0), ulp_half}), 2.0));
}

TEST_CASE("exact sum: a known exact sum among huge terms that cancel, in any order") {
  // Terms n_j 2^-30 with |n_j| < 2^20: their exact sum is an integer times
  // 2^-30 computed in int64, a double. Among them pairs +X, -X from the whole
  // range (1e300 and subnormals alike): a plain sum loses the small terms.
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::int64_t> n(-(1 << 20), 1 << 20);
  std::vector<double> x;
  std::int64_t total = 0;
  for (int j = 0; j < 3000; ++j) {
    const std::int64_t v = n(rng);
    total += v;
    x.push_back(std::ldexp(static_cast<double>(v), -30));
  }
  for (double big : wide_doubles(3000, 8)) {
    x.push_back(big);
    x.push_back(-big);
  }
  const double expected = std::ldexp(static_cast<double>(total), -30);
  for (int round = 0; round < 5; ++round) {
    std::shuffle(x.begin(), x.end(), rng);
    CHECK(same_bits(exact(x), expected));
  }
  double plain = 0.0;
  for (double v : x) plain += v;
  CHECK(plain != expected);  // the test is one a plain sum fails
}

TEST_CASE("exact sum: any order, any split, merged or summed as limbs, gives the same bits") {
  std::vector<double> x = wide_doubles(50000, 11, 900, 1150);  // |x| from 2^-123 to 2^127
  const std::vector<double> wide = wide_doubles(5000, 12);
  x.insert(x.end(), wide.begin(), wide.end());
  ExactSum whole;
  for (double v : x) whole.add(v);
  const double reference = whole.value();
  std::mt19937_64 rng(13);
  for (int round = 0; round < 4; ++round) {
    std::shuffle(x.begin(), x.end(), rng);
    CHECK(same_bits(exact(x), reference));
    // Split into parts (as ranks own floes), each summed alone, then merged
    // in reverse order, and as limbs summed element-wise (an MPI_SUM).
    const int parts = 2 + round;
    std::vector<ExactSum> part(static_cast<std::size_t>(parts));
    for (std::size_t i = 0; i < x.size(); ++i) part[rng() % part.size()].add(x[i]);
    ExactSum merged;
    for (auto p = part.rbegin(); p != part.rend(); ++p) merged += *p;
    CHECK(same_bits(merged.value(), reference));
    CHECK(merged == whole);
    std::vector<std::int64_t> words(ExactSum::kWords, 0);
    for (ExactSum& p : part) {
      const auto w = p.limbs();
      for (std::size_t k = 0; k < words.size(); ++k) words[k] += w[k];
    }
    const ExactSum from_words = ExactSum::from_limbs(words);
    CHECK(same_bits(from_words.value(), reference));
    ExactSum u = from_words, w = whole;
    const auto a = u.limbs(), b = w.limbs();
    CHECK(std::equal(a.begin(), a.end(), b.begin(), b.end()));
  }
}

TEST_CASE("exact sum: subnormals, zero, overflow and non-finite terms") {
  const double tiny = std::ldexp(1.0, -1074);
  CHECK(same_bits(exact(std::vector<double>(1000, tiny)), 1000 * tiny));
  CHECK(same_bits(exact({std::ldexp(1.0, -1022), -tiny}), std::nextafter(std::ldexp(1.0, -1022), 0.0)));
  CHECK(same_bits(exact({}), 0.0));
  CHECK(same_bits(exact({1.5, -1.5}), 0.0));
  CHECK(same_bits(exact({-tiny, -tiny}), -2 * tiny));
  const double big = std::numeric_limits<double>::max();
  CHECK(exact({big, big}) == INFINITY);
  CHECK(exact({-big, -big}) == -INFINITY);
  CHECK(same_bits(exact({big, big, -big}), big));  // no intermediate overflow
  CHECK(same_bits(exact({big, std::ldexp(1.0, 969)}), big));  // below the tie with 2^1024: stays
  CHECK(exact({big, std::ldexp(1.0, 970)}) == INFINITY);       // the tie rounds to (even) 2^1024: inf
  CHECK(exact({1.0, INFINITY, 2.0}) == INFINITY);
  CHECK(exact({-INFINITY, 1.0}) == -INFINITY);
  CHECK(std::isnan(exact({INFINITY, -INFINITY})));
  CHECK(std::isnan(exact({1.0, std::numeric_limits<double>::quiet_NaN()})));
  ExactSum a(INFINITY), b(-INFINITY);
  a += b;
  CHECK(std::isnan(a.value()));
}

TEST_SUITE_END();
