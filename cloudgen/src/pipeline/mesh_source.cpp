// A mesh file to a checked TriangleMesh through Assimp (mesh_source.h). Every file Assimp opens
// (the mesh, and the buffers or materials it names) goes through the one input layer: protected as
// an input, no pipes or devices, at most kMeshFileCap bytes.
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <functional>
#include <utility>

#include "cloudgen/errors.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/interrupt.h"
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

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CLOUD_MESH_SANITIZED 1  // ASan reserves terabytes of address space: no RLIMIT_AS
#endif
#endif
#ifndef CLOUD_MESH_SANITIZED
#define CLOUD_MESH_SANITIZED 0
#endif

constexpr unsigned kSteps = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                            aiProcess_SortByPType | aiProcess_ValidateDataStructure;

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

/// The scene's triangles as raw arrays (checked later by mesh_from_arrays, in the parent); returns
/// the scene's face count, and extracts nothing when it is over kMaxMeshTriangles (the parent
/// refuses the mesh by that count alone).
size_t extract(const aiScene* sc, std::vector<std::array<float, 3>>& points, std::vector<std::array<uint32_t, 3>>& tris) {
  size_t n = 0;
  for (unsigned i = 0; i < sc->mNumMeshes; ++i)
    if (sc->mMeshes[i]) n += sc->mMeshes[i]->mNumFaces;
  if (n > kMaxMeshTriangles) return n;
  for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
    const aiMesh* a = sc->mMeshes[i];
    if (!a || !(a->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const size_t base = points.size();
    for (unsigned v = 0; v < a->mNumVertices; ++v) points.push_back({a->mVertices[v].x, a->mVertices[v].y, a->mVertices[v].z});
    for (unsigned f = 0; f < a->mNumFaces; ++f) {
      const aiFace& face = a->mFaces[f];
      if (face.mNumIndices != 3) continue;
      std::array<uint32_t, 3> t;
      for (int k = 0; k < 3; ++k)  // an index past this mesh's points is sent as one past all of them
        t[k] = face.mIndices[k] < a->mNumVertices ? uint32_t(base + face.mIndices[k]) : uint32_t(0xffffffffu);
      tris.push_back(t);
    }
  }
  return tris.size();
}

// The child's answer on the pipe: a status byte, then for 0 (a scene) the counts (u64) and the
// arrays, for 1 (refused) the reason's length (u64) and text.
bool write_all(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w, n -= size_t(w);
  }
  return true;
}

/// Reads n bytes, or false at the end of the pipe or past `deadline` (then `late` is set).
bool read_all(int fd, void* data, size_t n, std::chrono::steady_clock::time_point deadline, bool& late) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      late = true;
      return false;
    }
    struct pollfd pf{fd, POLLIN, 0};
    const int ready = ::poll(&pf, 1, int(std::min<int64_t>(left.count(), 1000)));
    if (ready < 0 && errno == EINTR) {
      throw_if_interrupted();
      continue;
    }
    if (ready == 0) continue;
    const ssize_t r = ::read(fd, p, n);
    if (r < 0 && errno == EINTR) {
      throw_if_interrupted();
      continue;
    }
    if (r <= 0) return false;
    p += r, n -= size_t(r);
  }
  return true;
}

