// The preset parameter table and the JSON reader it drives.
#include "cloudgen/preset.h"

#include <cstdio>
#include <cstdlib>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "cloudgen/channel.h"
#include "cloudgen/io.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/param_group.h"
#include "cloudgen/preset_fields.h"
#include "cloudgen/preset_save.h"
#include "cloudgen/schema.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/printable.h"
#include "cloudgen/weather_map.h"
#include "cloudviewer/render_check.h"

namespace cloudgen {
namespace {

using json = nlohmann::json;
using Index = std::vector<size_t>;

/// One key of the table: its declaration (schema.h) and what it sets in a Preset.
struct Spec {
  FieldSpec field;
  ParamPlace place;  ///< the panel's and the docs' group (param_group.h)
  std::function<void(Preset&, const json&, const Index&)> set;
};

std::string fmt(double v) { return shortest_text(v); }

const char* kChannelNames[4] = {"r", "g", "b", "a"};
constexpr HeightProfile kHeightProfiles[] = {HeightProfile::Exponential, HeightProfile::Stratus, HeightProfile::Cumulus,
                                             HeightProfile::Cumulonimbus};
constexpr VdbCompression kCompressions[] = {VdbCompression::Blosc, VdbCompression::Zip, VdbCompression::None};
constexpr Texel kTexels[] = {Texel::Rgba8, Texel::Rgba16f, Texel::Rgba32f};
constexpr NvdbPrecision kPrecisions[] = {NvdbPrecision::Float, NvdbPrecision::Fp16, NvdbPrecision::Fp8,
                                         NvdbPrecision::Fp4, NvdbPrecision::FpN};

/// The choices of a string key, from the enum's one name table.
template <class E, size_t N>
std::vector<std::string> names_of(const E (&values)[N], const char* (*name)(E)) {
  std::vector<std::string> v;
  for (E e : values) v.push_back(name(e));
  return v;
}

/// A key that may be unset (its default is "null"): null unsets it, a value sets it. The schema
/// lets null through for exactly these keys (FieldSpec::nullable).
template <class T>
void set_optional(std::optional<T>& dst, const json& j) {
  if (j.is_null()) dst.reset();
  else dst = j.get<T>();
}

/// The `shape` section (shape.h): its keys, in world metres, y up; voxel (i, j, k) is centred at
/// origin + (i + 0.5, j + 0.5, k + 0.5) * voxel_size.
template <class Add>
void add_shape_keys(Add& add, double big) {
  auto src = [](Preset& p, const Index& i) -> ShapeSource& { return p.shape.sources[i[0]]; };
  auto v3 = [](const json& j) { return ShapeVec{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; };
  const std::string where = " World metres, y up: voxel (i, j, k) is centred at origin + (i + 0.5, j + 0.5, k + 0.5) * voxel_size.";
  add("/shape/blend", "number", "0", 0, big,
      "(metres) Smooth-union width of the sources (polynomial smooth-min); 0 = hard union.",
      [](Preset& p, const json& j, const Index&) { p.shape.blend = j.get<double>(); });
  add("/shape/falloff", "number", "100", 1e-3, big,
      "(metres) Width of the edge: base density s = S(clamp(0.5 - d / falloff, 0, 1)), S(u) = u^2 (3 - 2u), "
      "d the signed distance to the sources (negative inside); s = 0.5 on the surface, 0 from falloff / 2 outside.",
      [](Preset& p, const json& j, const Index&) { p.shape.falloff = j.get<double>(); });
  add("/shape/floor", "number", "null", -big, big,
      "(metres, world y) Cuts the shape flat below this height: d = max(d, floor - y). A cumulus's flat base at "
      "the condensation level. Unset: no cut.",
      [](Preset& p, const json& j, const Index&) { set_optional(p.shape.floor, j); });
  add("/shape/ceiling", "number", "null", -big, big,
      "(metres, world y) Cuts the shape flat above this height: d = max(d, y - ceiling). An anvil spreading "
      "under the tropopause. Unset: no cut.",
      [](Preset& p, const json& j, const Index&) { set_optional(p.shape.ceiling, j); });
  add("/shape/sources", "array", "[]", 0, 0,
      "Shape sources (docs/shaping.md), at most " + std::to_string(kMaxShapeSources) + ". Non-empty: s replaces the height profile, towers and coverage, and "
      "density = clamp(density_scale * (R * s - t) / (1 - t), 0, 1).",
      [](Preset& p, const json& j, const Index&) { p.shape.sources.resize(j.size()); });
  add("/shape/sources/*/kind", "string", "null", 0, 0,
      "Required. ellipsoid (center, radii), sphere (center, radius), capsule (a, b, radius), mesh (file) or vdb "
      "(file, grid).",
      [=](Preset& p, const json& j, const Index& i) {
        src(p, i).kind.reset();
        for (ShapeKind k : {ShapeKind::Ellipsoid, ShapeKind::Sphere, ShapeKind::Capsule, ShapeKind::Mesh, ShapeKind::Vdb})
          if (j.is_string() && j.get<std::string>() == shape_kind_name(k)) src(p, i).kind = k;
      },
      {"ellipsoid", "sphere", "capsule", "mesh", "vdb"});
  add("/shape/sources/*/file", "string", "null", 0, 0,
      "Mesh: an OBJ, PLY, STL, glTF/GLB (or another format Assimp reads) file; vdb: a .vdb file. Relative to the "
      "preset's folder (to the current folder with --set). Closed meshes give a solid, open ones a sheet (with a "
      "warning); at most " +
          std::to_string(kMaxMeshTriangles) + " triangles and " + std::to_string(kMeshFileCap >> 20) + " MiB.",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).file, j); });
  add("/shape/sources/*/grid", "string", "null", 0, 0,
      "Vdb: the float grid to read (a level set, or a fog volume cut at iso); unset: \"density\" if the file "
      "has it, else its first float grid.",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).grid, j); });
  add("/shape/sources/*/iso", "number", "null", 1e-9, 1e9,
      "Vdb: a fog volume's density at the surface (unset: 0.5); a level set's surface is its zero.",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).iso, j); });
  add("/shape/sources/*/up", "string", "null", 0, 0,
      "Vdb: the file's up axis: z for Blender's files, y for Houdini's; unset: the file's own (cloudgen writes "
      "it in the transform), else y.",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).up, j); },
      {"y", "z"});
  add("/shape/sources/*/fit", "bool", "false", 0, 0,
      "Mesh or vdb: scale it evenly and centre it so it fills the volume (less falloff / 2, the billows' amplitude and one voxel a side), after "
      "scale and rotate; translate then moves it from there.",
      [=](Preset& p, const json& j, const Index& i) { src(p, i).fit = j.get<bool>(); });
  add("/shape/sources/*/center", "vec3", "null", -big, big, "(metres) Ellipsoid or sphere centre." + where,
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).center, j); });
  add("/shape/sources/*/radii", "vec3", "null", 1e-3, big, "(metres) Ellipsoid semi-axes along x, y, z (before rotate).",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).radii, j); });
  add("/shape/sources/*/radius", "number", "null", 1e-3, big, "(metres) Sphere or capsule radius.",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).radius, j); });
  add("/shape/sources/*/a", "vec3", "null", -big, big, "(metres) Capsule: one end of its axis." + where,
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).a, j); });
  add("/shape/sources/*/b", "vec3", "null", -big, big, "(metres) Capsule: the other end of its axis.",
      [=](Preset& p, const json& j, const Index& i) { set_optional(src(p, i).b, j); });
  add("/shape/sources/*/scale", "vec3", "[1, 1, 1]", 1e-3, 1e3,
      "Scale along the source's own axes about its centre (a capsule's: the middle of a-b; uniform for capsules), "
      "applied first.",
      [=](Preset& p, const json& j, const Index& i) { src(p, i).scale = v3(j); });
  add("/shape/sources/*/rotate", "vec3", "[0, 0, 0]", -360, 360,
      "(degrees) Right-handed rotation about the source's centre: about x, then y, then z (fixed axes), after scale.",
      [=](Preset& p, const json& j, const Index& i) { src(p, i).rotate = v3(j); });
  add("/shape/sources/*/translate", "vec3", "[0, 0, 0]", -big, big, "(metres) Moves the source, applied last.",
      [=](Preset& p, const json& j, const Index& i) { src(p, i).translate = v3(j); });
}

