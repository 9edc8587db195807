#include "cloudviewer/controls.h"
#include "cloudviewer/render_check.h"
#include "cloudviewer/settings.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cloudviewer/errors.h"
#include "scene/param_parse.h"

namespace cloudviewer {
namespace {

using param::fmt;
[[noreturn]] void bad(const std::string& key, const std::string& value, const std::string& allowed) {
  param::bad("render", key, value, allowed);
}
double parse_double(const std::string& key, const std::string& v, double lo, double hi) {
  return param::parse_number("render", key, v, lo, hi);
}

ParamDef boolean(const std::string& key, bool RenderSettings::*m, const std::string& doc) {
  return param::boolean<RenderSettings>("render", key, param::member(m), doc);
}
ParamDef real(const std::string& key, double RenderSettings::*m, double lo, double hi, const std::string& doc) {
  return param::real<RenderSettings>("render", key, param::member(m), lo, hi, doc);
}
ParamDef integer(const std::string& key, int RenderSettings::*m, int lo, int hi, const std::string& doc) {
  return param::integer<RenderSettings>("render", key, param::member(m), lo, hi, doc);
}
template <class E>
ParamDef enumeration(const std::string& key, E RenderSettings::*m, std::vector<std::string> names,
                     const std::string& doc) {
  std::string allowed;
  for (size_t i = 0; i < names.size(); ++i) allowed += (i ? "|" : "") + names[i];
  return {key, "enum", allowed, doc,
          [key, m, names, allowed](RenderSettings& s, const std::string& v) {
            for (size_t i = 0; i < names.size(); ++i)
              if (names[i] == v) {
                s.*m = E(int(i));
                return;
              }
            bad(key, v, allowed);
          },
          [m, names](const RenderSettings& s) { return names[size_t(int(s.*m))]; }, ParamKind::Enum, 0,
          double(names.size() - 1), names};
}

std::vector<ParamDef> build() {
  std::vector<ParamDef> t;
  t.push_back(enumeration("mode", &RenderSettings::mode, {"box", "layer"}, "box: the volume where its file puts it; layer: the tileable texture repeated over a spherical cloud layer").in(cloudgen::ParamGroup::Shape));
  t.push_back(real("layer_bottom", &RenderSettings::layer_bottom, 0, 1e5, "layer mode: cloud layer bottom altitude, m").in(cloudgen::ParamGroup::Shape));
  t.push_back(real("layer_top", &RenderSettings::layer_top, 0, 1e5, "layer mode: layer top altitude, m (0 = bottom + the texture's height)").in(cloudgen::ParamGroup::Shape));
  t.push_back(real("earth_radius", &RenderSettings::earth_radius, 1e3, 1e9, "layer mode: Earth radius, m").in(cloudgen::ParamGroup::Shape, true));
  t.push_back(real("coverage", &RenderSettings::coverage, -1, 1, "layer mode: added to the coverage map").in(cloudgen::ParamGroup::Shape));
  t.push_back(real("cloud_type", &RenderSettings::cloud_type, -1, 1, "layer mode: 0 stratus, 0.5 cumulus, 1 cumulonimbus (-1 = from the map)").in(cloudgen::ParamGroup::Shape));
  t.push_back(integer("coverage_tiles", &RenderSettings::coverage_tiles, 1, 1024, "layer mode: texture tiles spanned by one period of the coverage map").in(cloudgen::ParamGroup::Shape));
  t.push_back(integer("steps", &RenderSettings::steps, 1, 8192, "small steps across the volume's largest extent (step = extent / steps)").in(cloudgen::ParamGroup::Quality));
  t.push_back(boolean("occupancy", &RenderSettings::occupancy, "empty-space skipping on (the scheme: render.skipping); false = none whatever render.skipping says (kept for older tracks)").in(cloudgen::ParamGroup::Quality));
  t.push_back(enumeration("skipping", &RenderSettings::skipping, {"none", "thesis", "distance", "tree"}, "empty-space skipping when render.occupancy is on: none; thesis (one large step per empty coarse cell, then small steps next to clouds); distance (jumps as far as the coarse distance field proves empty; the same image); tree (volume=nanovdb only: jumps over the NanoVDB tree's empty nodes, no field needed; the same image)").in(cloudgen::ParamGroup::Quality));
  t.push_back(boolean("occupancy_light", &RenderSettings::occupancy_light, "with skipping on, the light and ground-shadow marches also skip what the occupancy (the distance field, the NanoVDB tree) proves empty. Never changes the image; try it on sparse fields of small clouds").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("eroded_field", &RenderSettings::eroded_field, "the distance field also proves empty the cells the detail erosion empties, so skipping jumps farther on eroded clouds (rebuilt when the erosion or the motion changes). Never changes the image. false: any base density counts as cloud").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(integer("occupancy_cell", &RenderSettings::occupancy_cell, 2, 64, "edge of a coarse occupancy and distance-field cell, voxels. Larger cells take less memory and open faster but jump shorter; render.skipping=thesis steps padding x cell. Doubled while under 4 on grids of more than 8 M cells, then while over 32 M cells").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(integer("occupancy_padding", &RenderSettings::occupancy_padding, 1, 4, "occupancy dilation in cells (thesis: 2, \"double padding\"); the thesis scheme's large step spans it (padding x cell - half a voxel, less across a partial cell at a tiling seam), so each cell of padding lengthens that step by a cell and marks more space occupied").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("adaptive", &RenderSettings::adaptive, "step grows linearly with distance beyond adaptive_start").in(cloudgen::ParamGroup::Quality));
  t.push_back(real("adaptive_start", &RenderSettings::adaptive_start, 0, 1e7, "distance where the step starts growing, m (0 = largest extent / 4)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("adaptive_growth", &RenderSettings::adaptive_growth, 0, 10, "step growth per metre beyond the start, 1/m (0 = 4 / largest extent: the step doubles every quarter extent)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("jitter", &RenderSettings::jitter, "jitter the sample inside each step per pixel and frame (else the midpoint)").in(cloudgen::ParamGroup::Quality));
  t.push_back(boolean("exact_filter", &RenderSettings::exact_filter, "trilinear filtering by hand from texelFetch (strict GPU-vs-CPU mode)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("compiled_modes", &RenderSettings::compiled_modes, "GL: compile one program per set of the frame's modes (box or layer, motion, filter, light volume, sky, phase, skipping...) so the shader keeps no branch the frame does not take; a new mode compiles once, then is cached. false: one program reads the modes at run time, the same image. Keep it on unless compile time matters more than frame time").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("compute", &RenderSettings::compute, "GL: run the full-screen passes (cloud, temporal, bloom, tone map; not the ground) as compute shaders instead of full-screen triangles; the same image, bit for bit. Turn it on for GPUs that shade pixels on only part of their cores (compute-only data-centre GPUs); docs/viewer-speed.md says how to check").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("max_distance", &RenderSettings::max_distance, 1, 1e8, "march no farther than this, m").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("transmittance_cutoff", &RenderSettings::transmittance_cutoff, 0, 0.5, "stop the primary march when the transmittance falls below this (early exit)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(integer("density_step", &RenderSettings::density_step, 1, 16, "density-aware step: after a sample below density_step_below the next step is this many small steps (1 = off; changes the image)").in(cloudgen::ParamGroup::Quality));
  t.push_back(real("density_step_below", &RenderSettings::density_step_below, 0, 10, "density under which the density-aware step lengthens the step").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("sigma_t", &RenderSettings::sigma_t, 0, 1e4, "extinction per metre at density 1 (0 = 0.5 / voxel size)").in(cloudgen::ParamGroup::Shape));
  t.push_back(real("density", &RenderSettings::density, 0, 1e3, "density multiplier").in(cloudgen::ParamGroup::Shape));
  t.push_back(real("erosion", &RenderSettings::erosion, 0, 1, "strength of the G/B/A detail erosion of the R base shape").in(cloudgen::ParamGroup::Detail));
  t.push_back(boolean("detail", &RenderSettings::detail, "render-time detail: a small tileable Worley texture (libnoise3d), laid at render.detail_period metres, erodes the density near the cloud's boundary, finer than the voxels (erosion only: skipping stays exact; not in baked frames or LOD levels, so off by default)").in(cloudgen::ParamGroup::Detail));
  t.push_back(real("detail_period", &RenderSettings::detail_period, 10, 1e5, "render.detail: one tile of the detail texture, m (rounded to a whole number of tiles per volume axis); its finest Worley cells are a sixteenth of it").in(cloudgen::ParamGroup::Detail));
  t.push_back(real("detail_strength", &RenderSettings::detail_strength, 0, 1, "render.detail: erosion strength (the threshold the detail sets, as render.erosion's; 0 = no change)").in(cloudgen::ParamGroup::Detail));
  t.push_back(integer("detail_size", &RenderSettings::detail_size, 32, 128, "render.detail: the texture's edge in texels (made once per size at startup)").in(cloudgen::ParamGroup::Detail, true));
  t.push_back(real("albedo", &RenderSettings::albedo, 0, 1, "single-scattering albedo sigma_s / sigma_t").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(boolean("light_march", &RenderSettings::light_march, "secondary march toward the sun (off: no self-shadowing)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(integer("light_samples", &RenderSettings::light_samples, 1, 128, "samples of the light march").in(cloudgen::ParamGroup::Quality));
  t.push_back(real("light_step", &RenderSettings::light_step, 0, 1e6, "first light step, m (0 = 2.5 voxels)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("light_growth", &RenderSettings::light_growth, 1, 4, "each light step is this many times the previous").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("light_volume", &RenderSettings::light_volume, "box mode: look the sun's optical depth up in a precomputed 3D texture (rebuilt when the sun, the volume or a lighting key changes; moving clouds rebuild it every frame where it has no more texels than the frame marches pixels, else march) instead of marching toward the sun per sample").in(cloudgen::ParamGroup::Quality));
  t.push_back(integer("light_volume_scale", &RenderSettings::light_volume_scale, 1, 16, "light volume texels: the volume's voxels divided by this on each axis (doubled until at most 4 M texels)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(enumeration("phase", &RenderSettings::phase, {"none", "hg", "mie", "two-lobe-hg", "draine-hg"},
                          "phase function: none (isotropic), Henyey-Greenstein (render.g), Mie table (cloudgen's "
                          "Lorenz-Mie solution), two-lobe HG (render.g, g2, lobe_weight), Jendersie & d'Eon's "
                          "HG + Draine fit (render.droplet_diameter); docs/phase.md compares them").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("g", &RenderSettings::g, -0.99, 0.99, "Henyey-Greenstein asymmetry (two-lobe-hg: the forward lobe's)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("g2", &RenderSettings::g2, -0.99, 0.99, "two-lobe-hg: the backward lobe's asymmetry").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("lobe_weight", &RenderSettings::lobe_weight, 0, 1, "two-lobe-hg: weight of the forward lobe (0.97 with g 0.9 and g2 -0.3 gives Mie's g 0.864 for 10 um droplets)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("droplet_diameter", &RenderSettings::droplet_diameter, 5, 50, "draine-hg: droplet diameter in um (the fit's range)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("powder", &RenderSettings::powder, 0, 1, "strength of the powder term 1 - exp(-c d)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("powder_c", &RenderSettings::powder_c, 0, 100, "c of the powder term").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(integer("ms_octaves", &RenderSettings::ms_octaves, 1, 4, "multiple scattering by octaves (Wrenninge 2013, Hillaire 2016): 1 = single scattering; octave i adds weight a^i, optical depth b^i, phase eccentricity c^i (docs/accuracy.md: against the path tracer)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("ms_attenuation", &RenderSettings::ms_attenuation, 0, 1, "octaves: a, the weight factor (keep a <= ms_extinction for energy conservation)").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ms_extinction", &RenderSettings::ms_extinction, 0, 1, "octaves: b, the optical depth factor").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ms_eccentricity", &RenderSettings::ms_eccentricity, 0, 1, "octaves: c, the phase eccentricity factor").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(boolean("ms_volume", &RenderSettings::ms_volume, "box mode, still clouds: multiple scattering (orders >= 2) from a flux-limited diffusion solve on a coarse grid instead of the octaves, closer to the path tracer (use it with render.powder=0). Solved on the CPU when the sun, the volume or a lighting key changes, then one lookup per sample").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(integer("ms_volume_scale", &RenderSettings::ms_volume_scale, 1, 64, "diffusion cells: the volume's voxels divided by this on each axis (doubled until at most 64^3 cells)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("sun_intensity", &RenderSettings::sun_intensity, 0, 1e6, "sun radiance scale").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("ambient", &RenderSettings::ambient, 0, 1e6, "ambient sky radiance scale").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(ParamDef{"time_of_day", "float", "[0, 24] or auto",
               "local solar time, hours (12 = noon): the sun moves along the day at render.latitude on render.day_of_year "
               "(declination from the day, hour angle 15 degrees an hour; azimuth 0 = north = -z, 90 = east = +x) and "
               "replaces the view's sun (--sun still wins). auto = the sun of --sun, the preset's view.sun, the arrows or "
               "Shift + drag in the window",
               [](RenderSettings& s, const std::string& v) {
                 s.time_of_day = v == "auto" ? -1.0 : parse_double("time_of_day", v, 0, 24);
               },
               [](const RenderSettings& s) { return s.time_of_day < 0 ? std::string("auto") : fmt(s.time_of_day); },
               ParamKind::FloatOrAuto, 0, 24, {}}.in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("latitude", &RenderSettings::latitude, -90, 90, "render.time_of_day: the latitude, degrees (north > 0)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(integer("day_of_year", &RenderSettings::day_of_year, 1, 366, "render.time_of_day: the day, 1 = 1 January (81: March equinox, 172: June solstice, 355: December solstice)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(enumeration("sky", &RenderSettings::sky, {"analytic", "precomputed"}, "sky and sky light: analytic gradient and constant ambient (the thesis), or the precomputed atmosphere after Bruneton (atmosphere.* keys; transmittance LUT, marched single scattering, Hillaire's multiple-scattering LUT; docs/sky.md)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(boolean("sky_lut", &RenderSettings::sky_lut, "render.sky=precomputed: read the sky and the aerial perspective from Bruneton's 4D scattering LUT (512x128x32 texels x 3 parts, 96 MiB, computed when an atmosphere.* key changes) instead of marching 32 samples per pixel; docs/sky.md has its cost and error").in(cloudgen::ParamGroup::Quality));
  t.push_back(boolean("air_lut", &RenderSettings::air_lut, "render.sky=precomputed: read the sky and the aerial perspective from a small 3D LUT of the air seen from the camera's altitude (16 azimuths x 64 elevations x 64 distances x 2 parts, 2 MiB, after Hillaire 2020's sky-view and aerial-perspective LUTs; rebuilt when the sun, the camera's altitude or an atmosphere.* key changes), each texel marched as the per-pixel sky is (or read from the 4D LUT with render.sky_lut); from above the air the sky is marched; docs/sky.md has its cost and error").in(cloudgen::ParamGroup::Quality));
  t.push_back(boolean("ground", &RenderSettings::ground, "draw the ground pass").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(ParamDef{"ground_height", "float", "[-1e+07, 1e+07] or auto", "ground plane height, m (auto = min(0, volume bottom); 0 in layer mode)",
               [](RenderSettings& s, const std::string& v) {
                 if (v == "auto") {
                   s.ground_height_auto = true;
                   return;
                 }
                 s.ground_height = parse_double("ground_height", v, -1e7, 1e7);
                 s.ground_height_auto = false;
               },
               [](const RenderSettings& s) { return s.ground_height_auto ? std::string("auto") : fmt(s.ground_height); },
               ParamKind::FloatOrAuto, -1e7, 1e7, {}}.in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("ground_albedo", &RenderSettings::ground_albedo, 0, 1, "ground albedo").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(integer("shadow_samples", &RenderSettings::shadow_samples, 1, 256, "samples of the cloud-shadow march from the ground").in(cloudgen::ParamGroup::Quality));
  t.push_back(boolean("shadow_map", &RenderSettings::shadow_map, "box mode: the ground's cloud shadow from a 2D map of the same march at texel centres (rebuilt when the sun, the volume, the time or a lighting key changes) instead of marching it per ground pixel; moving clouds, which rebuild it every frame, march per pixel while the map has more texels than a quarter of the frame's pixels").in(cloudgen::ParamGroup::Quality));
  t.push_back(integer("shadow_map_scale", &RenderSettings::shadow_map_scale, 1, 16, "shadow map texels: this many voxels wide (doubled until at most 2048 per side)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("exposure", &RenderSettings::exposure, 0, 1e6, "exposure multiplier before tone mapping").in(cloudgen::ParamGroup::Output));
  t.push_back(enumeration("tonemap", &RenderSettings::tonemap, {"reinhard", "aces", "clamp"}, "tone map: Reinhard L/(1+L), ACES filmic, clamp").in(cloudgen::ParamGroup::Output));
  t.push_back(real("bloom", &RenderSettings::bloom, 0, 10, "bloom strength (0 = off)").in(cloudgen::ParamGroup::Output));
  t.push_back(real("bloom_threshold", &RenderSettings::bloom_threshold, 0, 1e6, "bright-pass threshold (linear radiance)").in(cloudgen::ParamGroup::Output));
  t.push_back(enumeration("output", &RenderSettings::output, {"radiance", "transmittance", "iterations"}, "what the cloud pass writes (debug views)").in(cloudgen::ParamGroup::Output, true));
  t.push_back(integer("frame", &RenderSettings::frame, 0, 1 << 30, "frame index of the jitter pattern (and of the temporal cross matrix)").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(boolean("temporal", &RenderSettings::temporal, "temporal upsampling: march one pixel of every 4x4 block per frame in the cross-matrix order and rebuild the rest from the reprojected history; for moving cameras and clouds at 16x fewer marched pixels (GL only; the CPU reference renders every pixel)").in(cloudgen::ParamGroup::Quality));
  t.push_back(enumeration("volume", &RenderSettings::volume, {"auto", "dense", "nanovdb"}, "how the volume reaches the shaders: dense (an RGBA float 3D texture, 16 bytes per voxel of the active box) or nanovdb (the sparse NanoVDB grids in a GPU buffer, through PNanoVDB.h; .nvdb and .vdb inputs load without a dense copy). auto: nanovdb when the dense texture plus occupancy (16.125 bytes per voxel) would exceed dense_budget or the texture alone 2 GiB (more than many drivers allocate for one texture), dense otherwise").in(cloudgen::ParamGroup::Quality));
  t.push_back(enumeration("nanovdb_lookup", &RenderSettings::nanovdb_lookup, {"table", "accessor", "atlas"}, "volume=nanovdb on the GPU: atlas (the occupied 8^3 leaves as 9^3 bricks of one 3D texture the texture unit filters, two fetches per sample; falls back to table beyond 1 GiB); table (a page table of the 8^3 leaves: one fetch and one buffer read per voxel); accessor (PNanoVDB's read accessor walking the tree: the slowest, for checking). All give the same values; the CPU reference always uses the accessor").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("dense_budget", &RenderSettings::dense_budget, 0, 1e9, "memory the dense path's RGBA copy and occupancy may use, MiB (0 = a third of the free memory when the input is opened: the reader's channels, the copy and the GL texture coexist); volume=dense refuses a volume beyond a set budget, volume=auto switches to nanovdb").in(cloudgen::ParamGroup::Quality, true));
  t.push_back(real("lod_bias", &RenderSettings::lod_bias, -16, 16, "a .vdb with levels of detail (cloudgen generate --lod): the coarsest level whose voxel is at most 2^lod_bias pixels at the volume's nearest point is drawn (0: about a pixel; +1 coarser, -1 finer), then coarser while the level exceeds dense_budget (volume=auto or dense); the level drawn is printed").in(cloudgen::ParamGroup::Quality));
  return t;
}

}  // namespace

const std::vector<ParamDef>& render_params() {
  static const std::vector<ParamDef> table = build();
  return table;
}

void apply_setting(RenderSettings& s, const std::string& assignment) {
  auto eq = assignment.find('=');
  if (eq == std::string::npos)
    throw InputError("--set " + assignment + ": expected render.key=value");
  std::string key = assignment.substr(0, eq);
  std::string value = assignment.substr(eq + 1);
  if (key.rfind("atmosphere.", 0) == 0) return apply_atmosphere_setting(s.atmosphere, assignment);
  if (key.rfind("motion.", 0) == 0) return cloudgen::set_motion_key(s.motion, key.substr(7), value, "--set");
  if (key.rfind("render.", 0) == 0) key = key.substr(7);
  std::string known;
  for (const ParamDef& p : render_params()) {
    if (p.key == key) {
      p.set(s, value);
      return;
    }
    known += (known.empty() ? "" : ", ") + p.key;
  }
  throw InputError("--set " + assignment + ": unknown key render." + key + " (known: " + known + ")");
}

std::string view_render_problem(const std::string& key, const std::string& value) {
  RenderSettings s;
  const std::string assignment = key + "=" + value;
  try {
    apply_setting(s, assignment);
    return "";
  } catch (const InputError& e) {
    // The table's words are a --set's ("--set render.KEY=VALUE: invalid value, allowed: ..."):
    // what follows the echoed assignment is the reason, which the caller puts after its own name
    // of the field.
    std::string m = e.what();
    const std::string echoed = "=" + value + ": ";
    const size_t at = m.rfind("--set ", 0) == 0 ? m.find(echoed) : std::string::npos;
    return at == std::string::npos ? m : m.substr(at + echoed.size());
  }
}

const ParamDef& render_param(const std::string& key) {
  for (const ParamDef& p : render_params())
    if (p.key == key) return p;
  std::string known;
  for (const ParamDef& p : render_params()) known += (known.empty() ? "" : ", ") + p.key;
  throw InputError("unknown key render." + key + " (known: " + known + ")");
}

std::string describe_settings(const RenderSettings& s) {
  std::string out;
  for (const ParamDef& p : render_params()) out += "render." + p.key + "=" + p.get(s) + "\n";
  for (const cloudgen::MotionKey& k : cloudgen::motion_keys())
    out += "motion." + k.key + "=" + param::fmt(s.motion.*k.member) + "\n";
  out += std::string("motion.") + cloudgen::kFlowMapKey + "=" + cloudgen::flow_map_name(s.motion) + "\n";
  return out;
}

}  // namespace cloudviewer

namespace cloudviewer {

std::string params_markdown() { return param::grouped_markdown(render_params(), "", "###"); }

const std::vector<KeyBinding>& key_bindings() {
  using A = KeyBinding::Action;
  // GLFW key codes (GLFW/glfw3.h), spelled out so this file needs no GLFW header.
  enum : int { kEqual = 61, kMinus = 45, kLeftBracket = 91, kRightBracket = 93 };
  static const std::vector<KeyBinding> b = {
      {"+", kEqual, "density", A::Scale, 1.25},
      {"-", kMinus, "density", A::Scale, 1 / 1.25},
      {"O", 'O', "occupancy", A::Toggle, 0},
      {"J", 'J', "adaptive", A::Toggle, 0},
      {"L", 'L', "light_march", A::Toggle, 0},
      {"P", 'P', "phase", A::Cycle, 0},
      {"T", 'T', "tonemap", A::Cycle, 0},
      {"B", 'B', "bloom", A::OnOff, 0},
      {"G", 'G', "ground", A::Toggle, 0},
      {"I", 'I', "output", A::Cycle, 0},
      {"X", 'X', "exact_filter", A::Toggle, 0},
      {"N", 'N', "jitter", A::Toggle, 0},
      {"U", 'U', "temporal", A::Toggle, 0},
      {"[", kLeftBracket, "steps", A::Scale, 0.5},
      {"]", kRightBracket, "steps", A::Scale, 2},
      {"1", '1', "exposure", A::Scale, 1 / 1.25},
      {"2", '2', "exposure", A::Scale, 1.25},
      {"3", '3', "g", A::Add, -0.05},
      {"4", '4', "g", A::Add, 0.05},
  };
  return b;
}

void apply_binding(RenderSettings& s, const KeyBinding& b) {
  const ParamDef& p = render_param(b.param);
  switch (b.action) {
    case KeyBinding::Action::Toggle:
      p.set(s, p.get(s) == "true" ? "false" : "true");
      return;
    case KeyBinding::Action::Cycle: {
      size_t i = size_t(std::find(p.choices.begin(), p.choices.end(), p.get(s)) - p.choices.begin());
      p.set(s, p.choices[(i + 1) % p.choices.size()]);
      return;
    }
    case KeyBinding::Action::OnOff: {
      double v = std::stod(p.get(s));
      p.set(s, v > 0 ? fmt(std::max(p.lo, 0.0)) : p.get(RenderSettings{}));
      return;
    }
    case KeyBinding::Action::Scale:
    case KeyBinding::Action::Add: {
      double v = std::stod(p.get(s));
      v = b.action == KeyBinding::Action::Scale ? v * b.amount : v + b.amount;
      if (p.kind == ParamKind::Int) v = std::round(v);
      v = std::clamp(v, p.lo, p.hi);
      std::ostringstream os;
      os.precision(17);
      os << v;
      p.set(s, os.str());
      return;
    }
  }
}

std::string key_help_markdown() {
  std::string md = "| key | parameter | action |\n|---|---|---|\n";
  RenderSettings d;
  for (const KeyBinding& b : key_bindings()) {
    const ParamDef& p = render_param(b.param);
    std::string action;
    switch (b.action) {
      case KeyBinding::Action::Toggle: action = "toggle"; break;
      case KeyBinding::Action::Cycle: action = "next of " + p.range; break;
      case KeyBinding::Action::OnOff: action = "0 / default " + p.get(d); break;
      case KeyBinding::Action::Scale: action = "x " + fmt(b.amount) + ", within " + p.range; break;
      case KeyBinding::Action::Add: action = (b.amount > 0 ? "+ " : "- ") + fmt(std::abs(b.amount)) + ", within " + p.range; break;
    }
    for (size_t i = 0; (i = action.find('|', i)) != std::string::npos; i += 2) action.replace(i, 1, "\\|");
    std::string keys = b.keys == "|" ? "\\|" : b.keys;
    md += "| `" + keys + "` | render." + p.key + " | " + action + " |\n";
  }
  return md;
}

std::vector<PanelWidget> panel_widgets() {
  std::vector<PanelWidget> w;
  RenderSettings d;
  for (const ParamDef& p : render_params()) {
    PanelWidget x;
    x.key = p.key;
    x.lo = p.lo, x.hi = p.hi;
    x.choices = p.choices;
    x.default_value = p.get(d);
    x.tooltip = p.doc + " (" + p.type + ", " + p.range + ", default " + x.default_value + ")";
    switch (p.kind) {
      case ParamKind::Bool: x.kind = PanelWidget::Kind::Checkbox; break;
      case ParamKind::Int: x.kind = PanelWidget::Kind::SliderInt; break;
      case ParamKind::Float: x.kind = PanelWidget::Kind::SliderFloat; break;
      case ParamKind::Enum: x.kind = PanelWidget::Kind::Combo; break;
      case ParamKind::FloatOrAuto: x.kind = PanelWidget::Kind::SliderFloatOrAuto; break;
    }
    // A linear slider over many decades cannot reach the small values.
    double span_lo = std::max(std::abs(p.lo), 1e-3);
    x.logarithmic = p.kind != ParamKind::Bool && p.kind != ParamKind::Enum && p.lo >= 0 && p.hi / span_lo > 1e3;
    x.group = p.group;
    x.advanced = p.advanced;
    w.push_back(x);
  }
  return w;
}

std::vector<PanelGroup> panel_groups() {
  const std::vector<PanelWidget> widgets = panel_widgets();
  std::vector<PanelGroup> out;
  for (cloudgen::ParamGroup g : cloudgen::kParamGroups) {
    PanelGroup pg;
    pg.group = g;
    pg.name = cloudgen::param_group_name(g);
    for (const PanelWidget& w : widgets)
      if (w.group == g) (w.advanced ? pg.render_advanced : pg.render).push_back(w);
    for (const AtmosphereParamDef& p : atmosphere_params())
      if (p.group == g) (p.advanced ? pg.atmosphere_advanced : pg.atmosphere).push_back(p.key);
    if (!pg.render.empty() || !pg.render_advanced.empty() || !pg.atmosphere.empty() || !pg.atmosphere_advanced.empty())
      out.push_back(std::move(pg));
  }
  return out;
}

}  // namespace cloudviewer
