// What a frame is made of: the volume (loaded or synthetic) prepared for marching, camera, sun,
// the Mie table, and the parameter block both renderers consume. No OpenGL here.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cloudgen/volume.h"
#include "cloudviewer/params.h"
#include "cloudviewer/settings.h"

namespace cloudgen {
struct NanoVolume;  // cloudgen/nvdb.h
}

namespace cloudviewer {

/// True when this build links the cloudgen library (reads .vdb/.raw/.ktx2, generates .json presets).
bool has_cloudgen();

/// Loads INPUT: `synthetic:sphere|slab|blob|noise` or a file cloudgen reads / generates from.
/// Throws InputError (missing file, unknown kind, not a cloud volume, too large for the memory) with
/// the path in the message; cloudgen's IoError (the file could not be read) passes through.
cloudgen::Volume load_volume(const std::string& input);

/// Synthetic volumes for development and tests (no cloudgen needed):
///  sphere: 64^3 voxels of 10 m, a soft ball with hash-noise detail channels;
///  slab:   32x8x32 voxels of 5 m, density 1 everywhere (160 x 40 x 160 m), no detail;
///  blob:   96x48x96 voxels of 12 m, fBm-shaped cumulus with height profile and detail.
cloudgen::Volume synthetic_volume(const std::string& kind);

/// What the distance field's cells assume about the density (docs/viewer-speed.md, "The eroded
/// field"). With erosion 0 a cell holds density when one of its voxels has base density > 0, which
/// holds for every setting. With erosion E > 0 only when a voxel's base can exceed the erosion
/// threshold its detail gives at strength E (cloudgen/erosion.glsl erosion_bound) at a height it
/// can be seen at: its trilinear reach, widened by `height_slack` (height fractions) for the
/// motion's up flow. A field built so serves frames that erode at least as much, with no more up
/// flow, in the same placement (field_covers).
struct FieldRule {
  double erosion = 0;       ///< the erosion strength the field assumed (0: the base alone)
  double height_slack = 0;  ///< how far (height fractions) the seen height may lie from the texel's
  bool layer = false;       ///< heights are the layer's (texture v), not the box's height_min/size
  bool operator==(const FieldRule& o) const {
    return erosion == o.erosion && height_slack == o.height_slack && layer == o.layer;
  }
  bool operator<(const FieldRule& o) const {
    if (erosion != o.erosion) return erosion < o.erosion;
    if (height_slack != o.height_slack) return height_slack < o.height_slack;
    return layer < o.layer;
  }
};
/// Whether a field built for `built` is exact for a frame that needs `needed` (field_rule).
bool field_covers(const FieldRule& built, const FieldRule& needed);

/// Volume in the form both renderers sample: interleaved RGBA floats and the occupancy grid.
struct PreparedVolume {
  std::array<int, 3> dims{{0, 0, 0}};
  double voxel_size = 1;
  glm::dvec3 origin{0.0};
  bool tiles = false;
  bool has_detail = false;
  std::vector<float> rgba;  ///< x fastest, 4 channels
  int occ_cell = 8;         ///< voxels per coarse cell
  int occ_padding = 2;      ///< dilation in coarse cells
  std::array<int, 3> occ_dims{{0, 0, 0}};
  std::vector<uint8_t> occ;
  /// Distance field of the coarse grid: per cell, the L-infinity distance in cells to the nearest
  /// cell holding a voxel with density > 0 (the grid before padding; 0 there, capped at 255); see
  /// occupancy_distance. Distance skipping proves density 0 within (d - 1) cells - half a voxel.
  std::vector<uint8_t> dist;
  /// What `dist` (and moved_near_sat) assumed: the base alone unless fit_distance_field eroded it.
  FieldRule dist_rule;
  /// Moving clouds (box mode) skip through a grid make_frame builds every frame over the march box
  /// (frame.cpp build_moved_occupancy), whose cells are moved_reach_cells(*this) static cells wide
  /// and marked where a static cell they can show lies within that many cells of density. Built
  /// with the grid (moved_near_table): per static y layer, a summed-area table over (x, z) of those
  /// cells, (occ_dims.z + 1) x (occ_dims.x + 1) entries per layer, so no frame rebuilds it.
  std::vector<uint32_t> moved_near_sat;
  double occupied_fraction = 0;
  /// The box the motion measures heights in (y, world metres): the whole preset's when the file
  /// records it (cloudgen's motion.box_min_y / motion.box_height), else this volume's own.
  double height_min = 0, height_size = 1;
  /// A frame of a baked motion sequence (its metadata has time_seconds): already displaced, so the
  /// viewer shows it still.
  bool baked_motion = false;
  /// render.volume=nanovdb: the NanoVDB grids both renderers march (rgba is then empty).
  std::shared_ptr<const cloudgen::NanoVolume> nano;
  glm::dvec3 size() const { return glm::dvec3(dims[0], dims[1], dims[2]) * voxel_size; }
  glm::dvec3 center() const { return origin + 0.5 * size(); }
};

/// Validates the volume (size, memory, non-empty density, finite values) and takes its occupancy
/// grid: the volume's own when it carries one for this cell and padding (cloudgen builds it with
/// cloudgen::build_occupancy), else built with that same function. A cell is occupied when a voxel
/// within `padding` cells (26-neighbourhood, wrapped in x/z when tiling) has density > 0; that
/// conservativeness is what makes skipping image-neutral (trilinear reads reach half a voxel into
/// the next cell).
/// With `fit`, the distance field is built once for the rule those settings need (field_rule), as
/// fit_distance_field would rebuild it; without, for the base alone.
PreparedVolume prepare_volume(const cloudgen::Volume& v, int occ_cell, int occ_padding = 2,
                              const RenderSettings* fit = nullptr);
/// Rebuilds only the occupancy grid with another cell size / padding (cloudgen::build_occupancy).
void build_occupancy(PreparedVolume& p, int occ_cell, int occ_padding);
/// The most coarse cells render.occupancy_cell gets below 4 voxels: 2^23 (8 M). Opening a volume and
/// refitting its distance field (the panel's erosion) take about 150 ns a cell: cumulus-field 1024
/// opened in 4.0 s at 2-voxel cells (19 M), 1.0 s at 4.
constexpr uint64_t kMaxFineOccupancyCells = uint64_t(1) << 23;
/// The most coarse cells at any size: 2^25 (32 M; the grid and its distance field a byte each, the
/// field's search 8 bytes a cell while it runs).
constexpr uint64_t kMaxOccupancyCells = uint64_t(1) << 25;
/// render.occupancy_cell for a volume of nx x ny x nz voxels: `cell`, doubled while it is under 4
/// voxels and the grid has more than kMaxFineOccupancyCells cells, then while it has more than
/// kMaxOccupancyCells (the default 2 stays 2 on the thesis volume and cumulus-field 512 and
/// becomes 4 on cumulus-field 1024 and 2048).
int occupancy_cell_for(int cell, uint64_t nx, uint64_t ny, uint64_t nz);

/// Rebuilds the distance field (and moved_near_sat) under `rule` from the dense texels; a NanoVDB
/// volume keeps the base rule (its cells come from the active voxels).
void build_distance_field(PreparedVolume& p, FieldRule rule);
/// The rule the frame of settings `s` needs: its erosion when it erodes (the volume has detail,
/// erosion > 0) and no curl distortion moves the detail away from the base, the motion's up flow
/// as height slack, the placement.
FieldRule field_rule(const PreparedVolume& vol, const RenderSettings& s);
/// Rebuilds the distance field for `s` when its rule does not cover field_rule(vol, s); true when
/// it did (the renderer then needs set_distance_field). make_frame never trusts a field that does not
/// cover its settings: it skips by the thesis scheme instead.
bool fit_distance_field(PreparedVolume& vol, const RenderSettings& s);

/// The distance field of an occupancy grid of `n` cells (x fastest): for each cell, the L-infinity
/// (Chebyshev) distance in cells to the nearest occupied cell, exact, 0 on occupied cells, capped at
/// 255 (also when the grid has none). Wrapped in x and z when `tiles` and the `dims` are whole
/// multiples of `cell`; a tiling volume whose cells do not divide it has a partial last cell, so
/// there the field is the smaller of the unwrapped field and the wrapped one less one, at least 1
/// (a lower bound in voxels). Exactness is what makes distance skipping safe: no occupied cell lies
/// within (d - 1) cells of any point of a cell at distance d (lighting.glsl's empty_radius).
std::vector<uint8_t> occupancy_distance(const std::vector<uint8_t>& occ, const std::array<int, 3>& n, bool tiles,
                                        const std::array<int, 3>& dims, int cell);

/// Cells of the moved grid per static cell, kMovedCellVoxels (8) voxels / occ_cell, at least 1; 1
/// without a distance field (the padded grid then marks what is near density).
int moved_reach_cells(const PreparedVolume& vol);
/// PreparedVolume::moved_near_sat for `reach` (the cells with dist <= reach, or occ != 0 without
/// a distance field or with use_dist false).
std::vector<uint32_t> moved_near_table(const PreparedVolume& vol, int reach, bool use_dist = true);

/// Bytes prepare_volume allocates for a volume of `voxels` voxels (RGBA floats, occupancy).
uint64_t prepared_bytes(uint64_t voxels);
/// The nanovdb path (render.volume=nanovdb): the volume fields, has_detail and the occupancy grid
/// from the NanoVDB density grid's leaves and tiles (cloudgen::nano_occupancy: the same cells as
/// the dense builder, no dense copy). Validates like prepare_volume. Needs cloudgen.
PreparedVolume prepare_nano(std::shared_ptr<const cloudgen::NanoVolume> n, int occ_cell, int occ_padding = 2);
/// render.nanovdb_lookup=atlas (GL): the occupied part of the volume as bricks of a 3D texture the
/// texture unit filters, the usual GPU sparse-volume layout. Brick cell c (per axis) holds the
/// dense texels 8 c - 1 .. 8 c + 7 (9 per axis: a trilinear lookup whose lower corner i0 has
/// (i0 + 1) >> 3 == c finds its 8 corners in that brick), clamped or wrapped at the volume's sides
/// as the dense texture's sampler does. A cell whose 9^3 densities are all 0 has no brick (the
/// lookup returns 0). Values are the dense texture's, bit for bit (nanovdb_texel).
struct NanoAtlas {
  static constexpr int kBrick = 9;
  std::array<int, 3> cells{{0, 0, 0}};   ///< brick cells per axis: dims / 8 + 1 (0: no atlas)
  std::array<int, 3> layout{{0, 0, 0}};  ///< bricks per axis of the atlas texture
  int channels = 1;                      ///< 1: density; 4: density and the three detail values
  size_t bricks = 0;
  std::vector<uint16_t> index;  ///< per cell x fastest: the brick's first texel (x, y, z) and 1; all 0: none
  std::vector<float> texels;    ///< channels per texel, x fastest, layout * kBrick texels per axis
  uint64_t bytes() const { return uint64_t(index.size()) * 2 + uint64_t(texels.size()) * 4; }
};
/// The atlas of a nanovdb volume; none (cells 0) when a texture side would exceed max_side texels
/// or the atlas max_bytes. Needs cloudgen.
NanoAtlas build_nano_atlas(const PreparedVolume& v, int max_side, uint64_t max_bytes);
/// Bytes the dense path's budget allows (render.dense_budget MiB, or a third of the free memory when 0).
uint64_t dense_budget_bytes(const RenderSettings& s);
/// The largest RGBA32F texture render.volume=auto sends to the dense path: 2 GiB.
constexpr uint64_t kDenseTextureLimit = uint64_t(1) << 31;
/// Whether INPUT of `voxels` voxels goes through NanoVDB under s.volume (auto: the dense texture
/// and occupancy, prepared_bytes(voxels), exceed dense_budget_bytes(s), or the texture alone
/// kDenseTextureLimit).
bool use_nanovdb(const RenderSettings& s, uint64_t voxels);
/// Bytes the volume occupies on the GPU under `lookup` (render.nanovdb_lookup): the RGBA32F
/// texture, or the NanoVDB buffer and its leaf page table (8 bytes per 8^3 cell, when every grid
/// has one; atlas: neither, the GL renderer reports the atlas it builds), plus the R8 occupancy and R8UI
/// distance textures.
uint64_t volume_gpu_bytes(const PreparedVolume& v, NanoLookup lookup);
/// Bytes of the NanoVDB grids (0 for a dense volume).
uint64_t nano_grid_bytes(const PreparedVolume& v);
/// Bytes of memory this process may still allocate (MemAvailable, or physical memory).
uint64_t available_memory_bytes();
/// Throws InputError naming `what`, the estimate and what is available when `bytes` will not fit.
void check_memory(const std::string& what, uint64_t bytes);

/// The viewer's input dispatch, everything before OpenGL in one call (what main, the window, the
/// bench and a fuzz target use): load_volume then prepare_volume with the settings' occupancy grid,
/// or, when use_nanovdb says so, the NanoVDB grids (.nvdb read sparse, .vdb converted sparse,
/// other inputs converted from their dense channels) through prepare_nano.
/// Throws InputError / IoError as those do; never allocates what check_memory refuses.
PreparedVolume open_input(const std::string& input, const RenderSettings& s);

struct Camera {
  glm::dvec3 eye{0.0, 0.0, -10.0};
  glm::dvec3 target{0.0};
  double fov_y_deg = 60;
};
/// Sun from azimuth (degrees clockwise from north = -z, east = +x) and elevation (degrees).
struct Sun {
  double azimuth_deg = 0, elevation_deg = 35;
  glm::dvec3 direction() const;
};

/// Camera framing the whole volume from the side (-z), slightly above its middle.
Camera default_camera(const PreparedVolume& vol, double fov_y_deg, double aspect);
/// Sun behind the viewer (the camera's azimuth seen from the target), 35 degrees up.
Sun default_sun(const Camera& cam);

/// The Mie phase function of cloud droplets per colour channel: Lorenz-Mie (cloudgen::phase, water
/// n = 1.331 / 1.333 / 1.337) at 650, 550 and 450 nm over cloudgen's default droplet population
/// (modified gamma, effective radius 10 um, variance 0.111), `size()` angles over theta = 0..pi,
/// each channel normalised to 1 over the sphere under phase.glsl's log-space interpolation.
struct MiePhaseTable {
  std::vector<float> rgb;  ///< 3 floats per angle: red, green, blue
  int size() const { return int(rgb.size() / 3); }
  float at(int i, int channel) const { return rgb[size_t(i) * 3 + size_t(channel)]; }
};
/// The table render.phase=mie reads (the --mie-table file if one was loaded), computed at its
/// first use and cached: ~0.9 s per wavelength on 2 cores, so renderers ask only for Mie frames.
const MiePhaseTable& mie_phase_table();
/// Bumped by every load_mie_table, so a GPU copy knows when to upload the table again.
int mie_table_generation();
/// Replaces the computed Mie table with one read from a text file (`--mie-table`): '#' comments,
/// then one value per line (uniform over theta = 0..180 degrees), two columns "theta_degrees value"
/// (whitespace) or `cloudgen phase`'s CSV (a header line "angle_deg,r,g,b", then one row per angle,
/// one value per channel); one value is used for all three channels. Angles increasing, covering
/// 0 and 180. Resampled to CV_MIE_TABLE_SIZE angles and each channel normalised to 1 over the
/// sphere. An empty path restores the computed table. Throws InputError naming the file and line.
void load_mie_table(const std::string& path);

/// Layer-mode coverage map: n x n texels, RG interleaved (coverage, cloud type), tileable fBm.
const std::vector<float>& coverage_map(int n = 256);

/// Position given in the volume's unit box (the bench track's "volume" space) in world metres. In
/// layer mode x and z count texture tiles and y runs from the layer bottom (0) to its top (1).
glm::dvec3 volume_space_to_world(const PreparedVolume& vol, const RenderSettings& s, const glm::dvec3& uvw);
/// Layer bottom and top altitudes (m above the ground) after the auto rules.
glm::dvec2 layer_altitudes(const PreparedVolume& vol, const RenderSettings& s);
/// World height of the ground plane after the auto rule.
double ground_height(const PreparedVolume& vol, const RenderSettings& s);
/// The default camera for the settings' mode (layer: below the layer, looking at the horizon).
Camera default_camera(const PreparedVolume& vol, const RenderSettings& s, double fov_y_deg, double aspect);

/// Projection used by both renderers (near 0.5 m, far 1e6 m, OpenGL clip conventions), and the
/// camera-relative view (camera at the origin).
glm::dmat4 view_projection(const Camera& cam, int width, int height);

/// The ground shadow map (render.shadow_map) has at most this many texels per side: make_frame
/// doubles the texel until it fits.
constexpr int kMaxShadowMapSide = 2048;
/// The light volume (render.light_volume) never has more texels than this: make_frame doubles
/// render.light_volume_scale until it fits.
constexpr int kMaxLightVolumeTexels = 1 << 22;
/// The diffusion volume (render.ms_volume) never has more cells than this (64^3): make_frame
/// doubles render.ms_volume_scale until it fits.
constexpr int kMaxMsVolumeCells = 1 << 18;

struct FrameSetup {
  int width = 0, height = 0;
  Camera camera;
  Sun sun;
  RenderSettings settings;
  ref::CloudParams params;   ///< double values, already rounded to float (what the GPU sees)
  glm::dmat4 view_proj;      ///< camera-relative
  glm::dmat4 inv_view_proj;  ///< rounded to float, like the GPU's
  double ground_half_extent = 0;
  /// Motion table (medium.glsl): D(h) at CV_MOTION_LUT_SIZE heights for this frame's time (row 0)
  /// and, for temporal reprojection, the previous frame's (row 1; the GL renderer fills it in).
  /// Empty when the clouds are still.
  std::vector<glm::dvec3> motion_table;
  /// Moving clouds in box mode: the occupancy of the march box at this time, params.moved_occ_dims
  /// cells of params.moved_occ_cell_m from params.march_min_m (x fastest, 0 or 1), which both
  /// renderers' occupied() reads instead of the volume's grid (medium.glsl). Empty otherwise, and
  /// when no call reads occupied() (distance skipping without render.occupancy_light: make_frame).
  std::vector<uint8_t> moved_occupancy;
};

/// motion_displacement (cloudgen/motion.glsl) at CV_MOTION_LUT_SIZE evenly spaced heights in
/// [0, 1] at time t: one row of FrameSetup::motion_table.
std::vector<glm::dvec3> motion_table_row(const RenderSettings& s, double t);

/// The phase function's slots of the parameter block (render.phase and its parameters; the HG +
/// Draine fit evaluated at render.droplet_diameter).
void set_phase_params(ref::CloudParams& p, const RenderSettings& s);

/// Fills the parameter block from the volume, settings, camera and sun.
FrameSetup make_frame(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam,
                      const Sun& sun, int width, int height);

/// The window's frame: make_frame with `s`, or, when the volume refuses them (InputError: a panel
/// choice such as render.mode=layer on a volume that does not tile, render.skipping=tree on the
/// dense path), `s` put back to `good` (the last settings a frame took; its time and frame index
/// kept) with the refusal in `refused`. `good` follows every frame that succeeds. Throws when
/// `good` is refused too (the command line's own settings).
FrameSetup make_frame_or_keep(const PreparedVolume& vol, RenderSettings& s, RenderSettings& good, const Camera& cam,
                              const Sun& sun, int width, int height, std::string& refused);

}  // namespace cloudviewer