/// The billowy and wispy modifiers of the shape (shape.h ShapeModifier).
template <class Add>
void add_modifier_keys(Add& add, double big) {
  for (const bool billowy : {true, false}) {
    const std::string base = billowy ? "/shape/billowy" : "/shape/wispy";
    auto m = [billowy](Preset& p) -> ShapeModifier& { return billowy ? p.shape.billowy : p.shape.wispy; };
    add(base + "/amplitude", "number", "0", 0, big,
        billowy ? "(metres) Cauliflower billows: the surface moves out along the distance's gradient by up to this "
                  "much, d' = d - amplitude * w * B, B an fBm of Worley domes sqrt(1 - F1^2) in [0, 1]. 0 = off."
                : "(metres) Wisps: the surface is eroded in by up to this much, d' = d + amplitude * w * E, E an fBm of "
                  "Perlin noise advected along curl noise, in [0, 1]. 0 = off.",
        [m](Preset& p, const json& j, const Index&) { m(p).amplitude = j.get<double>(); });
    add(base + "/period", "number", "400", 1e-3, big,
        "(metres) Size of the first octave's cells; each next octave is half as big.",
        [m](Preset& p, const json& j, const Index&) { m(p).period = j.get<double>(); });
    add(base + "/octaves", "integer", "3", 1, 8, "Octaves of the noise.",
        [m](Preset& p, const json& j, const Index&) { m(p).octaves = j.get<int>(); });
    add(base + "/gain", "number", "0.6", 0, 1, "Weight of each octave against the one before (0.6: a rough, fractal edge).",
        [m](Preset& p, const json& j, const Index&) { m(p).gain = j.get<double>(); });
    add(base + "/heights", "vec2", "null", -big, big,
        billowy ? "(metres, world y) Height ramp [from, to]: no billows at `from`, full at `to` (a cumulus's "
                  "billows grow toward its top). Unset: everywhere."
                : "(metres, world y) Height ramp [from, to]: no wisps at `from`, full at `to`; from > to makes them "
                  "strongest low down (a ragged base). Unset: everywhere.",
        [m](Preset& p, const json& j, const Index&) { set_optional(m(p).heights, j); });
    add(base + "/depth", "number", "300", 1e-3, big,
        "(metres) Depth below the surface over which the modifier fades out (keeps the interior whole).",
        [m](Preset& p, const json& j, const Index&) { m(p).depth = j.get<double>(); });
    if (billowy) continue;
    add(base + "/warp", "number", "0.5", 0, 8, "Curl advection of the noise lookup, in periods: 0 = plain Perlin, more = stretched fibres.",
        [m](Preset& p, const json& j, const Index&) { m(p).warp = j.get<double>(); });
    add(base + "/wind", "vec3", "[1, 0, 0]", -big, big, "Direction the wind blows to (world axes, y up; need not be unit length).",
        [m](Preset& p, const json& j, const Index&) {
          m(p).wind = ShapeVec{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
        });
    add(base + "/downwind", "number", "0.5", 0, 1, "0 = wisps all round; 1 = only where the surface faces downwind.",
        [m](Preset& p, const json& j, const Index&) { m(p).downwind = j.get<double>(); });
  }
}

std::vector<Spec> build_table() {
  std::vector<Spec> t;
  // The group of the rows added next (param_group.h): set before each run of rows.
  ParamPlace place;
  auto in = [&](ParamGroup g, bool advanced = false) { place = {g, advanced}; };
  auto add = [&](std::string ptr, std::string type, std::string def, double lo, double hi, std::string doc,
                 std::function<void(Preset&, const json&, const Index&)> set, std::vector<std::string> choices = {}) {
    Spec s;
    s.field.name = std::move(ptr);
    s.field.type = std::move(type);
    s.field.default_value = std::move(def);
    s.field.doc = std::move(doc);
    s.field.lo = lo, s.field.hi = hi;
    s.field.choices = std::move(choices);
    s.field.nullable = s.field.default_value == "null";  // every such setter reads null as unset
    s.set = std::move(set);
    s.place = place;
    t.push_back(std::move(s));
  };
  auto v3 = [](const json& j) { return std::array<double, 3>{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; };
  const double big = 1e9;

  in(ParamGroup::Output);
  add("/name", "string", "\"untitled\"", 0, 0, "Preset name, stored in the VDB metadata.",
      [](Preset& p, const json& j, const Index&) { p.name = j.get<std::string>(); });
  add("/description", "string", "\"\"", 0, 0, "One line shown by `cloudgen presets`.",
      [](Preset& p, const json& j, const Index&) { p.description = j.get<std::string>(); });
  in(ParamGroup::Shape);
  add("/seed", "integer", "1", 0, double(kMaxSeed), "Master seed; every noise channel derives its own.",
      [](Preset& p, const json& j, const Index&) { p.seed = j.get<uint64_t>(); });
  in(ParamGroup::Quality);
  add("/resolution", "ivec3", "[128, 128, 128]", 1, kMaxResolution, "Voxels along x, y (up), z.",
      [](Preset& p, const json& j, const Index&) {
        for (int a = 0; a < 3; ++a) p.resolution[a] = j[a].get<uint32_t>();
      });
  in(ParamGroup::Shape);
  add("/voxel_size", "number", "10.0", 1e-6, big, "Edge of one voxel in metres.",
      [](Preset& p, const json& j, const Index&) { p.voxel_size = j.get<double>(); });
  add("/origin", "vec3", "[0, 0, 0]", -big, big, "World position (metres) of the volume's min corner.",
      [=](Preset& p, const json& j, const Index&) { p.origin = v3(j); });
  in(ParamGroup::Shape, true);
  add("/tiling", "bool", "true", 0, 0,
      "The volume wraps seamlessly in x and z (noise periods fit the volume; towers stay off the edges).",
      [](Preset& p, const json& j, const Index&) { p.tiling = j.get<bool>(); });

  for (int c = 0; c < 4; ++c) {
    const std::string base = std::string("/channels/") + kChannelNames[c];
    const bool r = c == 0;
    const std::string what = r ? "base shape (R)" : std::string("detail channel ") + char(toupper(kChannelNames[c][0]));
    in(r ? ParamGroup::Shape : ParamGroup::Detail);
    add(base + "/enabled", "bool", r ? "true" : "false", 0, 0, "Generate the " + what + ".",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].enabled = j.get<bool>(); });
    add(base + "/kind", "string", r ? "\"perlin-worley\"" : "\"worley\"", 0, 0, "Noise of the " + what + ".",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].kind = noise3d::parse_kind(j.get<std::string>()); },
        {"perlin", "worley", "perlin-worley"});
    add(base + "/period", "period", r ? "4" : std::to_string(4 << c), 1, 65536,
        "Base-octave period in lattice cells across the volume's x extent: one integer (y and z follow "
        "the aspect ratio) or [x, y, z].",
        [c](Preset& p, const json& j, const Index&) {
          if (j.is_array())
            for (int a = 0; a < 3; ++a) p.channels[c].period[a] = j[a].get<uint32_t>();
          else
            p.channels[c].period = {j.get<uint32_t>(), 0, 0};
        });
    add(base + "/octaves", "integer", r ? "4" : "3", 1, noise3d::kMaxOctaves, "fBm octaves.",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].octaves = j.get<int>(); });
    add(base + "/gain", "number", "0.5", 1e-6, 1, "Amplitude ratio between octaves.",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].gain = j.get<double>(); });
    in(r ? ParamGroup::Shape : ParamGroup::Detail, true);
    add(base + "/lacunarity", "integer", "2", 2, noise3d::kMaxLacunarity,
        "Frequency ratio between octaves (an integer, so every octave still tiles).",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].lacunarity = j.get<int>(); });
    add(base + "/worley_octaves", "integer", "0", 0, noise3d::kMaxOctaves,
        "Perlin-Worley: octaves of the Worley part (0 = same as octaves).",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].worley_octaves = j.get<int>(); });
    in(r ? ParamGroup::Shape : ParamGroup::Detail);
    add(base + "/blend", "number", "1.0", 0, 1,
        "Perlin-Worley: how much Worley dilates the Perlin fBm (1 = full Perlin-Worley, 0 = Perlin alone).",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].blend = j.get<double>(); });
    add(base + "/remap", "vec2", "[0, 1]", -1, 2,
        "Contrast: [lo, hi] of the noise mapped to [0, 1] (clamped), before invert. fBm values crowd "
        "the middle of their range, e.g. Perlin-Worley has 80% of its values in [0.80, 0.90].",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].remap = {j[0].get<double>(), j[1].get<double>()}; });
    add(base + "/invert", "bool", "false", 0, 0, "Store 1 - noise.",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].invert = j.get<bool>(); });
    in(r ? ParamGroup::Shape : ParamGroup::Detail, true);
    add(base + "/seed_offset", "integer", std::to_string(c), 0, double(kMaxSeed),
        "Added to the master seed for this channel.",
        [c](Preset& p, const json& j, const Index&) { p.channels[c].seed_offset = j.get<uint64_t>(); });
  }

  in(ParamGroup::Shape);
  add("/height/profile", "string", "\"exponential\"", 0, 0,
      "Vertical profile: the thesis's HD(h) = (1 - exp(-a h)) exp(-b h), or a cloud-type gradient.",
      [](Preset& p, const json& j, const Index&) {
        for (HeightProfile h : kHeightProfiles)
          if (j.get<std::string>() == height_profile_name(h)) p.height_profile = h;
      },
      names_of(kHeightProfiles, height_profile_name));
  add("/height/a", "number", "50", 0.01, 1000, "HD sharpness of the flat bottom.",
      [](Preset& p, const json& j, const Index&) { p.height_a = j.get<double>(); });
  add("/height/b", "number", "4", 0, 1000, "HD falloff towards the top.",
      [](Preset& p, const json& j, const Index&) { p.height_b = j.get<double>(); });
  add("/height/normalize", "bool", "true", 0, 0, "Scale the profile so its peak is 1.",
      [](Preset& p, const json& j, const Index&) { p.height_normalize = j.get<bool>(); });

  add("/towers/list", "array", "[]", 0, 0, "Explicit Gaussian towers (multivariate-normal peaks added to the profile).",
      [](Preset& p, const json& j, const Index&) { p.towers.resize(j.size()); });
  add("/towers/list/*/center", "vec3", "[0.5, 0.2, 0.5]", 0, 1, "Tower centre in normalised volume coordinates.",
      [=](Preset& p, const json& j, const Index& i) { p.towers[i[0]].center = v3(j); });
  add("/towers/list/*/sigma", "vec3", "[0.1, 0.3, 0.1]", 1e-3, 10, "Standard deviations (normalised).",
      [=](Preset& p, const json& j, const Index& i) { p.towers[i[0]].sigma = v3(j); });
  add("/towers/list/*/amplitude", "number", "0.5", -10, 10, "Peak added to the height profile.",
      [](Preset& p, const json& j, const Index& i) { p.towers[i[0]].amplitude = j.get<double>(); });
  add("/towers/count", "integer", "0", 0, 256, "Extra towers at random positions (from towers.seed).",
      [](Preset& p, const json& j, const Index&) { p.tower_count = j.get<int>(); });
  add("/towers/seed", "integer", "7", 0, double(kMaxSeed), "Seed of the random towers.",
      [](Preset& p, const json& j, const Index&) { p.tower_seed = j.get<uint64_t>(); });
  add("/towers/amplitude", "number", "0.6", -10, 10, "Peak of each random tower.",
      [](Preset& p, const json& j, const Index&) { p.tower_amplitude = j.get<double>(); });
  add("/towers/sigma", "vec3", "[0.08, 0.35, 0.08]", 1e-3, 10, "Sigmas of the random towers.",
      [=](Preset& p, const json& j, const Index&) { p.tower_sigma = v3(j); });

  add("/coverage/enabled", "bool", "false", 0, 0, "Multiply by a 2D coverage map over x, z (weather map).",
      [](Preset& p, const json& j, const Index&) { p.coverage_enabled = j.get<bool>(); });
  add("/coverage/kind", "string", "\"perlin\"", 0, 0,
      "Noise of the coverage map, or \"image\": a painted weather map read from coverage.file (docs/shaping.md).",
      [](Preset& p, const json& j, const Index&) {
        p.coverage_image = j.get<std::string>() == "image";
        if (!p.coverage_image) p.coverage_kind = noise3d::parse_kind(j.get<std::string>());
      },
      {"perlin", "worley", "perlin-worley", "image"});
  add("/coverage/file", "string", "\"\"", 0, 0,
      "Weather map PNG for coverage.kind \"image\" (8/16-bit grey, RGB or RGBA, at most " +
          std::to_string(kWeatherMapMaxSide) + " a side), relative to the preset's folder (to the current folder with "
          "--set): R = coverage, G = cloud type (0 stratus, 0.5 cumulus, 1 cumulonimbus), B = cloud-top height / volume "
          "height; grey = coverage only. Over the x-z extent, bilinear, wrapping when tiling. `cloudgen weather-map` "
          "writes one to paint over.",
      [](Preset& p, const json& j, const Index&) { p.coverage_file = j.get<std::string>(); });
  add("/coverage/period", "integer", "2", 1, 65536, "Coverage noise period across the x extent.",
      [](Preset& p, const json& j, const Index&) { p.coverage_period = j.get<uint32_t>(); });
  add("/coverage/octaves", "integer", "3", 1, noise3d::kMaxOctaves, "Coverage fBm octaves.",
      [](Preset& p, const json& j, const Index&) { p.coverage_octaves = j.get<int>(); });
  add("/coverage/low", "number", "0.35", 0, 1, "Coverage noise value (in [0,1]) below which there is no cloud.",
      [](Preset& p, const json& j, const Index&) { p.coverage_low = j.get<double>(); });
  add("/coverage/high", "number", "0.65", 0, 1, "Coverage noise value above which coverage is full.",
      [](Preset& p, const json& j, const Index&) { p.coverage_high = j.get<double>(); });

  add_shape_keys(add, big);
  in(ParamGroup::Detail);
  add_modifier_keys(add, big);

  in(ParamGroup::Shape);
  add("/threshold", "number", "0.3", 0, 0.999, "Cut-off remap clamp((d - t) / (1 - t), 0, 1).",
      [](Preset& p, const json& j, const Index&) { p.threshold = j.get<double>(); });
  add("/density_scale", "number", "1.0", 0, 1000, "Multiplier after the threshold (result clamped to [0, 1]).",
      [](Preset& p, const json& j, const Index&) { p.density_scale = j.get<double>(); });

  in(ParamGroup::Quality, true);
  add("/occupancy/cell", "integer", "4", 1, 256, "Coarse occupancy cell edge in voxels.",
      [](Preset& p, const json& j, const Index&) { p.occupancy_cell = j.get<uint32_t>(); });
  add("/occupancy/padding", "integer", "2", 0, 16,
      "Dilation in coarse cells (2 = the thesis's double padding, so a large step can't cut a corner).",
      [](Preset& p, const json& j, const Index&) { p.occupancy_padding = j.get<uint32_t>(); });

  in(ParamGroup::Output);
  add("/export/vdb/half", "bool", "false", 0, 0, "Store VDB grids as half floats.",
      [](Preset& p, const json& j, const Index&) { p.export_options.vdb_half = j.get<bool>(); });
  add("/export/vdb/lod", "integer", "0", 0, kMaxLodLevels,
      "Levels of detail in .vdb outputs: grids density_level_1 .. density_level_N (and each detail grid's "
      "NAME_level_N) beside the full-resolution grids (OpenVDB's vdb_lod naming), each with voxels twice as large "
      "as the one before, averaged so every level holds the same total density (OpenVDB's MultiResGrid full "
      "weighting). 0 = none; at most the levels until the grid is one voxel along its longest axis.",
      [](Preset& p, const json& j, const Index&) { p.export_options.vdb_lod = j.get<uint32_t>(); });
  add("/export/vdb/compression", "string", "\"blosc\"", 0, 0, "VDB compression.",
      [](Preset& p, const json& j, const Index&) {
        p.export_options.vdb_compression = parse_vdb_compression(j.get<std::string>());
      },
      names_of(kCompressions, vdb_compression_name));
  add("/export/vdb/detail", "bool", "true", 0, 0, "Write the enabled detail channels as extra grids.",
      [](Preset& p, const json& j, const Index&) { p.export_options.vdb_detail = j.get<bool>(); });
  add("/export/vdb/up", "string", "\"z\"", 0, 0,
      "Up axis of the VDB's world: z puts the cloud's height on +z by a rotation in the grid transform "
      "(Blender), y keeps the height on +y (Houdini, Maya). The voxel data is the same.",
      [](Preset& p, const json& j, const Index&) { p.export_options.vdb_up = j.get<std::string>()[0]; }, {"z", "y"});
  add("/export/vdb/units", "string", "\"normalized\"", 0, 0,
      "normalized: density in [0, 1] (metadata extinction_per_metre gives the scale); physical: the density "
      "grid holds extinction per metre (Principled Volume Density 1).",
      [](Preset& p, const json& j, const Index&) { p.export_options.vdb_physical = j.get<std::string>() == "physical"; },
      {"normalized", "physical"});
  in(ParamGroup::Output, true);
  add("/export/vdb/bake_erosion", "bool", "true", 0, 0,
      "Apply the viewer's erosion (view.render.erosion, 0.35 by default) to density in the VDB and write no "
      "detail grids: a file about the size of its density grid that renders eroded in tools that read density "
      "only (Blender's Principled Volume: the default, Blender being the main target). The erosion can then no "
      "longer be changed at render time; false keeps the detail grids (on the density's topology dilated by one "
      "voxel) for the viewer's live erosion and for Houdini.",
      [](Preset& p, const json& j, const Index&) { p.export_options.vdb_bake_erosion = j.get<bool>(); });
  add("/export/nvdb/precision", "string", "\"float\"", 0, 0,
      "Value type of .nvdb grids: float (32 bits a voxel), or NanoVDB's quantised leaves, each 8^3 leaf storing "
      "min + code * (max - min) / (2^bits - 1): fp16 (16 bits, error at most (max - min) / 131070 of the leaf), "
      "fp8 (range / 510), fp4 (range / 30), fpn (per leaf the fewest of 1-16 bits within export.nvdb.tolerance). "
      "Readers decode to float; the .vdb export is unaffected (export.vdb.half). Sizes and render errors: "
      "docs/nanovdb.md.",
      [](Preset& p, const json& j, const Index&) {
        p.export_options.nvdb_precision = parse_nvdb_precision(j.get<std::string>());
      },
      names_of(kPrecisions, nvdb_precision_name));
  add("/export/nvdb/tolerance", "number", "0.01", 1e-6, 1000,
      "Largest absolute error of a voxel with export.nvdb.precision = fpn, in the density grid's units "
      "(normalised, or extinction per metre with export.vdb.units = physical); a leaf that 16 bits cannot keep "
      "within it gets 16 bits. Other precisions ignore it.",
      [](Preset& p, const json& j, const Index&) { p.export_options.nvdb_tolerance = j.get<double>(); });
  in(ParamGroup::Output);
  add("/export/raw/format", "string", "\"rgba8\"", 0, 0, "Texel format of raw/KTX2 textures.",
      [](Preset& p, const json& j, const Index&) { p.export_options.texel = parse_texel(j.get<std::string>()); },
      names_of(kTexels, texel_name));

  // The optional `view`: unset keys (null) leave the viewer's defaults.
  in(ParamGroup::Camera);
  add("/view/eye", "vec3", "null", -big, big, "Camera position, world metres (unset: the viewer's default framing).",
      [=](Preset& p, const json& j, const Index&) { set_optional(p.view.eye, j); });
  add("/view/target", "vec3", "null", -big, big, "Point the camera looks at, world metres (unset: the volume's centre).",
      [=](Preset& p, const json& j, const Index&) { set_optional(p.view.target, j); });
  add("/view/fov", "number", "null", 1, 170, "Vertical field of view, degrees (unset: 60).",
      [=](Preset& p, const json& j, const Index&) { set_optional(p.view.fov, j); });
  in(ParamGroup::LightAndSky);
  add("/view/sun/azimuth", "number", "null", -360, 360,
      "Sun azimuth, degrees clockwise from -z toward +x (unset: behind the camera).",
      [=](Preset& p, const json& j, const Index&) { set_optional(p.view.sun_azimuth, j); });
  add("/view/sun/elevation", "number", "null", -90, 90, "Sun elevation, degrees (unset: 35).",
      [=](Preset& p, const json& j, const Index&) { set_optional(p.view.sun_elevation, j); });
  in(ParamGroup::Output, true);
  add("/view/render", "object", "{}", 0, 0,
      "cloudviewer render settings for this preset, {\"KEY\": value} as in `cloudviewer --help-params` "
      "(e.g. {\"sigma_t\": 0.02, \"g\": 0.5}); keys and values are checked against the viewer's table when the "
      "preset is read, command-line flags override.",
      [](Preset& p, const json& j, const Index&) {
        p.view.render.clear();
        for (auto& [k, val] : j.items()) p.view.render.push_back({k, val.is_string() ? val.get<std::string>() : val.dump()});
      });
  // The `motion` section, from motion.h's one table (the viewer's --set motion.KEY reads it too).
  in(ParamGroup::Animation);
  const MotionParams motion_defaults;
  for (const MotionKey& k : motion_keys()) {
    double MotionParams::*member = k.member;
    add("/motion/" + k.key, "number", fmt(motion_defaults.*member), k.lo, k.hi,
        (k.unit.empty() ? "" : "(" + k.unit + ") ") + k.doc + "; used by `--frames` sequences (docs/motion.md).",
        [member](Preset& p, const json& j, const Index&) { p.motion.*member = j.get<double>(); });
  }
  add("/motion/flow_map", "string", "\"procedural\"", 0, 0,
      "The flow map: \"procedural\" (the curl of a three-wave stream function) or a PNG file, relative to the "
      "preset's folder (relative to the current folder when given with --set); x = flow phase (wraps), y = height "
      "(top row = top of the layer), R = up and G = forward as value * 2 - 1. `cloudgen flowmap` writes the "
      "procedural one to paint over (docs/motion.md).",
      [](Preset& p, const json& j, const Index&) { p.motion_flow_map = j.get<std::string>(); });
  return t;
}

