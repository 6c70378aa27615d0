// SPDX-License-Identifier: MIT
#include <assimp/DefaultIOStream.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/commonMetaData.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <bspc/import.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/Importer.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "import_obj.h"

namespace bspc {

namespace {

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return out;
}

// Rotates the source's up axis onto +Y (a proper rotation, so winding and
// handedness are kept) and scales to metres.
Eigen::Matrix4d sourceToLevel(const ImportSettings& settings) {
  Eigen::Matrix3d rotation;
  switch (settings.up) {
    case UpAxis::Y: rotation.setIdentity(); break;
    case UpAxis::Z: rotation << 1, 0, 0, 0, 0, 1, 0, -1, 0; break;  // (x, y, z) -> (x, z, -y)
    case UpAxis::X: rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1; break;  // (x, y, z) -> (-y, x, z)
  }
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = settings.scale * rotation;
  return m;
}

// Whether assimp read `scene` with its Collada importer (which converts the
// file's declared up axis to Y itself).
bool readAsCollada(const aiScene& scene) {
  aiString format;
  return scene.mMetaData && scene.mMetaData->Get(AI_METADATA_SOURCE_FORMAT, format) &&
         std::string_view(format.C_Str()).find("Collada") != std::string_view::npos;
}

// Appends every mesh of the scene's node tree, each vertex moved by its
// node's whole transform (`root` first). The tree is walked with a stack of
// our own, depth first in the order recursion would take, so a chain of
// nodes thousands deep cannot overflow bspc's stack. A transform that
// mirrors (negative determinant, as an FBX negative scale makes) turns a
// triangle inside out: it is written with two corners swapped, so it faces
// the way its mirrored surface does.
// The surface name of a mesh's material: its name, or kDefaultSurface for a
// mesh without one (assimp's own default material, an unnamed one).
std::string surfaceName(const aiScene& scene, const aiMesh& mesh) {
  if (mesh.mMaterialIndex >= scene.mNumMaterials || !scene.mMaterials[mesh.mMaterialIndex])
    return kDefaultSurface;
  aiString name;
  if (scene.mMaterials[mesh.mMaterialIndex]->Get(AI_MATKEY_NAME, name) != AI_SUCCESS)
    return kDefaultSurface;
  const std::string text(name.C_Str(), name.length);
  return text.empty() || text == AI_DEFAULT_MATERIAL_NAME ? kDefaultSurface : text;
}

// A source vertex where `transform` puts it in the level.
Eigen::Vector3d placed(const Eigen::Matrix4d& transform, float x, float y, float z) {
  const Eigen::Vector4d q = transform * Eigen::Vector4d(x, y, z, 1.0);
  return q.head<3>();
}

void appendScene(const aiScene& scene, const Eigen::Matrix4d& root, Mesh& out) {
  std::map<std::string, std::uint32_t> surfaceIds;  // name -> index in out.surfaces
  std::vector<std::pair<const aiNode*, Eigen::Matrix4d>> pending{{scene.mRootNode, root}};
  while (!pending.empty()) {
    const auto [node, parent] = pending.back();
    pending.pop_back();
    const Eigen::Matrix4d transform = parent * toEigen(node->mTransformation);
    const bool mirrors = transform.topLeftCorner<3, 3>().determinant() < 0;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh& mesh = *scene.mMeshes[node->mMeshes[i]];
      if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
      const auto base = static_cast<std::uint32_t>(out.vertices.size());
      const auto [named, added] = surfaceIds.try_emplace(
          surfaceName(scene, mesh), static_cast<std::uint32_t>(out.surfaces.size()));
      if (added) out.surfaces.push_back(named->first);
      const std::uint32_t surface = named->second;
      for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
        const aiVector3D& p = mesh.mVertices[v];
        out.vertices.push_back(placed(transform, p.x, p.y, p.z));
      }
      for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices != 3) continue;
        const std::uint32_t second = face.mIndices[mirrors ? 2 : 1];
        const std::uint32_t third = face.mIndices[mirrors ? 1 : 2];
        out.triangles.push_back({base + face.mIndices[0], base + second, base + third});
        out.triangleSurfaces.push_back(surface);
      }
    }
    for (unsigned c = node->mNumChildren; c-- > 0;)
      pending.emplace_back(node->mChildren[c], transform);
  }
}

