// OpenVDB export and import: the only translation unit that includes OpenVDB (its headers take
// 15-25 s to compile).
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/MultiResGrid.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <mutex>
#include <set>
#include <sstream>

#include "cloudgen/erosion.h"
#include "cloudgen/io.h"
#include "cloudgen/motion.h"
#include "cloudgen/schema.h"
#include "cloudgen/view.h"
#include "io/vdb_internal.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/interrupt.h"

// Under AddressSanitizer the address space is reserved in terabytes up front: no RLIMIT_AS then.
#if defined(__SANITIZE_ADDRESS__)
#define CLOUD_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CLOUD_UNDER_ASAN 1
#endif
#endif
#if defined(CLOUD_UNDER_ASAN)
#include <sanitizer/allocator_interface.h>
#include <sanitizer/common_interface_defs.h>

#include <thread>
#endif

namespace cloudgen {
namespace vdb {

void init() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// OpenVDB's convention: voxel (i,j,k)'s value sits at its centre, the integer index point, which
/// the transform maps to world space. Our voxel (i,j,k) covers [origin + i*vs, origin + (i+1)*vs),
/// so index (i,j,k) -> origin + (i + 0.5) * vs in the y-up frame. With up = 'z' a rotation of +90
/// degrees about x follows (right-handed, data unchanged): y-up (x, y, z) lands at (x, -z, y), the
/// height on +z as Blender expects.
openvdb::math::Transform::Ptr make_transform(const Volume& v, char up) {
  const double vs = v.voxel_size;
  const openvdb::Vec3d c0(v.origin[0] + 0.5 * vs, v.origin[1] + 0.5 * vs, v.origin[2] + 0.5 * vs);
  if (up != 'z') {
    auto xf = openvdb::math::Transform::createLinearTransform(vs);
    xf->postTranslate(c0);
    return xf;
  }
  // Written out rather than postRotate(pi/2), whose cos(pi/2) = 6e-17 leaves stray terms in the
  // map. Row-vector convention (world = index * M): the rows are the images of the index axes,
  // then the translation.
  const openvdb::Mat4d m(vs, 0.0, 0.0, 0.0,   //
                         0.0, 0.0, vs, 0.0,   //
                         0.0, -vs, 0.0, 0.0,  //
                         c0.x(), -c0.z(), c0.y(), 1.0);
  return openvdb::math::Transform::createLinearTransform(m);
}

/// The file's world frame back to the y-up frame: identity for 'y', (X, Y, Z) -> (X, Z, -Y) for 'z'.
openvdb::Vec3d to_y_up(const openvdb::Vec3d& w, char up) { return up == 'z' ? openvdb::Vec3d(w.x(), w.z(), -w.y()) : w; }

/// 'y' or 'z' from where the transform sends the index axes; InputError for anything else (other
/// rotations, shears), which a cloud volume reader would otherwise silently misplace.
char up_axis_of(const openvdb::math::Transform& xf, const std::string& path) {
  const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0.0));
  const double vs = xf.voxelSize()[0];
  auto axis = [&](int a) {
    openvdb::Vec3d e(0.0);
    e[a] = 1;
    return (xf.indexToWorld(e) - o) / vs;
  };
  auto near = [](const openvdb::Vec3d& a, const openvdb::Vec3d& b) { return (a - b).length() < 1e-6; };
  const openvdb::Vec3d x = axis(0), y = axis(1), z = axis(2);
  if (near(x, {1, 0, 0}) && near(y, {0, 1, 0}) && near(z, {0, 0, 1})) return 'y';
  if (near(x, {1, 0, 0}) && near(y, {0, 0, 1}) && near(z, {0, -1, 0})) return 'z';
  throw InputError(path + ": grid \"density\" has a rotated or sheared transform; cloudgen reads axis-aligned "
                          "y-up files and y-up files turned +90 degrees about x (export.vdb.up = z)");
}

openvdb::FloatGrid::Ptr make_empty_grid(const Volume& v, const std::string& name, bool half, char up) {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName(name);
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  grid->setTransform(make_transform(v, up));
  grid->setSaveFloatAsHalf(half);
  return grid;
}

openvdb::FloatGrid::Ptr make_grid(const Volume& v, const std::vector<float>& data, const std::string& name, bool half,
                                  char up) {
  auto grid = make_empty_grid(v, name, half, up);
  // Wrap our x-fastest buffer (no copy) and let OpenVDB's threaded copy activate every voxel
  // that differs from the background 0 (densities are >= 0, so exactly the cloud voxels).
  const openvdb::CoordBBox box(openvdb::Coord(0), openvdb::Coord(int(v.dims[0]) - 1, int(v.dims[1]) - 1,
                                                                 int(v.dims[2]) - 1));
  openvdb::tools::Dense<const float, openvdb::tools::LayoutXYZ> dense(box, data.data());
  openvdb::tools::copyFromDense(dense, *grid, 0.0f);
  openvdb::tools::prune(grid->tree());
  return grid;
}

openvdb::GridPtrVec make_empty_grids(const Volume& v, const ExportOptions& o) {
  openvdb::GridPtrVec grids{make_empty_grid(v, "density", o.vdb_half, o.vdb_up)};
  if (o.vdb_detail && !o.vdb_bake_erosion)
    for (int c = 0; c < 3; ++c)
      if (!v.detail[c].empty()) grids.push_back(make_empty_grid(v, v.detail_names[c], o.vdb_half, o.vdb_up));
  return grids;
}