const std::vector<Spec>& table() {
  static const std::vector<Spec> t = build_table();
  return t;
}

const Schema& schema() {
  static const Schema sc = [] {
    std::vector<FieldSpec> f;
    for (const Spec& s : table()) f.push_back(s.field);
    return Schema(std::move(f));
  }();
  return sc;
}

/// Walks a preset document through the table's schema, collecting every problem as
/// "<file>: <pointer>: <what>" and setting each valid key.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  void walk(Preset& p, const json& doc) {
    const Schema& sc = schema();
    sc.walk(
        doc, [&](const std::string& ptr, const std::string& what) { problem(ptr, what); },
        [&](const FieldSpec& f, const json& v, const std::string&, const Index& idx) {
          table()[size_t(&f - sc.fields().data())].set(p, v, idx);
        });
  }

  void problem(const std::string& ptr, const std::string& what) { problems_.push_back(source_ + ": " + ptr + ": " + what); }
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::string source_;
  std::vector<std::string> problems_;
};

// "a.b.c=value" -> sets /a/b/c in the document (value parsed as JSON, else a string).
void apply_override(json& doc, const std::string& ov, Reader& r) {
  auto eq = ov.find('=');
  if (eq == std::string::npos || eq == 0) {
    r.problem("--set " + ov, "expected key.path=value");
    return;
  }
  std::string key = ov.substr(0, eq), val = ov.substr(eq + 1);
  std::string ptr;
  for (size_t s = 0, e; s <= key.size(); s = e + 1) {
    e = key.find('.', s);
    if (e == std::string::npos) e = key.size();
    ptr += "/" + key.substr(s, e - s);
  }
  json v = json::parse(val, nullptr, false);
  if (v.is_discarded()) {
    v = val;  // not JSON: taken as a string
  } else {
    try {
      v = parse_json_checked(val, "--set " + key);  // bounded depth, no duplicate keys
    } catch (const InputError& e) {
      r.problem("--set " + key, e.what());
      return;
    }
  }
  // List indices may address an existing element or append one: "towers.list.99999999999=1"
  // would otherwise make the JSON library allocate a list of 1e11 elements (found by fuzzing).
  const json* node = &doc;
  for (size_t st = 1, en; st <= ptr.size(); st = en + 1) {
    en = ptr.find('/', st);
    if (en == std::string::npos) en = ptr.size();
    const std::string tok = ptr.substr(st, en - st);
    const bool digits = !tok.empty() && tok.find_first_not_of("0123456789") == std::string::npos;
    const bool numeric = digits && tok.size() <= 9;
    if (node && node->is_array()) {
      const size_t n = node->size();
      if (!numeric || std::stoul(tok) > n) {
        r.problem("--set " + printable(key), "\"" + printable(tok) + "\" is not an index of a list of " + std::to_string(n) +
                                                 " (use 0.." + std::to_string(n) + "; " + std::to_string(n) + " adds one)");
        return;
      }
      node = std::stoul(tok) < n ? &(*node)[std::stoul(tok)] : nullptr;
    } else if (node && node->is_object()) {
      node = node->contains(tok) ? &(*node)[tok] : nullptr;
    } else if (!node && digits && tok != "0") {  // a new list: only element 0 can be created
      r.problem("--set " + printable(key), "list index " + tok + " is beyond the end of a new list (use 0)");
      return;
    } else {
      node = nullptr;
    }
  }
  try {
    doc[json::json_pointer(ptr)] = v;
  } catch (const json::exception& e) {
    r.problem("--set " + printable(ov), printable(e.what()));
  }
}

