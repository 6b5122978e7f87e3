#pragma once

// Summary statistics of a sample: the run times of `paper`, the RMSEs of `study`.

#include <algorithm>
#include <cmath>
#include <vector>

namespace mjukf::examples::detail {

/// The median (the mean of the two middle values for an even count); the sample must not be empty.
inline double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

inline double mean(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values) sum += v;
  return sum / double(values.size());
}

/// The sample standard deviation (n − 1 in the denominator); 0 for a single value.
inline double standardDeviation(const std::vector<double>& values) {
  if (values.size() < 2) return 0;
  const double m = mean(values);
  double squares = 0;
  for (double v : values) squares += (v - m) * (v - m);
  return std::sqrt(squares / double(values.size() - 1));
}

/// The q-quantile of the χ² distribution with k degrees of freedom by the Wilson–Hilferty cube-root
/// normal approximation, z the standard normal quantile of q (within 0.1 % for k ≥ 10, 2 % for k = 1).
inline double chiSquareQuantile(double k, double z) {
  const double c = 2.0 / (9.0 * k);
  const double root = 1.0 - c + z * std::sqrt(c);
  return k * root * root * root;
}

}  // namespace mjukf::examples::detail