namespace {

/// Where a detail channel can matter: the density's active voxels dilated by the one voxel that a
/// trilinear read reaches (26-neighbourhood), clipped to the volume, wrapped across x and z when
/// the volume tiles (the viewer's trilinear reads wrap there). Erosion only lowers density, so
/// detail outside this mask never changes a rendered value.
openvdb::MaskGrid::Ptr detail_mask(const Volume& v, const openvdb::FloatGrid& density) {
  auto mask = openvdb::MaskGrid::create(false);
  mask->tree().topologyUnion(density.tree());
  mask->tree().voxelizeActiveTiles();
  openvdb::tools::dilateActiveValues(mask->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  const openvdb::Coord hi(int(v.dims[0]) - 1, int(v.dims[1]) - 1, int(v.dims[2]) - 1);
  if (v.tiles_xz) {
    // Voxels dilated past an x or z face stand for the voxels on the opposite face.
    std::vector<openvdb::Coord> wrapped;
    for (auto it = mask->cbeginValueOn(); it; ++it) {
      openvdb::Coord c = it.getCoord();
      if (c.y() < 0 || c.y() > hi.y()) continue;
      bool out = false;
      for (int a : {0, 2}) {
        const int n = hi[a] + 1;
        if (c[a] < 0 || c[a] > hi[a]) c[a] = ((c[a] % n) + n) % n, out = true;
      }
      if (out) wrapped.push_back(c);
    }
    auto acc = mask->getAccessor();
    for (const auto& c : wrapped) acc.setValueOn(c);
  }
  mask->tree().clip(openvdb::CoordBBox(openvdb::Coord(0), hi));
  return mask;
}

}  // namespace

/// Metadata that write_vdb computes (never copied from Volume::metadata, which may hold a stale
/// string copy read from another file).
const std::set<std::string>& computed_meta() {
  static const std::set<std::string> k{"extinction_per_metre", "voxel_size_metres", "phase_g", "albedo",
                                       "up_axis", "tiles_xz", "density_units", "erosion_baked"};
  return k;
}

/// Linear with equal voxel edges. Not GridBase::hasUniformVoxels: OpenVDB's test divides by the
/// cube root of the determinant, which rounds badly for rotated maps (a +90 degree turn of 50 m
/// voxels fails it).
bool cubic_voxels(const openvdb::GridBase& g) {
  if (!g.transform().isLinear()) return false;
  const openvdb::Vec3d v = g.voxelSize();
  return v[0] > 0 && std::abs(v[1] - v[0]) <= 1e-9 * v[0] && std::abs(v[2] - v[0]) <= 1e-9 * v[0];
}

/// Metadata as text for Volume::metadata: doubles with every digit (OpenVDB's str() keeps 6, and a
/// sequence frame's motion.* values must come back exactly), anything else as OpenVDB writes it.
std::string meta_text(const openvdb::Metadata& m) {
  if (const auto* d = dynamic_cast<const openvdb::DoubleMetadata*>(&m)) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", d->value());
    return buf;
  }
  return m.str();
}

namespace {

/// An exception's text cut to a length that fits a terminal line (a damaged file once put a
/// 1.4 GB "grid type" into OpenVDB's message).
std::string short_what(const std::exception& e) {
  std::string w = e.what();
  if (w.size() > 300) w = w.substr(0, 297) + "...";
  return printable(w);
}

/// Where OpenVDB writes the 36-character file UUID: after the 8-byte magic, three 4-byte version
/// words and the one-byte "has grid offsets" flag.
constexpr std::streamoff kVdbUuidAt = 21;
constexpr size_t kVdbUuidLen = 36;

}  // namespace

/// The seal of a .vdb file: a name-based (version 5 layout) UUID made from two 64-bit hashes of
/// every byte of the file, the UUID's own 36 bytes read as zeros. cloudgen writes it in place of
/// OpenVDB's random UUID, so the same volume gives the same bytes (README), and a reader can tell
/// a file cloudgen wrote and nothing changed since (vet_vdb).
std::string file_seal(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw IoError(printable(path) + ": cannot read back: " + std::strerror(errno));
  uint64_t a = 0x9e3779b97f4a7c15ull, b = 0xc2b2ae3d27d4eb4full, total = 0;
  auto rotl = [](uint64_t x, int r) { return (x << r) | (x >> (64 - r)); };
  std::vector<unsigned char> buf(1 << 20);
  for (;;) {
    const ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      ::close(fd);
      throw IoError(printable(path) + ": cannot read back: " + std::strerror(e));
    }
    if (n == 0) break;
    for (uint64_t k = uint64_t(kVdbUuidAt); k < uint64_t(kVdbUuidAt) + kVdbUuidLen; ++k)
      if (k >= total && k < total + uint64_t(n)) buf[size_t(k - total)] = 0;
    size_t i = 0;
    for (; i + 8 <= size_t(n); i += 8) {
      uint64_t w;
      std::memcpy(&w, &buf[i], 8);
      a = rotl(a ^ w, 31) * 0x9e3779b97f4a7c15ull;
      b = rotl(b ^ w, 27) * 0xc2b2ae3d27d4eb4full;
    }
    // A read that ends off a multiple of 8 (the last one): its tail, byte by byte.
    for (; i < size_t(n); ++i) {
      a = (a ^ buf[i]) * 0x100000001b3ull;
      b = (b ^ buf[i]) * 0x100000001b3ull;
    }
    total += uint64_t(n);
  }
  ::close(fd);
  a ^= total, b ^= rotl(total, 17);
  a = (a ^ (a >> 33)) * 0xff51afd7ed558ccdull, a ^= a >> 33;
  b = (b ^ (b >> 33)) * 0xc4ceb9fe1a85ec53ull, b ^= b >> 33;
  char out[40];
  std::snprintf(out, sizeof out, "%08llx-%04llx-5%03llx-%04llx-%012llx", (unsigned long long)(a >> 32),
                (unsigned long long)((a >> 16) & 0xffff), (unsigned long long)(a & 0xfff),
                (unsigned long long)(0x8000 | ((b >> 48) & 0x3fff)), (unsigned long long)(b & 0xffffffffffffull));
  return out;
}