/// Each source has its kind's keys; in a tiling volume the shape must be 0 at the tile's x and z
/// faces (shapes do not wrap), as towers must.
void shape_checks(const Preset& p, Reader& r) {
  const auto problems = shape_problems(p.shape);
  for (const auto& [ptr, what] : problems) r.problem(ptr, what);
  if (!problems.empty() || p.shape.sources.empty() || !p.tiling) return;
  if (const auto q = ShapeField(p.shape, p.voxel_size, p.seed).nonzero_at_side_faces(p.origin, p.resolution, p.voxel_size))
    r.problem("/shape/sources", "with /tiling true the shape must be 0 on the voxels of the x and z faces (the volume wraps "
                                "there, shapes do not), but the voxel at (" + fmt((*q)[0]) + ", " + fmt((*q)[1]) + ", " +
                                    fmt((*q)[2]) + ") m has s > 0: move the sources inward or set \"tiling\": false");
}

void cross_checks(const Preset& p, Reader& r) {
  if (p.coverage_low >= p.coverage_high)
    r.problem("/coverage/high", fmt(p.coverage_high) + " must be greater than /coverage/low (" + fmt(p.coverage_low) + ")");
  if (!p.channels[0].enabled) r.problem("/channels/r/enabled", "the base shape channel R must be enabled");
  for (int c = 0; c < 4; ++c)
    if (!(p.channels[c].remap[0] < p.channels[c].remap[1]))
      r.problem(std::string("/channels/") + kChannelNames[c] + "/remap",
                "lo must be below hi, got [" + fmt(p.channels[c].remap[0]) + ", " + fmt(p.channels[c].remap[1]) + "]");
  for (int c = 0; c < 4; ++c) {
    if (!p.channels[c].enabled) continue;
    try {
      noise3d::validate(channel_params(p, c));
    } catch (const noise3d::InvalidParameter& e) {
      r.problem(std::string("/channels/") + kChannelNames[c], e.what());
    }
  }
  if (p.tiling)
    for (size_t i = 0; i < p.towers.size(); ++i) {
      const Tower& t = p.towers[i];
      for (int a : {0, 2})
        if (t.center[a] - 3 * t.sigma[a] < 0 || t.center[a] + 3 * t.sigma[a] > 1)
          r.problem("/towers/list/" + std::to_string(i),
                    std::string("centre ") + (a ? "z" : "x") + " +- 3 sigma = [" + fmt(t.center[a] - 3 * t.sigma[a]) +
                        ", " + fmt(t.center[a] + 3 * t.sigma[a]) +
                        "] must lie inside [0, 1] so the tower is zero at the tile edges and the volume still wraps");
    }
  shape_checks(p, r);
  if (p.tower_count > 0 && p.tiling)
    for (int a : {0, 2})
      if (6 * p.tower_sigma[a] >= 1)
        r.problem("/towers/sigma", "6 * sigma must be below 1 on x and z so random towers fit inside the tile");
}

