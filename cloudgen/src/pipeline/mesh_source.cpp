// A mesh file to a checked TriangleMesh through Assimp (mesh_source.h). Every file Assimp opens
// (the mesh, and the buffers or materials it names) goes through the one input layer: protected as
// an input, no pipes or devices, at most kMeshFileCap bytes.
#include <sys/stat.h>

#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

#include "cloudgen/errors.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/printable.h"
#include "cloudgen/schema.h"

namespace cloudgen {
namespace {

/// One file's bytes, read whole by the input layer.
class BytesStream : public Assimp::IOStream {
 public:
  explicit BytesStream(std::vector<uint8_t> b) : b_(std::move(b)) {}
  size_t Read(void* dst, size_t size, size_t count) override {
    if (size == 0 || count == 0) return 0;
    const size_t n = std::min(count, (b_.size() - pos_) / size);
    if (n) std::memcpy(dst, b_.data() + pos_, n * size);
    pos_ += n * size;
    return n;
  }
  size_t Write(const void*, size_t, size_t) override { return 0; }
  aiReturn Seek(size_t off, aiOrigin origin) override {
    size_t to;
    if (origin == aiOrigin_SET) to = off;
    else if (origin == aiOrigin_CUR) to = pos_ + off;
    else to = b_.size() - std::min(off, b_.size());  // aiOrigin_END: off counts back from the end
    if (origin == aiOrigin_END ? off > b_.size() : to > b_.size()) return aiReturn_FAILURE;
    pos_ = to;
    return aiReturn_SUCCESS;
  }
  size_t Tell() const override { return pos_; }
  size_t FileSize() const override { return b_.size(); }
  void Flush() override {}