namespace {

/// Walks the parts of a .vdb file that OpenVDB reads before any grid (header, file metadata,
/// grid descriptors) with every length and offset checked against the file's size. OpenVDB
/// trusts them: a truncated or damaged file made it allocate and print gigabytes.
void check_vdb_layout(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(printable(path) + ": cannot open file");
  const uint64_t size = uint64_t(in.tellg());
  in.seekg(0);
  uint64_t pos = 0;
  auto bad = [&](const std::string& what) {
    throw InputError(printable(path) + ": not a valid OpenVDB file: " + what + " (the file has " + std::to_string(size) +
                     " bytes; truncated or damaged?)");
  };
  auto read = [&](void* dst, uint64_t n, const char* what) {
    if (n > size - pos) bad(std::string(what) + " at byte " + std::to_string(pos) + " runs past the end");
    in.read(static_cast<char*>(dst), std::streamsize(n));
    if (!in) bad(std::string("cannot read ") + what);
    pos += n;
  };
  auto skip_string = [&](const char* what, uint32_t max_len) {
    uint32_t n = 0;
    read(&n, 4, what);
    if (n > max_len || n > size - pos)
      bad(std::string(what) + " at byte " + std::to_string(pos - 4) + " claims " + std::to_string(n) + " bytes");
    in.seekg(std::streamoff(pos + n));
    pos += n;
  };
  int64_t magic = 0;
  read(&magic, 8, "magic number");
  if (magic != openvdb::OPENVDB_MAGIC) bad("no OpenVDB magic number at the start");
  uint32_t version = 0, lib[2];
  read(&version, 4, "file format version");
  if (version < openvdb::OPENVDB_FILE_VERSION_BOOST_UUID) return;  // ancient layout: left to OpenVDB
  read(lib, 8, "library version");
  char has_offsets = 0;
  read(&has_offsets, 1, "grid offsets flag");
  if (version < openvdb::OPENVDB_FILE_VERSION_SELECTIVE_COMPRESSION) {
    char c;
    read(&c, 1, "compression flag");
  }
  char uuid[36];
  read(uuid, 36, "file UUID");
  uint32_t meta_count = 0;
  read(&meta_count, 4, "metadata count");
  if (meta_count > 100000) bad("it claims " + std::to_string(meta_count) + " metadata entries");
  for (uint32_t i = 0; i < meta_count; ++i) {
    skip_string("metadata name", 1 << 16);
    skip_string("metadata type", 1 << 10);
    skip_string("metadata value", 1u << 30);
  }
  if (!has_offsets) return;  // a streamed file: grids follow one another, read by OpenVDB
  int32_t grids = 0;
  read(&grids, 4, "grid count");
  if (grids < 0 || grids > 100000) bad("it claims " + std::to_string(grids) + " grids");
  for (int32_t g = 0; g < grids; ++g) {
    skip_string("grid name", 1 << 16);
    skip_string("grid type", 1 << 10);
    if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) skip_string("grid instance parent", 1 << 16);
    int64_t off[3];
    read(off, 24, "grid offsets");
    for (int k = 0; k < 3; ++k)
      if (off[k] < int64_t(pos) || uint64_t(off[k]) > size)
        bad("grid " + std::to_string(g) + " ends at byte " + std::to_string(off[2]) + ", past the end");
    if (!(off[0] <= off[1] && off[1] <= off[2])) bad("grid " + std::to_string(g) + " has inconsistent offsets");
    in.seekg(off[2]);
    pos = uint64_t(off[2]);
  }
}

}  // namespace

/// Reads the whole file with OpenVDB in a child process under an address-space limit, so that a
/// damaged file that crashes OpenVDB's reader (a heap overflow in its leaf decompression, which no
/// check of ours can reach) or asks it for gigabytes ends the child, not us: InputError, exit 1.
void read_in_child(const std::string& path, uint64_t file_size) {
  const uint64_t budget = (uint64_t(1) << 30) + 32 * file_size;  // docs/robustness.md, "VDB"
  uint64_t vm_pages = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    unsigned long long pages = 0;
    if (std::fscanf(f, "%llu", &pages) == 1) vm_pages = pages;
    std::fclose(f);
  }
  [[maybe_unused]] const uint64_t limit = vm_pages * uint64_t(::sysconf(_SC_PAGESIZE)) + budget;  // (not under ASan)
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return;  // no child to spare: the reader runs in this process, as before
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);  // glibc's abort message: ours says it
    if (null >= 0) ::dup2(null, STDERR_FILENO);
#if !defined(CLOUD_UNDER_ASAN)
    struct rlimit rl{rlim_t(limit), rlim_t(limit)};
    ::setrlimit(RLIMIT_AS, &rl);
#else
    // The same budget on the heap ASan counts: a file that asks for gigabytes ends the child with
    // the memory answer (10), as the address-space limit does without ASan, instead of running
    // for seconds through ASan's quarantine (fuzz_vdb's timeouts).
    // A sanitizer report in the child is the child's death, which the parent reports; the death
    // callback a fuzzer installed (it saves the input as a crash) belongs to the parent.
    __sanitizer_set_death_callback([] { ::_exit(11); });
    std::thread([budget] {
      for (;;) {
        if (__sanitizer_get_current_allocated_bytes() > budget) ::_exit(10);
        ::usleep(500);
      }
    }).detach();
#endif
    int code = 0;
    try {
      std::ifstream in(path, std::ios::binary);
      in.exceptions(std::ios::failbit | std::ios::badbit);
      openvdb::io::Stream st(in, /*delayLoad=*/false);
      st.getGrids();
    } catch (const std::bad_alloc&) {
      code = 10;
    } catch (...) {
      code = 0;  // a refusal the parent's own read reports with its message
    }
    ::_exit(code);
  }
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) return;
    if (g_interrupted.load()) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw Cancelled();
    }
    ::usleep(1000);
  }
  if (WIFSIGNALED(status))
    throw InputError(printable(path) + ": damaged: OpenVDB's reader crashed on it (" + strsignal(WTERMSIG(status)) +
                     ", in a separate process: nothing here was harmed)");
  if (WIFEXITED(status) && WEXITSTATUS(status) == 10)
    throw InputError(printable(path) + ": reading it takes more than " + std::to_string(budget >> 20) +
                     " MiB of memory (1 GiB + 32 x its " + std::to_string(file_size) +
                     " bytes): damaged, or too large for this reader");
  // The child answers 0 (read, or refused with a message the parent's own read gives) or 10; any
  // other end (a library that calls exit, a sanitizer's report, which exits 1) is no answer, and
  // the parent must not read the file itself after it.
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw InputError(printable(path) + ": damaged: OpenVDB's reader stopped on it without an answer (exit status " +
                     std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                     ", in a separate process: nothing here was harmed)");
}