/// The meshes of mesh sources, read (a file named in the preset is found next to it; one given with
/// --set, from the current folder), then the fitted ones placed (shape.h fit_sources). A source
/// without its keys is left to shape_checks.
void load_meshes(Preset& p, const std::string& source, const std::vector<std::string>& overrides, Reader& r) {
  for (size_t i = 0; i < p.shape.sources.size(); ++i) {
    ShapeSource& s = p.shape.sources[i];
    if ((s.kind != ShapeKind::Mesh && s.kind != ShapeKind::Vdb) || !s.file) continue;
    const std::string ptr = "/shape/sources/" + std::to_string(i) + "/file";
    const std::string key = "shape.sources." + std::to_string(i);
    const bool from_set = std::any_of(overrides.begin(), overrides.end(), [&](const std::string& ov) {
      for (const std::string& k : {key + ".file=", key + "=", std::string("shape.sources="), std::string("shape=")})
        if (ov.rfind(k, 0) == 0) return true;
      return false;
    });
    std::filesystem::path file = *s.file;
    if (file.empty()) {
      r.problem(ptr, s.kind == ShapeKind::Vdb ? "empty; give a .vdb file" : "empty; give a mesh file (OBJ, PLY, STL, glTF/GLB)");
      continue;
    }
    if (!from_set && file.is_relative()) file = (std::filesystem::path(source).parent_path() / file).lexically_normal();
    try {
      if (s.kind == ShapeKind::Vdb) {
        const char up = s.up ? (*s.up)[0] : 0;
        s.vdb = std::make_shared<const VdbShape>(
            read_vdb_shape(file.string(), s.grid.value_or(""), s.iso.value_or(0.5), up, printable(file.string())));
        continue;
      }
      s.mesh = std::make_shared<const TriangleMesh>(read_mesh(file.string(), printable(file.string())));
      if (s.mesh->open_edges > 0)
        std::fprintf(stderr, "warning: %s: %s is not closed (%zu edges with one triangle): it has no inside, so it "
                             "becomes a sheet of cloud along its surface (unsigned distance)\n",
                     ptr.c_str(), printable(file.string()).c_str(), s.mesh->open_edges);
    } catch (const InputError& e) {
      r.problem(ptr, e.what());
    }
  }
  if (r.problems().empty()) fit_sources(p.shape, p.origin, p.resolution, p.voxel_size);
}

