// SPDX-License-Identifier: MIT
// The sorted sweep's pair scan (BodyGrid::sweepPairsBySorting): boxes
// sorted by their low x, each tested against those after it that start
// before it ends along x. Private to the runtime.
#pragma once

#include <cstdint>
#include <vector>

namespace bspf::detail {

/// Boxes after the last one in SortedBoxes's arrays: they start at x
/// +infinity and meet nothing, so the scan reads whole runs of this many.
inline constexpr std::uint32_t kBoxRun = 4;

/// Boxes sorted by low x, as arrays of `count + kBoxRun` entries: the last
/// kBoxRun low bounds +infinity, high bounds -infinity, not fast.
struct SortedBoxes {
  const float *lowX, *highX, *lowY, *highY, *lowZ, *highZ;
  const std::uint32_t* body;  ///< the box's body index
  const std::uint32_t* fast;  ///< all ones for a fast body's box, else 0
  std::uint32_t count;
};

/// Appends `a << 32 | b` (a < b, body indices) to `pairs` for each pair of
/// the boxes that meet (closed intervals along each axis) and hold a fast
/// body, in the order of their first box, then their second. With SSE2,
/// four boxes at a time (one branch each, where one per box mispredicted at
/// the end of most runs: 6% of a 40 m/s walker step's cycles on oa_dm5);
/// the same pairs as appendMeetingPairsOneByOne.
void appendMeetingPairs(const SortedBoxes& boxes, std::vector<std::uint64_t>& pairs);

/// The reference: the same scan one box at a time.
void appendMeetingPairsOneByOne(const SortedBoxes& boxes, std::vector<std::uint64_t>& pairs);

}  // namespace bspf::detail