 private:
  std::vector<uint8_t> b_;
  size_t pos_ = 0;
};

/// Assimp's file system: regular files through read_input_bytes, nothing written; with `none`, no
/// file at all (bytes from memory: a fuzzed OBJ naming /etc/passwd as its material reads nothing).
class InputLayerIO : public Assimp::IOSystem {
 public:
  InputLayerIO(std::string what, bool none) : what_(std::move(what)), none_(none) {}
  bool Exists(const char* f) const override {
    struct stat st;
    return !none_ && f && ::stat(f, &st) == 0 && S_ISREG(st.st_mode);
  }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* f, const char* mode) override {
    if (none_ || !f || !mode || std::strchr(mode, 'w') || std::strchr(mode, 'a') || !Exists(f)) return nullptr;
    // An InputError here (a pipe, a file over the cap) must reach the user, not be turned by Assimp
    // into "file not found": kept, and thrown again after the import returns.
    try {
      return new BytesStream(read_input_bytes(f, "the mesh " + printable(f), what_ + " " + printable(f), kMeshFileCap));
    } catch (...) {
      if (!error_) error_ = std::current_exception();
      return nullptr;
    }
  }
  void Close(Assimp::IOStream* s) override { delete s; }
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::string what_;
  bool none_;
  std::exception_ptr error_;
};

constexpr unsigned kSteps = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                            aiProcess_SortByPType | aiProcess_ValidateDataStructure;

void configure(Assimp::Importer& im) {
  // Points and lines bound no volume: dropped by SortByPType.
  im.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
}

std::string fmt(double v) { return shortest_text(v); }
/// A float read from the file, as %g writes it (1e+30, not the double nearest the float).
std::string fmt_float(float v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", double(v));
  return b;
}

/// Assimp's reason, or ours where Assimp's says less ("Mesh contains no faces": no triangles).
std::string import_error(const std::string& what, const std::string& reason) {
  if (reason.find("no faces") != std::string::npos || reason.find("No meshes") != std::string::npos)
    return what + ": the file has no triangles (a mesh source needs a surface)";
  return what + ": not a mesh Assimp can read (" + printable(reason) + ")";
}

/// The scene's triangles as one checked mesh.
TriangleMesh collect(const aiScene* sc, const std::string& what) {
  TriangleMesh m;
  size_t tris = 0;
  for (unsigned i = 0; i < sc->mNumMeshes; ++i)
    if (sc->mMeshes[i]) tris += sc->mMeshes[i]->mNumFaces;
  if (tris > kMaxMeshTriangles)
    throw InputError(what + ": " + std::to_string(tris) + " triangles; a mesh source may have at most " +
                     std::to_string(kMaxMeshTriangles) + " (decimate it first)");
  m.triangles.reserve(tris);
  for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
    const aiMesh* a = sc->mMeshes[i];
    if (!a || !(a->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const size_t base = m.points.size();
    for (unsigned v = 0; v < a->mNumVertices; ++v) {
      const aiVector3D& q = a->mVertices[v];
      for (float c : {q.x, q.y, q.z})
        if (!std::isfinite(c) || std::abs(c) > kMaxMeshCoordinate)
          throw InputError(what + ": vertex " + std::to_string(base + v) + " has the coordinate " + fmt_float(c) +
                           "; allowed: finite, within +-" + fmt(kMaxMeshCoordinate));
      m.points.push_back({q.x, q.y, q.z});
    }
    for (unsigned f = 0; f < a->mNumFaces; ++f) {
      const aiFace& face = a->mFaces[f];
      if (face.mNumIndices != 3) continue;
      std::array<uint32_t, 3> t;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= a->mNumVertices)
          throw InputError(what + ": a triangle names vertex " + std::to_string(face.mIndices[k]) + " of " +
                           std::to_string(a->mNumVertices));
        t[k] = uint32_t(base + face.mIndices[k]);
      }
      m.triangles.push_back(t);
    }
  }
  if (m.triangles.empty()) throw InputError(what + ": the file has no triangles (a mesh source needs a surface)");
  m.lo = {1e300, 1e300, 1e300}, m.hi = {-1e300, -1e300, -1e300};
  // Equal points joined by position (JoinIdenticalVertices keeps points that differ in normals or
  // texture coordinates apart), so an edge shared by two faces is seen as shared. Sorting, not
  // maps: a mesh may have millions of points.
  std::vector<uint32_t> order(m.points.size()), canon(m.points.size());
  for (size_t v = 0; v < order.size(); ++v) order[v] = uint32_t(v);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return m.points[a] < m.points[b]; });
  for (size_t k = 0; k < order.size(); ++k)
    canon[order[k]] = k > 0 && m.points[order[k]] == m.points[order[k - 1]] ? canon[order[k - 1]] : order[k];
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(3 * m.triangles.size());
  for (const auto& t : m.triangles) {
    std::array<double, 3> p[3];
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        p[k][a] = m.points[t[k]][a];
        m.lo[a] = std::min(m.lo[a], p[k][a]), m.hi[a] = std::max(m.hi[a], p[k][a]);
      }
      const uint32_t u = canon[t[k]], w = canon[t[(k + 1) % 3]];
      if (u != w) edges.push_back({std::min(u, w), std::max(u, w)});
    }
    const std::array<double, 3> e1{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]},
        e2{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    m.area += 0.5 * std::sqrt(std::pow(e1[1] * e2[2] - e1[2] * e2[1], 2) + std::pow(e1[2] * e2[0] - e1[0] * e2[2], 2) +
                              std::pow(e1[0] * e2[1] - e1[1] * e2[0], 2));
  }
  std::sort(edges.begin(), edges.end());
  for (size_t k = 0; k < edges.size();) {  // runs of one edge: a run of length 1 is a border
    size_t e = k;
    while (e < edges.size() && edges[e] == edges[k]) ++e;
    m.open_edges += e - k == 1;
    k = e;
  }
  uint64_t h = 0xcbf29ce484222325ull;
  auto mix = [&](const void* data, size_t n) {
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(data)[i]) * 0x100000001b3ull;
  };
  mix(m.points.data(), m.points.size() * sizeof(m.points[0]));
  mix(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
  m.fnv1a = h;
  if (!(m.area > 0)) throw InputError(what + ": every triangle has zero area (a mesh source needs a surface)");
  return m;
}

}  // namespace

TriangleMesh read_mesh(const std::string& path, const std::string& what) {
  protect_input(path, "the mesh " + printable(path));  // a pipe or device: refused here
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw InputError(what + ": no such file");
  if (!S_ISREG(st.st_mode)) throw InputError(what + ": not a regular file");
  Assimp::Importer im;
  configure(im);
  auto* io = new InputLayerIO(what, false);
  im.SetIOHandler(io);  // the importer owns it
  const aiScene* sc = im.ReadFile(path, kSteps);
  io->rethrow();
  if (!sc) throw InputError(import_error(what, im.GetErrorString()));
  TriangleMesh m = collect(sc, what);
  m.file = path;
  return m;
}

TriangleMesh read_mesh_bytes(const std::vector<uint8_t>& bytes, const std::string& extension, const std::string& what) {
  Assimp::Importer im;
  configure(im);
  im.SetIOHandler(new InputLayerIO(what, true));
  const aiScene* sc = im.ReadFileFromMemory(bytes.data(), bytes.size(), kSteps, extension.c_str());
  if (!sc) throw InputError(import_error(what, im.GetErrorString()));
  return collect(sc, what);
}

}  // namespace cloudgen