/// coverage.kind "image": needs coverage.enabled and coverage.file, read like motion.flow_map (a
/// file named in the preset is found next to it; one given with --set, from the current folder).
void load_weather_image(Preset& p, const std::string& source, const std::vector<std::string>& overrides, Reader& r) {
  if (!p.coverage_image) return;
  if (!p.coverage_enabled) {
    r.problem("/coverage/enabled", "coverage.kind \"image\" needs coverage.enabled true");
    return;
  }
  if (p.coverage_file.empty()) {
    r.problem("/coverage/file", "coverage.kind \"image\" needs a PNG file here (8/16-bit grey, RGB or RGBA)");
    return;
  }
  const bool from_set = std::any_of(overrides.begin(), overrides.end(), [](const std::string& ov) {
    return ov.rfind("coverage.file=", 0) == 0;
  });
  std::filesystem::path file = p.coverage_file;
  if (!from_set && file.is_relative()) file = std::filesystem::path(source).parent_path() / file;
  try {
    p.weather_map = load_weather_map(file.string());
  } catch (const InputError& e) {
    r.problem("/coverage/file", e.what());
  }
}

}  // namespace

const char* height_profile_name(HeightProfile h) {
  switch (h) {
    case HeightProfile::Exponential: return "exponential";
    case HeightProfile::Stratus: return "stratus";
    case HeightProfile::Cumulus: return "cumulus";
    case HeightProfile::Cumulonimbus: return "cumulonimbus";
  }
  return "?";
}

