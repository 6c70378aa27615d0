// SPDX-License-Identifier: MIT
// The median the benchmark programs quote.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace bspf::bench {

/// The median of `values`: the middle one, or the mean of the middle two for
/// an even count; 0 for none.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const std::size_t mid = values.size() / 2;
  return values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

}  // namespace bspf::bench
