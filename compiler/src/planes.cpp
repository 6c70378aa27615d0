// SPDX-License-Identifier: MIT
#include <bspc/planes.h>

#include "parallel.h"

namespace bspc {

namespace {

bspf::schema::Plane toPlane(const Eigen::Vector3d& normal, const Eigen::Vector3d& through) {
  // Normalise the float-rounded normal so the stored plane is unit length in
  // float, then place it through the point.
  const Eigen::Vector3d n = normal.cast<float>().cast<double>().normalized();
  const Eigen::Vector3f nf = n.cast<float>();
  return bspf::schema::Plane(bspf::schema::Vec3(nf.x(), nf.y(), nf.z()),
                             static_cast<float>(nf.cast<double>().dot(through)));
}

bspf::schema::TrianglePlanes trianglePlanes(const Mesh& mesh, const std::array<std::uint32_t, 3>& t,
                                            std::uint8_t meetable) {
  const Eigen::Vector3d p[3] = {mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]};
  const Eigen::Vector3d face = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
  std::array<Eigen::Vector3d, 3> edgeNormal;
  std::array<bspf::schema::Plane, 3> edges, caps;
  for (int i = 0; i < 3; ++i) {
    // face x edge points into a counter-clockwise triangle.
    edgeNormal[i] = face.cross(p[(i + 1) % 3] - p[i]).normalized();
    edges[i] = toPlane(edgeNormal[i], p[i]);
  }
  for (int i = 0; i < 3; ++i) {
    // The edge opposite corner i runs from corner i+1 to corner i+2.
    caps[i] = toPlane(-edgeNormal[(i + 1) % 3], p[i]);
  }
  return bspf::schema::TrianglePlanes(toPlane(face, (p[0] + p[1] + p[2]) / 3.0),
                                      flatbuffers::span<const bspf::schema::Plane, 3>(edges),
                                      flatbuffers::span<const bspf::schema::Plane, 3>(caps),
                                      meetable);
}

}  // namespace

std::vector<bspf::schema::TrianglePlanes> computeTrianglePlanes(
    const Mesh& mesh, std::span<const std::uint8_t> meetable, bspf::ThreadPool* pool) {
  std::vector<bspf::schema::TrianglePlanes> out(mesh.triangles.size());
  const auto fill = [&](int, std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i)
      out[i] = trianglePlanes(mesh, mesh.triangles[i],
                              meetable.empty() ? kAllPlanesMeetable : meetable[i]);
  };
  // Each triangle's planes land in its own slot: the same bytes on any
  // number of threads. Chunks of 1,024 (about 0.2 ms each) share even a
  // small level's few thousand triangles between the threads.
  runParallel(pool, out.size(), 1024, fill);
  return out;
}

}  // namespace bspc