/// Runs `import` (Assimp, which can loop forever or crash on a damaged file: found by fuzz_mesh)
/// in a child process with a CPU-time limit and, outside the sanitizers, an address-space limit;
/// returns the checked mesh, or throws InputError naming the file and what happened.
TriangleMesh import_in_child(const std::string& what, size_t bytes,
                             const std::function<const aiScene*(Assimp::Importer&, InputLayerIO*&)>& import) {
  int fds[2];
  if (::pipe(fds) != 0) throw IoError(what + ": cannot start the mesh reader: " + std::strerror(errno));
  // CPU time: two seconds plus one per MiB (Assimp reads tens of MiB a second).
  const rlim_t cpu = rlim_t(2 + bytes / (1 << 20));
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]), ::close(fds[1]);
    throw IoError(what + ": cannot start the mesh reader: " + std::strerror(errno));
  }
  if (pid == 0) {  // the child: import, send, _exit (no atexit handlers, no flushing of the parent's streams)
    ::close(fds[0]);
    for (int sig : {SIGINT, SIGTERM, SIGALRM, SIGPIPE}) std::signal(sig, SIG_DFL);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // the parent gone (Ctrl-C), the reader goes too
    struct rlimit rl{cpu, cpu + 1};
    ::setrlimit(RLIMIT_CPU, &rl);
#if !CLOUD_MESH_SANITIZED
    struct rlimit as{rlim_t(8) << 30, rlim_t(8) << 30};  // 8 GiB: a damaged count cannot swap the machine
    ::setrlimit(RLIMIT_AS, &as);
#endif
    uint8_t status = 1;
    std::string reason;
    std::vector<std::array<float, 3>> points;
    std::vector<std::array<uint32_t, 3>> tris;
    size_t faces = 0;
    try {
      Assimp::Importer im;
      im.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
      InputLayerIO* io = nullptr;
      const aiScene* sc = import(im, io);
      if (io) io->rethrow();
      if (!sc) {
        reason = import_error(what, im.GetErrorString());
      } else {
        faces = extract(sc, points, tris);
        status = 0;
      }
    } catch (const std::exception& e) {
      reason = e.what();
    } catch (...) {
      reason = what + ": the mesh reader failed";
    }
    bool ok = write_all(fds[1], &status, 1);
    if (status == 0) {
      const uint64_t n[2] = {points.size(), faces};
      ok = ok && write_all(fds[1], n, sizeof n);
      if (faces <= kMaxMeshTriangles)
        ok = ok && write_all(fds[1], points.data(), points.size() * sizeof points[0]) &&
             write_all(fds[1], tris.data(), tris.size() * sizeof tris[0]);
    } else {
      const uint64_t n = reason.size();
      ok = ok && write_all(fds[1], &n, sizeof n) && write_all(fds[1], reason.data(), reason.size());
    }
    ::_exit(ok ? 0 : 1);
  }
  ::close(fds[1]);
  struct Reap {  // the child is waited for on every path (a throw included), killed if still running
    pid_t pid;
    int fd;
    int status = 0;
    bool done = false;
    int wait() {
      ::close(fd), fd = -1;
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      done = true;
      return status;
    }
    ~Reap() {
      if (done) return;
      ::kill(pid, SIGKILL);
      wait();
    }
  } child{pid, fds[0]};
  // Wall clock too, twice the CPU time plus a second: a starved or sleeping reader is stopped as well.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2 * cpu + 1);
  bool late = false;
  auto read_all = [&](int fd, void* data, size_t n) { return ::cloudgen::read_all(fd, data, n, deadline, late); };
  uint8_t status = 2;
  std::vector<std::array<float, 3>> points;
  std::vector<std::array<uint32_t, 3>> tris;
  std::string reason;
  bool complete = read_all(child.fd, &status, 1);
  if (complete && status == 0) {
    uint64_t n[2];
    complete = read_all(child.fd, n, sizeof n);
    if (complete && n[1] > kMaxMeshTriangles)
      throw InputError(what + ": " + std::to_string(n[1]) + " triangles; a mesh source may have at most " +
                       std::to_string(kMaxMeshTriangles) + " (decimate it first)");
    if (complete && n[0] > 3 * kMaxMeshTriangles + 3)  // more points than any triangles use: refused the same way
      throw InputError(what + ": " + std::to_string(n[0]) + " points; a mesh source may have at most " +
                       std::to_string(3 * kMaxMeshTriangles + 3));
    if (complete) {
      points.resize(n[0]), tris.resize(n[1]);
      complete = read_all(child.fd, points.data(), points.size() * sizeof points[0]) &&
                 read_all(child.fd, tris.data(), tris.size() * sizeof tris[0]);
    }
  } else if (complete && status == 1) {
    uint64_t n = 0;
    complete = read_all(child.fd, &n, sizeof n) && n < (1 << 20);
    if (complete) {
      reason.resize(n);
      complete = read_all(child.fd, reason.data(), n);
    }
  }
  if (late) ::kill(pid, SIGKILL);
  const int st = child.wait();
  throw_if_interrupted();
  if (WIFSIGNALED(st)) {
    const int sig = WTERMSIG(st);
    if (late || sig == SIGXCPU || sig == SIGKILL)
      throw InputError(what + ": the mesh reader (Assimp) was still reading after " + std::to_string(cpu) +
                       " s of CPU time (or twice that on the clock) and was stopped: a damaged file (a header that never ends, a count that "
                       "does not match the data)?");
    throw InputError(what + ": the mesh reader (Assimp) crashed on this file (signal " + std::to_string(sig) + ", " +
                     strsignal(sig) + "): a damaged file?");
  }
  if (!complete || status > 1) throw InputError(what + ": the mesh reader (Assimp) stopped without an answer");
  if (status == 1) throw InputError(reason);
  return mesh_from_arrays(std::move(points), std::move(tris), what);
}

}  // namespace