/// What every reader of a .vdb does before OpenVDB reads grids: the layout walk
/// (check_vdb_layout), then either the seal (a file cloudgen wrote, unchanged since: trusted) or,
/// for any other file, the read in a child process (read_in_child). A file with a cloudgen seal
/// that no longer matches its bytes was changed or damaged after writing and is refused.
void vet_vdb(const std::string& path) {
  check_vdb_layout(path);
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const uint64_t size = uint64_t(in.tellg());
  char uuid[kVdbUuidLen] = {};
  in.seekg(kVdbUuidAt);
  const bool sealed = in.read(uuid, kVdbUuidLen) && uuid[14] == '5' && uuid[8] == '-';
  if (sealed) {
    if (file_seal(path) == std::string(uuid, kVdbUuidLen)) return;
    throw InputError(printable(path) + ": damaged: its bytes no longer match the seal cloudgen wrote into its UUID "
                     "(changed or corrupted after writing; generate it again)");
  }
  read_in_child(path, size);
}

namespace {

/// A .vdb file read whole through io::Stream on a stream that throws on any failed read: OpenVDB
/// does not check its reads, and past the end of a damaged file it used values it never read
/// (a "compressed size" of 140 TB, found by fuzzing). io::File opens its own unchecked stream.
class VdbFile {
 public:
  explicit VdbFile(const std::string& path) : path_(path) {
    protect_input(path, "the input " + printable(path));
    init();
    vet_vdb(path);  // layout, then the seal or a read in a child process
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(printable(path) + ": cannot open file");
    in.exceptions(std::ios::failbit | std::ios::badbit);
    auto fail = [&](const std::string& why) {
      throw InputError(printable(path) + ": not a readable OpenVDB file (" + why + ")");
    };
    try {
      openvdb::io::Stream s(in, /*delayLoad=*/false);
      grids_ = s.getGrids();
      meta_ = s.getMetadata();
      compression_ = s.compression();
    } catch (const openvdb::Exception& e) {
      fail(short_what(e));
    } catch (const std::ios_base::failure&) {
      fail("it ends or breaks off in the middle of a grid");
    } catch (const std::bad_alloc&) {
      // OpenVDB sizes buffers from the file: a damaged one asks for absurd amounts.
      fail("it asks for more memory than is available: damaged, or too large for this machine");
    } catch (const std::length_error& e) {
      fail(short_what(e));
    }
    if (!grids_ || grids_->empty())
      throw InputError(printable(path) + ": the OpenVDB file holds no grids (empty, or truncated after its header)");
  }
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& g : *grids_) n.push_back(g->getName());
    return n;
  }
  /// The grid called `name` (the first, if several share it); nullptr if none.
  openvdb::GridBase::Ptr grid(const std::string& name) const {
    for (const auto& g : *grids_)
      if (g->getName() == name) return g;
    return nullptr;
  }
  const openvdb::GridPtrVec& grids() const { return *grids_; }
  const openvdb::MetaMap& metadata() const { return *meta_; }
  uint32_t compression() const { return compression_; }

 private:
  std::string path_;
  openvdb::GridPtrVecPtr grids_;
  openvdb::MetaMap::Ptr meta_;
  uint32_t compression_ = 0;
};


/// OpenVDB's io::File::write opens its own std::ofstream and never checks it, so a full disk
/// gave a truncated file and exit 0. Archive::write on our checked stream, with the same
/// `seekable` layout io::File writes, reports every failed write.
class CheckedVdbArchive : public openvdb::io::Archive {
 public:
  void write_to(std::ostream& os, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) const {
    openvdb::io::Archive::write(os, grids, /*seekable=*/true, meta);
  }
};

/// The levels of detail of `grids` (density and the detail channels; a frame's velocity has none):
/// NAME_level_1 .. NAME_level_N, OpenVDB's vdb_lod naming, made by its MultiResGrid. Level L's
/// voxel c is the full-weighting average (weights (1,2,1)/4 along each axis) of the level below
/// around voxel 2c, so every voxel of the finer level gives 1/8 of its value to the coarser one:
/// the sum times the voxel volume (the cloud's integral) is the same at every level. The transform
/// is the fine one scaled by 2^L in index space, so each level overlays the fine grid in world space.
openvdb::GridPtrVec lod_grids(const Volume& v, const openvdb::GridPtrVec& grids, const ExportOptions& o) {
  openvdb::GridPtrVec out;
  if (o.vdb_lod == 0) return out;
  check_lod_levels(o.vdb_lod, v.dims.data());
  for (const auto& base : grids) {
    auto src = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!src) continue;
    const std::string name = src->getName();
    if (name != "density" && std::find(std::begin(v.detail_names), std::end(v.detail_names), name) == std::end(v.detail_names))
      continue;
    // The restriction reads inactive values too, and the detail grids keep values under the voxels
    // their mask deactivated: averaged from a copy whose inactive values are 0, so a level holds
    // exactly what the active voxels hold.
    openvdb::FloatGrid::Ptr clean = src->deepCopy();
    for (auto it = clean->tree().beginValueOff(); it; ++it) it.setValue(0.0f);
    openvdb::tools::MultiResGrid<openvdb::FloatTree> levels(o.vdb_lod + 1, clean);  // takes the copy's tree
    for (uint32_t l = 1; l <= o.vdb_lod; ++l) {
      auto g = openvdb::FloatGrid::create(levels.treePtr(l));
      openvdb::tools::prune(g->tree());
      g->setName(name + "_level_" + std::to_string(l));
      g->setGridClass(openvdb::GRID_FOG_VOLUME);
      openvdb::math::Transform::Ptr xf = src->transform().copy();
      xf->preScale(double(1u << l));
      g->setTransform(xf);
      g->setSaveFloatAsHalf(o.vdb_half);
      g->insertMeta("lod_level", openvdb::Int32Metadata(int32_t(l)));
      g->insertMeta("voxel_size_metres", openvdb::DoubleMetadata(v.voxel_size * double(1u << l)));
      out.push_back(g);
    }
  }
  return out;
}

}  // namespace

