// Meshes as shape sources (shape.h, `{"kind": "mesh", "file": "PATH"}`): the reader (OBJ, PLY, STL,
// glTF/GLB through Debian's Assimp) and the signed distance to the placed mesh (OpenVDB's
// mesh-to-level-set, sampled from a dense copy). Neither Assimp's nor OpenVDB's headers leak out of
// this header: both compile slowly and only mesh_source.cpp / mesh_distance.cpp need them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cloudgen {

/// A triangle mesh in its file's own units and axes (node transforms applied), checked: at least
/// one triangle, every coordinate finite and within +-kMaxMeshCoordinate, every index in range.
struct TriangleMesh {
  std::string file;                              ///< as named (for messages)
  std::vector<std::array<float, 3>> points;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::array<double, 3> lo{}, hi{};              ///< bounding box of the points used by triangles
  size_t open_edges = 0;  ///< edges with one triangle (after joining equal points): > 0 = not closed
  double area = 0;        ///< total triangle area, in the file's units squared
  uint64_t fnv1a = 0;     ///< FNV-1a of the points' and triangles' bytes (the preset hash's part)
};

/// The largest mesh file read (bytes): a binary STL of about 5 M triangles.
inline constexpr size_t kMeshFileCap = size_t(256) << 20;
/// The most triangles a mesh source may have.
inline constexpr size_t kMaxMeshTriangles = 5'000'000;
/// The largest coordinate a mesh may use (in its own units).
inline constexpr double kMaxMeshCoordinate = 1e7;

/// Reads `path` (format from its extension: .obj .ply .stl .gltf .glb .fbx .dae .off ...) through
/// the one input layer (input_scope.h: protected as an input, no pipes, at most kMeshFileCap; the
/// files it names, such as a glTF's buffers or an OBJ's materials, too). Assimp runs in a child
/// process with a CPU-time limit (2 s + 1 s per MiB; twice that + 1 s on the clock) and an 8 GiB
/// address-space limit, since it loops forever or crashes on some damaged files (fuzz_mesh found a
/// PLY header that never ends): either becomes an InputError here. `what` names the file in errors. Throws InputError: missing
/// or unreadable as a mesh, no triangles, a coordinate that is NaN, infinite or beyond the limit,
/// too many triangles.
TriangleMesh read_mesh(const std::string& path, const std::string& what);
/// The same from bytes in memory; `extension` ("obj", "stl", ...) picks the reader.
TriangleMesh read_mesh_bytes(const std::vector<uint8_t>& bytes, const std::string& extension, const std::string& what);
/// The checks of a mesh (triangle count, finite coordinates within the limit, indices in range, at
/// least one triangle of non-zero area), its box, open edges, area and hash; InputError naming
/// `what` otherwise. What the readers above end with (and what fuzz_mesh drives directly).
TriangleMesh mesh_from_arrays(std::vector<std::array<float, 3>> points, std::vector<std::array<uint32_t, 3>> triangles,
                              const std::string& what);

/// A float grid of a VDB file as a shape source (`{"kind": "vdb", "file": ..., "grid": ...}`): a
/// level set (Houdini's, OpenVDB's, Blender's Mesh to SDF) or a fog volume (a cloud, Blender's Mesh
/// to Volume) whose surface is where its density is `iso`. Read by the checked VDB reader (the
/// seal, or the read in a child process: docs/robustness.md).
struct VdbShape {
  std::string file, grid;
  bool level_set = false;
  double iso = 0.5;
  char up = 'y';                        ///< the file's up axis ('z': Blender's frame, or cloudgen's z-up files)
  std::array<double, 3> lo{}, hi{};     ///< the y-up world box of the grid's active voxels
  uint64_t fnv1a = 0;                   ///< of the file's seal, the grid's name, iso and up (the preset hash's part)
  std::shared_ptr<const void> grid_ptr;  ///< the openvdb::FloatGrid (mesh_distance.cpp only)
};

/// Reads grid `grid` of `path` ("": "density" if the file has it, else its first float grid).
/// `up`: the file's up axis, 0 for the file's own (cloudgen's z-up files say so; others are y-up).
/// Throws InputError: no such grid, not a float grid, no active voxels, a fog volume that never
/// reaches `iso`.
VdbShape read_vdb_shape(const std::string& path, const std::string& grid, double iso, char up, const std::string& what);

/// The signed distance to a placed mesh (negative inside; for an open mesh, the unsigned distance
/// to its surface, a sheet), sampled on a dense lattice of spacing h over the mesh's box grown by
/// `band` + 2 h, trilinear between samples, clamped to [-band', band'] (band' >= band, the
/// narrow band's half width): the field is the true distance where |d| < band, and +-band' beyond.
class MeshDistance {
 public:
  /// `world(q)` of each mesh point is `to_world` applied to it; h > 0 the lattice spacing; band >= 0.
  /// Throws InputError when the lattice would exceed kMaxMeshSamples.
  MeshDistance(const TriangleMesh& m, const std::array<double, 12>& to_world, double h, double band);
  /// The same for a VDB grid: its level set (a fog volume's at `iso`) rebuilt with a band of at
  /// least `band`, then sampled at the lattice's points placed back in the file's frame.
  MeshDistance(const VdbShape& g, const std::array<double, 12>& to_world, double h, double band);
  double distance(const std::array<double, 3>& p) const;
  /// A lower bound of distance() over the box [lo, hi] (world): the least sample that any point of
  /// the box interpolates from (a trilinear value is a convex combination of its 8 samples). Exact.
  double lower_bound(const std::array<double, 3>& lo, const std::array<double, 3>& hi) const;
  /// The world box of the placed mesh's points.
  const std::array<double, 3>& mesh_lo() const { return mesh_lo_; }
  const std::array<double, 3>& mesh_hi() const { return mesh_hi_; }
  double band() const { return band_; }
  double spacing() const { return h_; }
  bool signed_distance() const { return signed_; }

 private:
  double sample(int64_t i, int64_t j, int64_t k) const;
  /// Sets the lattice over [mesh_lo_, mesh_hi_] grown by the band; returns the half width in samples.
  int setup(double band, const std::string& what);
  /// The per-block minima, once v_ is filled.
  void finish();
  std::array<double, 3> lo_{}, mesh_lo_{}, mesh_hi_{};
  double h_ = 1, band_ = 0;
  std::array<int64_t, 3> n_{};
  std::vector<float> v_;     ///< n_[0] * n_[1] * n_[2] samples, x fastest
  std::vector<float> bmin_;  ///< per block of 8^3 samples, the least
  std::array<int64_t, 3> nb_{};
  bool signed_ = true;
};

/// The most samples one mesh's lattice may have (128 MiB of floats).
inline constexpr size_t kMaxMeshSamples = size_t(32) << 20;

}  // namespace cloudgen