TriangleMesh read_mesh(const std::string& path, const std::string& what) {
  protect_input(path, "the mesh " + printable(path));  // a pipe or device: refused here
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw InputError(what + ": no such file");
  if (!S_ISREG(st.st_mode)) throw InputError(what + ": not a regular file");
  if (size_t(st.st_size) > kMeshFileCap)
    throw InputError(what + ": " + std::to_string(st.st_size) + " bytes; a mesh file may have at most " +
                     std::to_string(kMeshFileCap >> 20) + " MiB");
  TriangleMesh m = import_in_child(what, size_t(st.st_size), [&](Assimp::Importer& im, InputLayerIO*& io) {
    io = new InputLayerIO(what, false);
    im.SetIOHandler(io);  // the importer owns it
    return im.ReadFile(path, kSteps);
  });
  m.file = path;
  return m;
}

TriangleMesh read_mesh_bytes(const std::vector<uint8_t>& bytes, const std::string& extension, const std::string& what) {
  return import_in_child(what, bytes.size(), [&](Assimp::Importer& im, InputLayerIO*& io) {
    io = new InputLayerIO(what, true);
    im.SetIOHandler(io);
    return im.ReadFileFromMemory(bytes.data(), bytes.size(), kSteps, extension.c_str());
  });
}

TriangleMesh mesh_from_arrays(std::vector<std::array<float, 3>> points, std::vector<std::array<uint32_t, 3>> triangles,
                              const std::string& what) {
  TriangleMesh m;
  if (triangles.size() > kMaxMeshTriangles)
    throw InputError(what + ": " + std::to_string(triangles.size()) + " triangles; a mesh source may have at most " +
                     std::to_string(kMaxMeshTriangles) + " (decimate it first)");
  for (size_t v = 0; v < points.size(); ++v)
    for (float c : points[v])
      if (!std::isfinite(c) || std::abs(c) > kMaxMeshCoordinate)
        throw InputError(what + ": vertex " + std::to_string(v) + " has the coordinate " + fmt_float(c) +
                         "; allowed: finite, within +-" + fmt(kMaxMeshCoordinate));
  for (const auto& t : triangles)
    for (uint32_t i : t)
      if (i >= points.size())
        throw InputError(what + ": a triangle names vertex " + (i == 0xffffffffu ? std::string("beyond its mesh") : std::to_string(i)) +
                         " of " + std::to_string(points.size()));
  m.points = std::move(points);
  m.triangles = std::move(triangles);
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

}  // namespace cloudgen