void finish_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o,
                  double erosion_baked) {
  // The one-process writer, the MPI / tile assembler and the NanoVDB writer all pass here, so the
  // grids' topology, scale and metadata come out the same whichever path made the voxels.
  if (o.vdb_up != 'y' && o.vdb_up != 'z')
    throw InputError(std::string("export.vdb.up: \"") + o.vdb_up + "\" is not one of z, y");
  if (o.vdb_bake_erosion && erosion_baked < 0)
    throw InputError("export.vdb.bake_erosion needs the dense detail channels: it is not available for MPI or merged "
                     "outputs (write the baked VDB from one process, or keep the detail grids)");
  const View view = view_of_metadata(v.metadata, path);
  const Look look = look_of_view(view, path);
  const double extinction = look.extinction(v.voxel_size);
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0]);
  // Detail grids: exactly the density's voxels dilated by the one voxel a trilinear read reaches
  // (values outside never change a rendered value; inside, voxels whose detail is 0 are active
  // too, as the dense texture holds them).
  if (grids.size() > 1) {
    auto mask = detail_mask(v, *density);
    // A sub-box of a larger volume (a farm tile, `--region`): cloud just outside it can need the
    // detail on its faces, so the faces stay, and merged tiles equal the one-process file.
    bool partial = false;
    for (const auto& [k, val] : v.metadata) partial |= k == "region";
    if (partial) {
      auto acc = mask->getAccessor();
      const int n[3] = {int(v.dims[0]), int(v.dims[1]), int(v.dims[2])};
      for (int z = 0; z < n[2]; ++z)
        for (int y = 0; y < n[1]; ++y)
          for (int x = 0; x < n[0]; ++x)
            if (x == 0 || y == 0 || z == 0 || x == n[0] - 1 || y == n[1] - 1 || z == n[2] - 1)
              acc.setValueOn(openvdb::Coord(x, y, z));
    }
    tbb::parallel_for(size_t(1), grids.size(), [&](size_t i) {
      auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[i]);
      if (!g) return;  // not a detail channel (a sequence frame's velocity grid keeps its own topology)
      g->tree().topologyUnion(mask->tree());
      g->tree().topologyIntersection(mask->tree());
      g->tree().voxelizeActiveTiles();
      openvdb::tools::prune(g->tree());
    });
  }
  if (o.vdb_physical) {  // the grid holds extinction per metre: Principled Volume density 1
    const float k = float(extinction);
    openvdb::tools::foreach(density->beginValueOn(), [k](const openvdb::FloatGrid::ValueOnIter& it) {
      it.setValue(*it * k);
    });
  }
  // Keys the grid already holds (OpenVDB's own, e.g. is_saved_as_half_float of a volume read back
  // from a .vdb) keep their typed value: OpenVDB refuses to retype them.
  for (auto& [k, val] : v.metadata)
    if (!computed_meta().count(k) && k != "motion.box_min_y" && k != "motion.box_height" && !(*density)[k])
      density->insertMeta(k, openvdb::StringMetadata(val));
  // The physical scale any renderer needs to light the cloud like cloudviewer does.
  density->insertMeta("extinction_per_metre", openvdb::DoubleMetadata(extinction));
  density->insertMeta("voxel_size_metres", openvdb::DoubleMetadata(v.voxel_size));
  density->insertMeta("phase_g", openvdb::DoubleMetadata(look.g));
  density->insertMeta("albedo", openvdb::DoubleMetadata(look.albedo));
  density->insertMeta("up_axis", openvdb::StringMetadata(std::string(1, o.vdb_up)));
  density->insertMeta("tiles_xz", openvdb::BoolMetadata(v.tiles_xz));
  for (auto& [k, val] : v.metadata) {  // the motion's height box (generate.cpp volume_header), as numbers
    if (k != "motion.box_min_y" && k != "motion.box_height") continue;
    char* end = nullptr;
    double x = std::strtod(val.c_str(), &end);
    if (!val.empty() && end == val.c_str() + val.size() && std::isfinite(x)) density->insertMeta(k, openvdb::DoubleMetadata(x));
  }
  if (o.vdb_bake_erosion) density->insertMeta("erosion_baked", openvdb::DoubleMetadata(erosion_baked));
  density->insertMeta("density_units",
                      openvdb::StringMetadata(o.vdb_physical ? "extinction_per_metre" : "normalized"));
  // Never a creator starting with "Houdini": Blender then assumes a Y-up Houdini file and rotates it.
  density->setCreator(std::string("cloudgen ") + CLOUDGEN_VERSION);
}

void write_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o,
                 OutputBatch& batch, double erosion_baked) {
  finish_grids(v, grids, path, o, erosion_baked);
  openvdb::GridPtrVec all = grids;
  const openvdb::GridPtrVec levels = lod_grids(v, grids, o);  // after the physical scale and detail topology
  all.insert(all.end(), levels.begin(), levels.end());
  CheckedVdbArchive archive;
  uint32_t comp = openvdb::io::COMPRESS_ACTIVE_MASK;
  switch (o.vdb_compression) {
    case VdbCompression::Blosc:
      comp |= openvdb::io::Archive::hasBloscCompression() ? openvdb::io::COMPRESS_BLOSC : openvdb::io::COMPRESS_ZIP;
      break;
    case VdbCompression::Zip: comp |= openvdb::io::COMPRESS_ZIP; break;
    case VdbCompression::None: break;
  }
  archive.setCompression(comp);
  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata(std::string("cloudgen ") + CLOUDGEN_VERSION));
  // Only when there are levels, so files without them keep their bytes.
  if (o.vdb_lod > 0) meta.insertMeta("lod_levels", openvdb::Int32Metadata(int32_t(o.vdb_lod)));
  batch.stage(path, [&](const std::string& tmp) {
    write_file_stream(tmp, [&](std::ostream& os) {
      try {
        archive.write_to(os, all, meta);
        // Deterministic bytes, and a seal a reader checks: OpenVDB's random UUID replaced by one
        // made from the file's other bytes (file_seal).
        // A failed flush (a full disk) is left to write_file_stream, which reports the system's reason.
        if (os.flush()) {
          const std::string uuid = file_seal(tmp);
          os.seekp(kVdbUuidAt);
          os.write(uuid.data(), std::streamsize(uuid.size()));
        }
      } catch (const openvdb::Exception& e) {
        throw IoError(printable(path) + ": OpenVDB could not write the grids: " + e.what());
      }
    });
  });
}

