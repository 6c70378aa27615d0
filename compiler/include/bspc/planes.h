// SPDX-License-Identifier: MIT
// bspc/planes.h: stage 4, per-triangle collision planes.
#pragma once

#include <bspc/mesh.h>
#include <bspf/bspf_generated.h>
#include <bspf/thread_pool.h>

#include <cstdint>
#include <span>
#include <vector>

namespace bspc {

/// For each triangle: its face plane; three edge planes, each containing an
/// edge and the face normal, facing into the triangle; three vertex caps, each
/// through a corner, parallel to the opposite edge, facing into the triangle
/// (the article's figures 9 to 11). Computed in double, stored as float.
/// `meetable`: each triangle's meetable-plane bits (meetablePlanes,
/// bspc/edges.h), or empty for every plane meetable. With a pool, the
/// triangles are shared between its threads; the result is the same to the
/// bit on any number of threads (null: this thread only). Precondition: a
/// cleaned mesh (no zero-area triangles); `meetable` empty or parallel to
/// its triangles.
std::vector<bspf::schema::TrianglePlanes> computeTrianglePlanes(
    const Mesh& mesh, std::span<const std::uint8_t> meetable = {},
    bspf::ThreadPool* pool = nullptr);

/// The meetable bits of a triangle whose planes are all met.
inline constexpr std::uint8_t kAllPlanesMeetable = 0b111111;

}  // namespace bspc
