#pragma once
// Random doubles for the file formats' round trips: every bit of the mantissa drawn, so that a
// writer that loses one shows.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>

namespace pcr::testing {

/// A random finite double spread over many magnitudes (random mantissa bits): about 10^e for e
/// uniform in [lo_exp, hi_exp], of either sign unless `positive`.
inline double random_double(std::mt19937_64& rng, double lo_exp, double hi_exp, bool positive) {
  std::uniform_real_distribution<double> e(lo_exp, hi_exp);
  std::uniform_int_distribution<std::uint64_t> mantissa(0, (std::uint64_t(1) << 52) - 1);
  double x = std::pow(10.0, e(rng));
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof x);
  bits = (bits & ~((std::uint64_t(1) << 52) - 1)) | mantissa(rng);
  std::memcpy(&x, &bits, sizeof x);
  if (!positive && (rng() & 1)) x = -x;
  return x;
}

}  // namespace pcr::testing