void write_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o) {
  OutputBatch batch;
  write_grids(v, grids, path, o, batch, -1);
  batch.commit();
}

}  // namespace vdb

namespace {
using vdb::cubic_voxels;
using vdb::up_axis_of;
using vdb::to_y_up;
using vdb::VdbFile;
using vdb::check_vdb_layout;
using vdb::short_what;
using vdb::computed_meta;
void init_vdb() { vdb::init(); }
}  // namespace

namespace vdb {

openvdb::GridPtrVec export_grids(const Volume& v, const std::string& path, const ExportOptions& o,
                                 double* erosion_baked) {
  init();
  const View view = view_of_metadata(v.metadata, path);
  const Look look = look_of_view(view, path);
  const bool all_detail = !v.detail[0].empty() && !v.detail[1].empty() && !v.detail[2].empty();
  const std::vector<float>* dens = &v.density;
  std::vector<float> baked;
  if (o.vdb_bake_erosion && all_detail && look.erosion > 0) {
    // The height fraction runs over the box the viewer measures heights in for this file's
    // unbaked twin: the preset's box (motion.box_min_y / motion.box_height, which the volume
    // header records), else the box of the non-zero voxels (the viewer crops to it).
    uint32_t ylo = v.dims[1], yhi = 0;
    for (uint32_t z = 0; z < v.dims[2]; ++z)
      for (uint32_t y = 0; y < v.dims[1]; ++y)
        for (uint32_t x = 0; x < v.dims[0]; ++x)
          if (v.density[v.index(x, y, z)] > 0) ylo = std::min(ylo, y), yhi = std::max(yhi, y);
    baked.resize(v.density.size());
    double ny = yhi >= ylo ? double(yhi - ylo + 1) : 1.0;
    double y0 = double(ylo);  // in voxels from v's origin
    double min_y = 0, height = 0;
    if (motion_height_box(v.metadata, min_y, height)) {
      y0 = (min_y - v.origin[1]) / v.voxel_size;
      ny = height / v.voxel_size;
    }
    for (uint32_t z = 0; z < v.dims[2]; ++z)
      for (uint32_t y = 0; y < v.dims[1]; ++y)
        for (uint32_t x = 0; x < v.dims[0]; ++x) {
          const size_t i = v.index(x, y, z);
          baked[i] = float(eroded_density(v.density[i], v.detail[0][i], v.detail[1][i], v.detail[2][i],
                                          (double(y) - y0 + 0.5) / ny, look.erosion));
        }
    dens = &baked;
  }
  openvdb::GridPtrVec grids{make_grid(v, *dens, "density", o.vdb_half, o.vdb_up)};
  std::vector<std::pair<const std::vector<float>*, std::string>> todo;
  if (o.vdb_detail && !o.vdb_bake_erosion)
    for (int c = 0; c < 3; ++c)
      if (!v.detail[c].empty()) todo.push_back({&v.detail[c], v.detail_names[c]});
  grids.resize(todo.size() + 1);
  tbb::parallel_for(size_t(0), todo.size(), [&](size_t i) {
    grids[i + 1] = make_grid(v, *todo[i].first, todo[i].second, o.vdb_half, o.vdb_up);
  });
  if (erosion_baked) *erosion_baked = all_detail ? look.erosion : 0.0;
  return grids;
}

openvdb::GridPtrVec read_grids(const std::string& path) { return VdbFile(path).grids(); }

}  // namespace vdb

void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch) {
  double erosion = 0;
  const openvdb::GridPtrVec grids = vdb::export_grids(v, path, o, &erosion);
  vdb::write_grids(v, grids, path, o, batch, erosion);
}

Volume read_vdb(const std::string& path, uint64_t max_bytes) { return read_vdb_level(path, 0, max_bytes); }

uint32_t vdb_lod_levels(const std::string& path) {
  const VdbFile file(path);
  uint32_t n = 0;
  while (n < kMaxLodLevels && file.grid("density_level_" + std::to_string(n + 1))) ++n;
  return n;
}

namespace {
double grid_integral(const openvdb::FloatGrid& g) {
  double sum = 0;
  for (auto it = g.cbeginValueOn(); it; ++it) sum += double(*it) * double(it.getVoxelCount());
  const double vs = g.voxelSize()[0];
  return sum * vs * vs * vs;
}
}  // namespace

std::vector<VdbGridSummary> vdb_grid_summaries(const std::string& path) {
  const VdbFile file(path);
  std::vector<VdbGridSummary> out;
  for (const auto& base : file.grids())
    if (auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(base))
      out.push_back({g->getName(), g->voxelSize()[0], g->activeVoxelCount(), grid_integral(*g)});
  return out;
}