Preset::Preset() {
  for (const Spec& s : table())
    if (s.field.name.find('*') == std::string::npos) s.set(*this, json::parse(s.field.default_value), {});
}

const std::vector<ParamInfo>& params() {
  static const std::vector<ParamInfo> infos = [] {
    std::vector<ParamInfo> v;
    for (const Spec& s : table())
      v.push_back({s.field.name, s.field.type, s.field.default_value, s.field.range(), s.field.doc});
    return v;
  }();
  return infos;
}

ParamPlace preset_param_place(const std::string& pointer) {
  for (const Spec& s : table())
    if (s.field.name == pointer) return s.place;
  return {};
}

std::string params_markdown() {
  // One table per group (param_group.h), in the panel's order; the engineering switches of a group
  // in a table of their own under it.
  std::ostringstream o;
  auto cell = [](std::string t) {  // a '|' inside a cell would end it
    for (size_t k = 0; (k = t.find('|', k)) != std::string::npos; k += 2) t.replace(k, 1, "\\|");
    return t;
  };
  for (ParamGroup g : kParamGroups)
    for (bool advanced : {false, true}) {
      std::ostringstream rows;
      for (const Spec& s : table()) {
        if (s.place.group != g || s.place.advanced != advanced) continue;
        std::string key = s.field.name.substr(1);
        std::replace(key.begin(), key.end(), '/', '.');
        rows << "| `" << key << "` | " << s.field.type << " | `" << s.field.default_value << "` | "
             << cell(s.field.range()) << " | " << cell(s.field.doc) << " |\n";
      }
      if (rows.str().empty()) continue;
      o << (advanced ? "### " : "## ") << param_group_name(g) << (advanced ? ": advanced" : "") << "\n\n"
        << "| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n" << rows.str() << "\n";
    }
  return o.str();
}

Preset parse_preset(const std::string& text, const std::string& source, const std::vector<std::string>& overrides) {
  Reader r(source);
  json doc = parse_json_checked(text, source);
  if (!doc.is_object()) throw InputError(source + ": the preset must be a JSON object");
  for (const std::string& ov : overrides) apply_override(doc, ov, r);
  Preset p;  // the table's defaults
  p.source_path = source;
  r.walk(p, doc);
  // view.render is the viewer's to apply, so it is checked with the viewer's own table (one table,
  // cloudviewer_params): a value the viewer would refuse is refused here, before any file is written.
  for (const auto& [key, value] : p.view.render)
    if (const std::string why = cloudviewer::view_render_problem(key, value); !why.empty())
      r.problem("/view/render/" + key, value + " is refused by cloudviewer's table: " + why);
  if (r.problems().empty() && p.motion_flow_map != "procedural") {
    // A file named in the preset is found next to it; one given with --set, from where the user is.
    const bool from_set = std::any_of(overrides.begin(), overrides.end(), [](const std::string& ov) {
      return ov.rfind("motion.flow_map=", 0) == 0;
    });
    std::filesystem::path file = p.motion_flow_map;
    if (!from_set && file.is_relative()) file = std::filesystem::path(source).parent_path() / file;
    try {
      p.motion.flow_map = load_flow_map(file.string());
    } catch (const InputError& e) {
      r.problem("/motion/flow_map", e.what());
    }
  }
  if (r.problems().empty()) load_weather_image(p, source, overrides, r);
  if (r.problems().empty()) load_meshes(p, source, overrides, r);
  if (r.problems().empty()) cross_checks(p, r);
  if (!r.problems().empty()) {
    std::string all;
    for (const auto& m : r.problems()) all += (all.empty() ? "" : "\n") + m;
    throw InputError(all);
  }
  return p;
}

