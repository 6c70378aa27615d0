// SPDX-License-Identifier: MIT
#include <bspc/mesh.h>
#include <bspc/settings.h>
#include <bspf/world.h>

#include <cmath>
#include <sstream>

namespace bspc {

const char* toString(UpAxis axis) {
  switch (axis) {
    case UpAxis::X: return "x";
    case UpAxis::Y: return "y";
    case UpAxis::Z: return "z";
  }
  return "?";
}

const char* toString(SplitCandidates candidates) {
  switch (candidates) {
    case SplitCandidates::Axis: return "axis";
    case SplitCandidates::Triangle: return "triangle";
    case SplitCandidates::Both: return "both";
  }
  return "?";
}

namespace {
void require(bool ok, const char* what) {
  if (!ok) throw CompileError(std::string("invalid setting: ") + what);
}
}  // namespace

void validate(const CompileSettings& s) {
  require(std::isfinite(s.import.scale) && s.import.scale > 0, "scale must be finite and > 0");
  require(std::isfinite(s.import.timeoutSeconds) && s.import.timeoutSeconds > 0 &&
              s.import.timeoutSeconds <= 86400,
          "import timeout must be > 0 and at most 86400 s");
  require(std::isfinite(s.clean.weldTolerance) && s.clean.weldTolerance >= 0 &&
              s.clean.weldTolerance < 1,
          "weld tolerance must be >= 0 and < 1 m");
  require(std::isfinite(s.clean.minTriangleArea) && s.clean.minTriangleArea >= 0,
          "minimum triangle area must be >= 0");
  require(s.clean.dropSurfaces.empty() || s.clean.onlySurfaces.empty(),
          "surfaces to drop and surfaces to keep only cannot both be given");
  require(s.tree.maxLeafTriangles >= 1 && s.tree.maxLeafTriangles <= 4096,
          "max leaf triangles must be 1 to 4096");
  require(s.tree.maxDepth >= 1 && s.tree.maxDepth <= bspf::kMaxTreeDepth,
          "max depth must be 1 to 64");
  require(std::isfinite(s.tree.balanceWeight) && s.tree.balanceWeight >= 0,
          "balance weight must be >= 0");
  require(std::isfinite(s.tree.splitWeight) && s.tree.splitWeight >= 0,
          "split weight must be >= 0");
  require(std::isfinite(s.tree.queryReach) && s.tree.queryReach >= 0,
          "query reach must be finite and >= 0");
  require(s.tree.axisCandidatesPerAxis >= 1 && s.tree.axisCandidatesPerAxis <= 64,
          "axis candidates must be 1 to 64");
  require(s.limits.maxBlobBytes >= 1 && s.limits.maxBlobBytes <= kMaxBlobBytes,
          "max blob bytes must be 1 to 2^31 - 1");
  require(s.tree.triangleCandidates >= 1 && s.tree.triangleCandidates <= 256,
          "triangle candidates must be 1 to 256");
  const double rxz = s.reach.radiusXZ, ry = s.reach.radiusY;
  require(std::isfinite(rxz) && std::isfinite(ry) && rxz > 0.01 && ry > 0.01 && rxz <= 8 * ry &&
              ry <= 8 * rxz,
          "body radii must be finite, > 0.01 m, and within a factor 8 of each other");
  require(s.reach.maxCells >= 1 && s.reach.maxCells <= (std::uint64_t(1) << 32),
          "reach grid cells must be 1 to 2^32");
  require(s.reach.cellOfRadius >= 0.05 && s.reach.cellOfRadius <= 0.4,
          "reach cell must be 0.05 to 0.4 of the smaller radius");
  for (const Eigen::Vector3d& p : s.reach.from)
    require(p.allFinite(), "reach points must be finite");
  require(s.threads <= 1024, "threads must be 0 (every core) to 1024");
}

std::string describeOptions(const CompileSettings& s) {
  std::ostringstream out;
  out.precision(9);
  out << "up=" << toString(s.import.up) << " scale=" << s.import.scale
      << " weld=" << s.clean.weldTolerance << " min-area=" << s.clean.minTriangleArea
      << " max-leaf-triangles=" << s.tree.maxLeafTriangles << " max-depth=" << s.tree.maxDepth
      << " balance-weight=" << s.tree.balanceWeight << " split-weight=" << s.tree.splitWeight
      << " query-reach=" << s.tree.queryReach << " candidates=" << toString(s.tree.candidates)
      << " axis-candidates=" << s.tree.axisCandidatesPerAxis
      << " triangle-candidates=" << s.tree.triangleCandidates
      << " drop-covered-faces=" << (s.dropCoveredFaces ? 1 : 0);
  // Only when off, so the line of a compile that keeps no buried face is
  // the one bspc wrote before the rule.
  if (!s.dropBuriedFaces) out << " drop-buried-faces=0";
  // Likewise only when on.
  if (s.tree.exhaustiveSplitSearch) out << " exhaustive-split-search=1";
  // The reach rule shapes the output too: how many points and which body.
  if (!s.reach.from.empty())
    out << " reach-points=" << s.reach.from.size() << " body-radii=" << s.reach.radiusXZ << ","
        << s.reach.radiusY;
  // Only when given, so the line of a compile without them is unchanged.
  for (const std::string& name : s.clean.dropSurfaces) out << " drop-surface=" << name;
  for (const std::string& name : s.clean.onlySurfaces) out << " only-surface=" << name;
  return out.str();
}

}  // namespace bspc