Volume read_vdb_level(const std::string& path, uint32_t level, uint64_t max_bytes) {
  const VdbFile file(path);
  openvdb::GridBase::Ptr base;
  const std::vector<std::string> names = file.names();
  if (std::find(names.begin(), names.end(), "density") == names.end()) {
    std::string have;
    for (auto& n : names) have += (have.empty() ? "" : ", ") + n;
    throw InputError(printable(path) + ": no float grid named \"density\" (grids: " + (have.empty() ? "none" : have) + ")");
  }
  // Level L reads NAME_level_L for every channel; the look (units, extinction, view, tiling) is
  // the full-resolution density's, which only it carries.
  const std::string suffix = level ? "_level_" + std::to_string(level) : "";
  auto fine = openvdb::gridPtrCast<openvdb::FloatGrid>(file.grid("density"));
  if (!fine) throw InputError(printable(path) + ": grid \"density\" is " + printable(file.grid("density")->valueType()) + ", expected float");
  if (level && !file.grid("density" + suffix)) {
    uint32_t have = 0;
    while (have < kMaxLodLevels && file.grid("density_level_" + std::to_string(have + 1))) ++have;
    throw InputError(printable(path) + ": no level of detail " + std::to_string(level) + " (grid \"density" + suffix +
                     "\"); the file has levels 0 .. " + std::to_string(have));
  }
  base = file.grid("density" + suffix);
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw InputError(printable(path) + ": grid \"density" + suffix + "\" is " + printable(base->valueType()) + ", expected float");
  if (grid->getGridClass() == openvdb::GRID_LEVEL_SET)
    throw InputError(printable(path) + ": grid \"density\" is a level set (signed distances to a surface), not a fog "
                     "volume of densities; convert it first (e.g. OpenVDB's sdfToFogVolume, or Houdini's VDB Convert)");
  if (!cubic_voxels(*grid))
    throw InputError(printable(path) + ": grid \"density\" needs a linear transform with cubic voxels");
  const char up = up_axis_of(grid->transform(), path);
  Volume v;
  openvdb::CoordBBox bb = grid->evalActiveVoxelBoundingBox();
  if (bb.empty()) throw InputError(printable(path) + ": grid \"density\" has no active voxels");
  if (!(grid->voxelSize()[0] > 0) || !std::isfinite(grid->voxelSize()[0]) || grid->voxelSize()[0] > 1e9)
    throw InputError(printable(path) + ": voxel size " + shortest_text(grid->voxelSize()[0]) + " is outside (0, 1e9] metres");
  const openvdb::Coord lo = bb.min(), dim = bb.dim();
  uint64_t count = 0, xy = 0;
  if (__builtin_mul_overflow(uint64_t(dim.x()), uint64_t(dim.y()), &xy) ||
      __builtin_mul_overflow(xy, uint64_t(dim.z()), &count) || dim.x() > 65536 || dim.y() > 65536 || dim.z() > 65536)
    throw InputError(printable(path) + ": the active bounding box " + std::to_string(dim.x()) + " x " +
                     std::to_string(dim.y()) + " x " + std::to_string(dim.z()) + " is too large to load densely");
  int channels = 1;
  for (int c = 0; c < 3; ++c) channels += std::find(names.begin(), names.end(), v.detail_names[c] + suffix) != names.end();
  check_read_budget(count, channels, 0, max_bytes, path);
  for (int a = 0; a < 3; ++a) v.dims[a] = uint32_t(dim[a]);
  v.voxel_size = grid->voxelSize()[0];
  // Index lo is the centre of the first voxel (OpenVDB's convention); our origin is its min corner.
  const openvdb::Vec3d w = to_y_up(grid->indexToWorld(lo.asVec3d()), up);
  for (int a = 0; a < 3; ++a) v.origin[a] = w[a] - 0.5 * v.voxel_size;
  auto fill = [&](const openvdb::FloatGrid& g, std::vector<float>& out) {
    out.assign(v.voxel_count(), 0.0f);
    for (auto it = g.cbeginValueOn(); it; ++it) {
      openvdb::CoordBBox vb;
      it.getBoundingBox(vb);
      vb.intersect(bb);
      // Detail grids reach beyond the density's bounding box; an empty intersection's iterator
      // would still visit coordinates, so skip it.
      if (vb.empty()) continue;
      for (auto c = vb.begin(); c; ++c) {
        const openvdb::Coord q = *c - lo;
        out[v.index(uint32_t(q.x()), uint32_t(q.y()), uint32_t(q.z()))] = *it;
      }
    }
  };
  fill(*grid, v.density);
  for (int c = 0; c < 3; ++c)
    if (std::find(names.begin(), names.end(), v.detail_names[c] + suffix) != names.end())
      if (auto d = openvdb::gridPtrCast<openvdb::FloatGrid>(file.grid(v.detail_names[c] + suffix)))
        fill(*d, v.detail[c]);
  check_finite_channels(v, path);
  grid = fine;  // the metadata below: the full-resolution density's
  for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it)
    if (it->first.rfind("file_", 0) != 0 && it->first != "class" && it->first != "name" &&
        !computed_meta().count(it->first))
      v.metadata.push_back({it->first, vdb::meta_text(*it->second)});
  // Every field cloudgen writes comes back: tiling, and normalised density from physical units.
  // A level is not periodic: its voxels straddle the fine box's faces and the restriction does not wrap.
  if (auto t = grid->getMetadata<openvdb::BoolMetadata>("tiles_xz")) v.tiles_xz = t->value() && level == 0;
  auto units = grid->getMetadata<openvdb::StringMetadata>("density_units");
  auto ext = grid->getMetadata<openvdb::DoubleMetadata>("extinction_per_metre");
  if (units && units->value() == "extinction_per_metre") {
    if (!ext || !(ext->value() > 0))
      throw InputError(path + ": density_units is extinction_per_metre but extinction_per_metre is missing or not positive");
    const float inv = float(1.0 / ext->value());
    for (float& d : v.density) d *= inv;
  }
  if (level) {
    // The extinction per metre at density 1 stays the full-resolution grid's: by default it
    // follows the voxel size (default_extinction_per_metre), which would thin a coarse level.
    View view = view_of_metadata(v.metadata, path);
    bool pinned = false;
    for (const auto& kv : view.render) pinned |= kv.first == "sigma_t";
    if (!pinned) {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", default_extinction_per_metre(fine->voxelSize()[0]));
      view.render.push_back({"sigma_t", buf});
      add_view_metadata(v.metadata, view);
    }
  }
  build_occupancy(v);
  return v;
}