std::string edited_preset_text(const std::string& path, const std::vector<std::string>& sets, const std::string& to) {
  namespace fs = std::filesystem;
  Reader r(path);
  json doc = parse_json_checked(read_text_input(path, "the input preset " + printable(path), path), path);
  if (!doc.is_object()) throw InputError(path + ": the preset must be a JSON object");
  for (const std::string& ov : sets) apply_override(doc, ov, r);
  if (!r.problems().empty()) {
    std::string all;
    for (const auto& m : r.problems()) all += (all.empty() ? "" : "\n") + m;
    throw InputError(all);
  }
  // A file named relative to the preset's folder (from a set: to the current folder) is named
  // relative to the new file's folder, so the saved preset finds it.
  std::vector<std::string> file_keys = {"/coverage/file", "/motion/flow_map"};
  const json::json_pointer sources_at("/shape/sources");
  if (doc.contains(sources_at) && doc[sources_at].is_array())
    for (size_t i = 0; i < doc[sources_at].size(); ++i) file_keys.push_back("/shape/sources/" + std::to_string(i) + "/file");
  for (const std::string& ptr : file_keys) {
    const json::json_pointer at(ptr);
    if (!doc.contains(at) || !doc[at].is_string()) continue;
    const std::string name = doc[at].get<std::string>();
    if (name.empty() || name == "procedural" || fs::path(name).is_absolute()) continue;
    std::string key = ptr.substr(1);
    std::replace(key.begin(), key.end(), '/', '.');
    // A mesh's file came from --set also when its source or the list was set whole.
    const std::string source_key = key.substr(0, key.rfind('.'));
    const bool from_set = std::any_of(sets.begin(), sets.end(), [&](const std::string& s) {
      if (s.rfind(key + "=", 0) == 0) return true;
      if (ptr.rfind("/shape/sources/", 0) != 0) return false;
      for (const std::string& k : {source_key + "=", std::string("shape.sources="), std::string("shape=")})
        if (s.rfind(k, 0) == 0) return true;
      return false;
    });
    const fs::path base = from_set ? fs::current_path() : fs::absolute(path).parent_path();
    const fs::path file = (base / name).lexically_normal();
    const fs::path rel = file.lexically_relative(fs::absolute(to).parent_path());
    doc[at] = (rel.empty() ? file : rel).generic_string();
  }
  std::string text = doc.dump(2) + "\n";
  parse_preset(text, to);  // what is saved reads back as a valid preset where it goes
  return text;
}

std::string list_element_key(const std::string& key, size_t i) {
  const size_t star = key.find(".*.");
  if (star == std::string::npos) return key;
  return key.substr(0, star) + "." + std::to_string(i) + key.substr(star + 2);
}

const std::vector<PresetField>& preset_fields() {
  static const std::vector<PresetField> fields = [] {
    std::vector<PresetField> v;
    for (const Spec& s : table()) {
      PresetField f;
      f.pointer = s.field.name;
      f.key = f.pointer.substr(1);
      std::replace(f.key.begin(), f.key.end(), '/', '.');
      f.type = s.field.type;
      f.default_value = s.field.default_value;
      f.lo = s.field.lo, f.hi = s.field.hi;
      f.choices = s.field.choices;
      f.range = s.field.range();
      f.doc = s.field.doc;
      f.place = s.place;
      v.push_back(std::move(f));
    }
    return v;
  }();
  return fields;
}

std::map<std::string, std::string> preset_values(const std::string& path, const std::vector<std::string>& sets) {
  const json doc = json::parse(edited_preset_text(path, sets, path));
  std::map<std::string, std::string> out;
  for (const PresetField& f : preset_fields()) {
    const size_t star = f.pointer.find("/*/");
    if (star == std::string::npos) {
      if (f.pointer.find('*') != std::string::npos) continue;  // (no other list form in the table)
      const json::json_pointer at(f.pointer);
      out[f.key] = doc.contains(at) ? doc[at].dump() : f.default_value;
      continue;
    }
    // A list element's key, once per element the preset has: "shape.sources.1.radius".
    const json::json_pointer list(f.pointer.substr(0, star));
    const std::string rest = f.pointer.substr(star + 2);  // "/radius"
    if (rest.find('*') != std::string::npos || !doc.contains(list) || !doc[list].is_array()) continue;
    for (size_t i = 0; i < doc[list].size(); ++i) {
      const json::json_pointer at(list.to_string() + "/" + std::to_string(i) + rest);
      out[list_element_key(f.key, i)] = doc.contains(at) ? doc[at].dump() : f.default_value;
    }
  }
  return out;
}

Preset load_preset(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_preset(read_text_input(path, "the input preset " + printable(path), path), path, overrides);
}

std::vector<std::string> check_preset(const std::string& path, const std::vector<std::string>& overrides) {
  try {
    load_preset(path, overrides);
    return {};
  } catch (const InputError& e) {
    std::vector<std::string> out;
    std::stringstream ss(e.what());
    for (std::string line; std::getline(ss, line);) out.push_back(line);
    return out;
  }
}

void rescale(Preset& p, uint32_t n) {
  // The preset table's own range of /resolution, so no estimate downstream can overflow.
  if (n < 1 || n > kMaxResolution)
    throw InputError("--resolution: " + std::to_string(n) + " is out of range [1, " + std::to_string(kMaxResolution) +
                     "] (the range of /resolution)");
  const uint32_t longest = *std::max_element(p.resolution.begin(), p.resolution.end());
  const double f = double(n) / longest;
  for (auto& r : p.resolution) r = std::max<uint32_t>(1, uint32_t(std::lround(r * f)));
  p.voxel_size /= f;
}

}  // namespace cloudgen