// assimp's file access, except that it opens only regular files for reading,
// and checks the type on the open descriptor (opened non-blocking), so no
// FIFO or device swapped in after a check can block it.
class RegularFilesOnly : public Assimp::DefaultIOSystem {
 public:
  // assimp's own opens the file to see whether it exists.
  bool Exists(const char* file) const override {
    struct stat info {};
    return ::stat(file, &info) == 0;
  }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (std::string_view(mode).find_first_of("wa+") != std::string_view::npos)
      return Assimp::DefaultIOSystem::Open(file, mode);
    const int fd = ::open(file, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return nullptr;
    struct stat info {};
    if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode) ||
        ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK) != 0) {
      ::close(fd);
      return nullptr;
    }
    FILE* stream = ::fdopen(fd, "rb");
    if (!stream) {
      ::close(fd);
      return nullptr;
    }
    return new Stream(stream, file);
  }

 private:
  struct Stream : Assimp::DefaultIOStream {
    Stream(FILE* file, const std::string& name) : Assimp::DefaultIOStream(file, name) {}
  };
};

// The up axis a Collada file declares in its <asset> (<up_axis>X_UP</up_axis>,
// say), or Y when it declares none or an unknown one. The asset element
// comes first in the file: the first 64 kB are read (opened as assimp's
// reads are: a regular file only, never waited on).
UpAxis colladaDeclaredUp(const std::filesystem::path& path) {
  RegularFilesOnly files;
  const std::unique_ptr<Assimp::IOStream> in(files.Open(path.c_str(), "rb"));
  if (!in) return UpAxis::Y;
  std::string head(64 * 1024, '\0');
  head.resize(in->Read(head.data(), 1, head.size()));
  const std::size_t open = head.find("<up_axis>");
  if (open == std::string::npos) return UpAxis::Y;
  const std::size_t from = open + 9, close = head.find("</up_axis>", from);
  if (close == std::string::npos) return UpAxis::Y;
  std::string value;
  for (const char c : head.substr(from, close - from))
    if (c != ' ' && c != '\t' && c != '\n' && c != '\r') value += c;
  if (value == "X_UP") return UpAxis::X;
  if (value == "Z_UP") return UpAxis::Z;
  return UpAxis::Y;
}

}  // namespace

std::optional<Mesh> importPlainObj(const std::filesystem::path& path,
                                   const ImportSettings& settings) {
  const std::optional<std::vector<std::array<float, 3>>> corners = readPlainObjCorners(path);
  if (!corners) return std::nullopt;
  // As appendScene converts assimp's scene of it: one mesh under the root
  // node, each corner its own vertex, no node transform of its own.
  const Eigen::Matrix4d transform = sourceToLevel(settings);
  const bool mirrors = transform.topLeftCorner<3, 3>().determinant() < 0;
  Mesh mesh;
  mesh.vertices.reserve(corners->size());
  for (const auto& [x, y, z] : *corners) mesh.vertices.push_back(placed(transform, x, y, z));
  const auto triangles = static_cast<std::uint32_t>(corners->size() / 3);
  mesh.triangles.reserve(triangles);
  for (std::uint32_t t = 0; t < triangles; ++t)
    mesh.triangles.push_back({3 * t, 3 * t + (mirrors ? 2 : 1), 3 * t + (mirrors ? 1 : 2)});
  mesh.surfaces = {kDefaultSurface};
  mesh.triangleSurfaces.assign(triangles, 0);
  return mesh;
}

Mesh importMesh(const std::filesystem::path& path, const ImportSettings& settings) {
  {
    // assimp's own message for a missing file is vague; say why plainly.
    // The type first: opening a FIFO to read would wait for a writer.
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0)
      throw CompileError(std::string("cannot open: ") + std::strerror(errno));
    if (S_ISDIR(info.st_mode)) throw CompileError("is a directory, not a mesh");
    if (!S_ISREG(info.st_mode))
      throw CompileError("is not a regular file (a FIFO, device or socket), not a mesh");
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw CompileError(std::string("cannot open: ") + std::strerror(errno));
  }
  if (settings.readPlainObj)
    if (std::optional<Mesh> mesh = importPlainObj(path, settings)) return std::move(*mesh);
  Assimp::Importer importer;
  // Files the scene names (an OBJ's material library, say) are opened the
  // same way: a FIFO among them must not block the compile either.
  importer.SetIOHandler(new RegularFilesOnly);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_SortByPType |
                                           aiProcess_ValidateDataStructure);
  if (!scene || !scene->mRootNode) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown format or unreadable file";
    throw CompileError("cannot import: " + why);
  }
  Mesh mesh;
  ImportSettings applied = settings;
  if (settings.up != UpAxis::Y && readAsCollada(*scene)) {
    const UpAxis declared = colladaDeclaredUp(path);
    if (declared != UpAxis::Y) {
      // assimp already turned this scene to Y up: --up again would turn it over.
      applied.up = UpAxis::Y;
      mesh.warnings.push_back(std::string("the Collada file declares ") + toString(declared) +
                              " up, which the importer already turned to Y up: --up " +
                              toString(settings.up) + " not applied");
    }
  }
  appendScene(*scene, sourceToLevel(applied), mesh);
  if (mesh.triangles.empty()) throw CompileError("the scene holds no triangles");
  return mesh;
}

}  // namespace bspc