std::string describe_vdb(const std::string& path) {
  const VdbFile file(path);
  std::ostringstream o;
  o << printable(path) << " (OpenVDB, compression " << openvdb::io::compressionToString(file.compression()) << ")\n";
  for (auto it = file.metadata().beginMeta(); it != file.metadata().endMeta(); ++it)
    o << "  file " << printable(it->first) << ": " << printable(it->second->str()) << "\n";
  // Levels of detail (export.vdb.lod, OpenVDB's vdb_lod naming): each level's voxel size.
  uint32_t levels = 0;
  while (levels < kMaxLodLevels && file.grid("density_level_" + std::to_string(levels + 1))) ++levels;
  if (levels > 0) {
    o << "  levels of detail: " << levels << " (density_level_1 .. density_level_" << levels << "; voxel size";
    for (uint32_t l = 0; l <= levels; ++l)
      o << (l ? ", " : " ") << file.grid(l ? "density_level_" + std::to_string(l) : "density")->voxelSize()[0];
    o << ")\n";
  }
  for (const openvdb::GridBase::Ptr& g : file.grids()) {
    o << "  grid \"" << printable(g->getName()) << "\": " << printable(g->valueType()) << ", class "
      << openvdb::GridBase::gridClassToString(g->getGridClass()) << ", voxel size " << g->voxelSize()[0]
      << ", active voxels " << g->activeVoxelCount() << ", saved as " << (g->saveFloatAsHalf() ? "half" : "float")
      << "\n";
    if (g->getName() == "density" && g->transform().isLinear()) {
      try {
        o << (up_axis_of(g->transform(), path) == 'z' ? "    up axis: z (height along +z: Blender)\n"
                                                       : "    up axis: y (height along +y: Houdini, Maya)\n");
      } catch (const InputError&) {
        o << "    up axis: neither y nor z (rotated transform)\n";
      }
    }
    openvdb::CoordBBox bb = g->evalActiveVoxelBoundingBox();
    if (!bb.empty()) {
      const openvdb::Vec3d a = g->indexToWorld(bb.min().asVec3d() - openvdb::Vec3d(0.5)),
                           b = g->indexToWorld(bb.max().asVec3d() + openvdb::Vec3d(0.5));
      const openvdb::Vec3d wlo = openvdb::math::minComponent(a, b), whi = openvdb::math::maxComponent(a, b);
      o << "    index bbox " << bb.min() << " .. " << bb.max() << ", world bbox " << wlo << " .. " << whi << "\n";
    }
    if (auto fg = openvdb::gridPtrCast<openvdb::FloatGrid>(g)) {
      // Finite values only in min/max; NaN and infinities counted (tiles count once per value).
      float lo = 0, hi = 0;
      size_t finite = 0, nan = 0, inf = 0;
      for (auto v = fg->cbeginValueOn(); v; ++v) {
        const float f = *v;
        if (std::isnan(f)) ++nan;
        else if (std::isinf(f)) ++inf;
        else if (finite++ == 0) lo = hi = f;
        else lo = std::min(lo, f), hi = std::max(hi, f);
      }
      if (finite) o << "    values min " << lo << ", max " << hi << ", background " << fg->background() << "\n";
      if (finite && !nan && !inf && fg->transform().isLinear())  // what a level of detail keeps (export.vdb.lod)
        o << "    integral (values x voxel volume): " << grid_integral(*fg) << " m^3\n";
      if (nan || inf)
        o << "    WARNING: " << nan << " NaN and " << inf << " infinite values (not valid densities)\n";
      if (g->getGridClass() == openvdb::GRID_LEVEL_SET)
        o << "    WARNING: a level set (signed distances), not a fog volume: cloudviewer refuses it as density\n";
    }
    for (auto m = g->beginMeta(); m != g->endMeta(); ++m)
      if (m->first.rfind("file_", 0) != 0)
        o << "    " << printable(m->first) << ": " << printable(m->second->str()) << "\n";
  }
  return o.str();
}

SceneInfo read_vdb_scene_info(const std::string& path) {
  init_vdb();
  check_vdb_layout(path);  // the header and grid descriptors, bounded, before io::File reads them
  openvdb::io::File file(path);
  openvdb::GridBase::Ptr g;
  try {
    file.open();
    if (!file.hasGrid("density")) {
      file.close();
      read_vdb(path);  // throws the reader's message (no density grid, grids present)
    }
    // Grid metadata only: OpenVDB stores the active bounding box as file_bbox_min / file_bbox_max.
    g = file.readGridMetadata("density");
  } catch (const openvdb::Exception& e) {
    throw InputError(printable(path) + ": not a readable OpenVDB file (" + short_what(e) + ")");
  } catch (const std::ios_base::failure& e) {
    throw InputError(printable(path) + ": not a readable OpenVDB file (" + short_what(e) + ")");
  } catch (const std::bad_alloc&) {
    throw InputError(printable(path) + ": not a readable OpenVDB file (it asks for more memory than is available)");
  }
  openvdb::CoordBBox bb;
  auto bmin = g->getMetadata<openvdb::Vec3IMetadata>("file_bbox_min");
  auto bmax = g->getMetadata<openvdb::Vec3IMetadata>("file_bbox_max");
  if (bmin && bmax) {
    bb = openvdb::CoordBBox(openvdb::Coord(bmin->value()), openvdb::Coord(bmax->value()));
  } else {
    bb = VdbFile(path).grid("density")->evalActiveVoxelBoundingBox();  // the checked full read
  }
  if (bb.empty()) throw InputError(path + ": grid \"density\" has no active voxels");
  if (!cubic_voxels(*g))
    throw InputError(path + ": grid \"density\" needs a linear transform with cubic voxels");
  SceneInfo s;
  s.up = up_axis_of(g->transform(), path);
  s.voxel_size = g->voxelSize()[0];
  const openvdb::Vec3d w = to_y_up(g->indexToWorld(bb.min().asVec3d()), s.up);
  for (int a = 0; a < 3; ++a) s.origin[a] = w[a] - 0.5 * s.voxel_size, s.dims[a] = uint32_t(bb.dim()[a]);
  for (auto it = g->beginMeta(); it != g->endMeta(); ++it)
    if (it->first.rfind("file_", 0) != 0 && it->first != "class" && it->first != "name")
      s.metadata.push_back({it->first, vdb::meta_text(*it->second)});
  while (s.lod_levels < kMaxLodLevels && file.hasGrid("density_level_" + std::to_string(s.lod_levels + 1))) ++s.lod_levels;
  file.close();
  return s;
}

}  // namespace cloudgen
