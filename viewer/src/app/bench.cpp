// Benchmark over a camera track (thesis 3.2: below-, inside- and above-cloud views), once per
// configuration, with GPU timer queries; per-frame CSV and a summary table like the thesis's
// tables 3.1-3.4 (mean frame time per technique, with the image change each one causes).
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <tuple>
#include <ostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cloudgen/printable.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/schema.h"
#include "cloudviewer/errors.h"
#include "app/session.h"
#include "internal.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/output.h"
#include "cloudgen/input_scope.h"
#endif

namespace cloudviewer {
namespace {

using cloudgen::check_value;
using cloudgen::FieldSpec;
using cloudgen::Schema;

using nlohmann::json;

// The fields of a track file (cloudgen/schema.h): types, ranges and defaults in one table, checked
// by the checker that reads presets. Positions allow +-1e8 (world metres) here; volume-space
// tracks are held to kVolumePosition after the walk.
FieldSpec field(std::string name, std::string type, std::string def, std::string doc, double lo = -1e300,
                double hi = 1e300, std::vector<std::string> choices = {}, std::string allowed = {}) {
  FieldSpec f;
  f.name = std::move(name), f.type = std::move(type), f.default_value = std::move(def), f.doc = std::move(doc);
  f.lo = lo, f.hi = hi, f.choices = std::move(choices), f.allowed = std::move(allowed);
  return f;
}
const std::string kSets = "list of \"render.KEY=VALUE\" strings";
const Schema& track_schema() {
  static const Schema s({
      field("/description", "string", "\"\"", "What the track is for (not read)."),
      field("/space", "string", "\"volume\"",
            "volume: positions in the volume's unit box (tiles in layer mode); world: metres.", 0, 0, {"volume", "world"}),
      field("/fov", "number", "null", "Vertical field of view, degrees (unset: --fov).", 1, 170),
      field("/frames_per_segment", "integer", "1", "Frames from one key to the next, the key included.", 1, 1000),
      field("/sun", "vec2", "null", "[azimuth, elevation] in degrees for every frame (unset: --sun or behind the camera).",
            -360, 360),
      field("/keys", "array", "[]", "Key frames, at least one: {name, view, eye, target, set}."),
      field("/keys/*/name", "string", "null", "Frame name in the CSV (unset: keyN)."),
      field("/keys/*/view", "string", "null", "View class the summary groups by (unset: the name)."),
      field("/keys/*/eye", "vec3", "null", "Camera position (required).", -1e8, 1e8),
      field("/keys/*/target", "vec3", "null", "Point looked at (required).", -1e8, 1e8),
      field("/keys/*/set", "strings", "[]", "Settings of this key's frames.", 0, 0, {}, kSets),
      field("/configs", "array", "null", "Configurations, each over the whole track (unset: the built-in list)."),
      field("/configs/*/name", "string", "\"config\"", "Configuration name in the table."),
      field("/configs/*/set", "strings", "[]", "Settings of this configuration.", 0, 0, {}, kSets),
  });
  return s;
}
const FieldSpec kSunElevation = field("/sun/1", "number", "null", "Sun elevation, degrees.", -90, 90);
const FieldSpec kVolumePosition = field("", "vec3", "null", "A position in volume space (unit boxes).", -1e5, 1e5);

glm::dvec3 vec3_of(const json& j) { return glm::dvec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); }

std::vector<Config> default_configs() {
  std::vector<Config> c = {{"baseline", {}},
                           {"occupancy off", {"render.occupancy=false"}},
                           {"adaptive on", {"render.adaptive=true"}},
                           {"light march off", {"render.light_march=false"}},
                           {"phase mie", {"render.phase=mie"}},
                           {"phase none", {"render.phase=none"}}};
  for (int s : {8, 16, 32, 64, 256, 512}) c.push_back({"steps " + std::to_string(s), {"render.steps=" + std::to_string(s)}});
  return c;
}

}  // namespace

BenchPlan parse_track(const std::string& text, const std::string& where, const Options& o, const PreparedVolume& vol) {
  const json track = cloudgen::parse_json_checked(text, where);  // bounded depth, no duplicate keys
  // Every field against the table, every problem of the file at once ("<file>: <pointer>: <what>").
  std::vector<std::string> problems;
  auto problem = [&](const std::string& ptr, const std::string& what) { problems.push_back(where + ": " + ptr + ": " + what); };
  auto refuse_if_any = [&] {
    if (problems.empty()) return;
    std::string all;
    for (const std::string& m : problems) all += (all.empty() ? "" : "\n") + m;
    throw InputError(all);
  };
  track_schema().walk(track, problem);
  refuse_if_any();
  if (!track.contains("keys") || track["keys"].empty())
    problem("/keys", "missing or empty; expected a list of at least one {name, view, eye, target, set}");
  const std::string space = track.value("space", "volume");
  for (size_t i = 0; track.contains("keys") && i < track["keys"].size(); ++i)
    for (const char* f : {"eye", "target"}) {
      const std::string ptr = "/keys/" + std::to_string(i) + "/" + f;
      if (!track["keys"][i].contains(f))
        problem(ptr, "missing; expected an array of 3 numbers, each " + track_schema().find("/keys/*/eye")->range());
      else if (space == "volume") check_value(kVolumePosition, track["keys"][i][f], ptr, problem);
    }
  if (track.contains("sun")) check_value(kSunElevation, track["sun"][1], "/sun/1", problem);
  refuse_if_any();

  const double fov = track.contains("fov") ? track["fov"].get<double>() : o.fov;
  const int per_segment = int(track.value("frames_per_segment", 1.0));
  auto to_world = [&](const glm::dvec3& p) { return space == "volume" ? volume_space_to_world(vol, o.settings, p) : p; };
  std::vector<TrackFrame> keys;
  for (size_t i = 0; i < track["keys"].size(); ++i) {
    const json& k = track["keys"][i];
    const std::string p = where + ": /keys/" + std::to_string(i);
    TrackFrame f;
    f.name = k.contains("name") ? k["name"].get<std::string>() : "key" + std::to_string(i);
    f.view = k.contains("view") ? k["view"].get<std::string>() : f.name;
    f.camera.eye = to_world(vec3_of(k["eye"]));
    f.camera.target = to_world(vec3_of(k["target"]));
    if (glm::length(f.camera.target - f.camera.eye) < 1e-6) throw InputError(p + ": eye and target coincide");
    f.camera.fov_y_deg = fov;
    // A view may need its own settings (the issue's view from below marches at most 2133 m).
    const json sets = k.value("set", json::array());
    for (size_t si = 0; si < sets.size(); ++si) {
      RenderSettings check = o.settings;
      try {
        apply_setting(check, sets[si].get<std::string>());  // a bad key fails here, before OpenGL
      } catch (const InputError& e) {
        throw InputError(p + "/set/" + std::to_string(si) + ": " + e.what());
      }
      f.sets.push_back(sets[si].get<std::string>());
    }
    keys.push_back(f);
  }
  std::vector<TrackFrame> frames;
  for (size_t i = 0; i < keys.size(); ++i) {
    frames.push_back(keys[i]);
    if (i + 1 == keys.size()) break;
    for (int s = 1; s < per_segment; ++s) {
      double a = double(s) / per_segment;
      TrackFrame f;
      f.name = keys[i].name + ">" + keys[i + 1].name + "@" + std::to_string(s);
      f.view = a < 0.5 ? keys[i].view : keys[i + 1].view;
      f.camera.eye = glm::mix(keys[i].camera.eye, keys[i + 1].camera.eye, a);
      f.camera.target = glm::mix(keys[i].camera.target, keys[i + 1].camera.target, a);
      f.camera.fov_y_deg = fov;
      f.sets = a < 0.5 ? keys[i].sets : keys[i + 1].sets;
      frames.push_back(f);
    }
  }
  std::vector<Config> configs;
  if (track.contains("configs")) {
    for (const json& c : track["configs"]) {
      Config cfg{c.value("name", "config"), {}};
      for (const json& a : c.value("set", json::array())) cfg.sets.push_back(a.get<std::string>());
      configs.push_back(cfg);
    }
  } else {
    configs = default_configs();
  }
  Sun fixed_sun;
  bool has_sun = track.contains("sun");
  if (has_sun) fixed_sun = Sun{track["sun"][0].get<double>(), track["sun"][1].get<double>()};
  if (o.sun) fixed_sun = *o.sun, has_sun = true;

  std::vector<RenderSettings> settings;
  for (const Config& c : configs) {
    RenderSettings s = o.settings;
    for (const std::string& a : c.sets) apply_setting(s, a);
    settings.push_back(s);
  }

  BenchPlan plan;
  plan.frames = std::move(frames);
  plan.configs = std::move(configs);
  plan.settings = std::move(settings);
  plan.fixed_sun = fixed_sun;
  plan.has_sun = has_sun;
  return plan;
}

namespace {

std::string read_track_file(const std::string& path) {
  return cloudgen::read_text_input(path, "the bench track " + path, "--bench " + path);
}

Sun sun_of(const BenchPlan& plan, const TrackFrame& f) { return plan.has_sun ? plan.fixed_sun : default_sun(f.camera); }

// CPU reference per frame (baseline settings at the reference step count); empty images without
// --bench-reference.
std::vector<Image> reference_images(const Options& o, const BenchPlan& plan, const PreparedVolume& vol,
                                    std::ostream& out) {
  std::vector<Image> reference(plan.frames.size());
  if (o.bench_reference <= 0) return reference;
  auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < plan.frames.size(); ++i) {
    RenderSettings s = o.settings;
    for (const std::string& a : plan.frames[i].sets) apply_setting(s, a);
    s.steps = o.bench_reference;
    s.light_volume = false;  // the reference marches toward the sun per sample, at full-length steps
    s.density_step = 1;
    const Camera& cam = plan.frames[i].camera;
    reference[i] = render_cpu(vol, make_frame(vol, s, cam, sun_of(plan, plan.frames[i]), o.width, o.height)).display;
  }
  out << "cpu reference (" << o.bench_reference << " steps) in "
      << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  return reference;
}

// Configurations may change the occupancy grid (cell, padding) and the distance field's rule
// (erosion, motion: field_rule): one volume per grid and rule, the session's own where they match.
class GridCache {
 public:
  GridCache(const PreparedVolume& vol, std::ostream& out) : vol_(vol), out_(out) {}
  const PreparedVolume& operator()(const RenderSettings& s) {
    const int cell = occupancy_cell_for(s.occupancy_cell, uint64_t(vol_.dims[0]), uint64_t(vol_.dims[1]), uint64_t(vol_.dims[2]));
    const auto key = std::make_tuple(cell, s.occupancy_padding, field_rule(vol_, s));
    if (key == std::make_tuple(vol_.occ_cell, vol_.occ_padding, vol_.dist_rule)) return vol_;
    auto it = grids_.find(key);
    if (it != grids_.end()) return it->second;
    PreparedVolume copy = vol_;
    copy.dist_rule = std::get<2>(key);  // the field build_occupancy builds with its grid
    if (cell == vol_.occ_cell && s.occupancy_padding == vol_.occ_padding) {
      build_distance_field(copy, copy.dist_rule);
    } else {
      build_occupancy(copy, cell, s.occupancy_padding);
      out_ << "occupancy grid of " << cell << "-voxel cells, padding " << s.occupancy_padding << ": "
           << std::lround(copy.occupied_fraction * 100) << "% occupied (base grid "
           << std::lround(vol_.occupied_fraction * 100) << "%)\n";
    }
    return grids_.emplace(key, std::move(copy)).first->second;
  }

 private:
  const PreparedVolume& vol_;
  std::ostream& out_;
  std::map<std::tuple<int, int, FieldRule>, PreparedVolume> grids_;
};

// Per (configuration c, frame i), at c * frames + i: the best of the rounds and what the first
// round saw; per configuration, the rebuilds timed apart and the GL programs it compiled.
struct BenchResults {
  BenchResults(size_t configs, size_t frames)
      : nfr(frames), best(configs * frames), best_wall(configs * frames, 1e300), images(configs * frames),
        trips(configs * frames, 0.0), rebuild_ms(configs, 0.0), tables_ms(configs, 0.0), shadow_ms(configs, 0.0),
        compile_ms(configs, 0.0) {
    for (GpuTimings& t : best) t.total_ms = 1e300;
  }
  // GL programs compiled per configuration (its set of render.compiled_modes, and the trip
  // count's): wall clock, outside every frame time; seconds each on some GPUs' drivers.
  void count_compile(size_t c, const GpuTimings& t) { compile_ms[c] += t.compile_ms, linked += t.programs_linked; }

  size_t nfr;
  std::vector<GpuTimings> best;
  std::vector<double> best_wall;
  std::vector<Image> images;
  std::vector<double> trips;
  std::vector<double> rebuild_ms, tables_ms, shadow_ms, compile_ms;
  int linked = 0;
};

// Work count, independent of machine load: primary-loop trips per pixel (output=iterations).
double trips_per_pixel(const Options& o, GlRenderer& renderer, GridCache& grids, const FrameSetup& setup,
                       size_t c, BenchResults& r) {
  RenderSettings si = setup.settings;
  si.output = OutputMode::Iterations;
  GpuTimings ti;
  renderer.render(make_frame(grids(si), si, setup.camera, setup.sun, o.width, o.height), &ti);
  r.count_compile(c, ti);
  const Image lin = renderer.read_back().linear;
  double sum = 0;
  for (size_t k = 0; k < lin.rgba.size(); k += 4) sum += lin.rgba[k];
  return sum / double(o.width) / double(o.height);
}

// Frame k = (c, i) once in round `round`.
void time_frame(const Options& o, GlRenderer& renderer, GridCache& grids, const FrameSetup& setup, size_t c,
                size_t k, int round, BenchResults& r) {
  GpuTimings t;
  auto w0 = std::chrono::steady_clock::now();
  renderer.render(setup, &t);
  double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count();
  r.count_compile(c, t);
  // A light volume rebuilt because the previous configuration differed is not this frame's
  // cost with a still sun: timed apart (the light_volume_ms column). So are the atmosphere's
  // tables (its LUTs, and the air LUT, which the track's frames at other camera altitudes
  // rebuild in turn): the atmosphere_ms column.
  r.rebuild_ms[c] = std::max(r.rebuild_ms[c], t.light_volume_ms);
  r.tables_ms[c] = std::max(r.tables_ms[c], t.atmosphere_ms);
  r.shadow_ms[c] = std::max(r.shadow_ms[c], t.shadow_map_ms);
  t.total_ms -= t.light_volume_ms + t.atmosphere_ms + t.shadow_map_ms;
  if (t.total_ms < r.best[k].total_ms) r.best[k] = t;
  r.best_wall[k] = std::min(r.best_wall[k], wall);
  if (round == 0) {
    r.images[k] = renderer.read_back().display;
    r.trips[k] = trips_per_pixel(o, renderer, grids, setup, c, r);
  }
}

// Timing on a shared machine: every (configuration, frame) is rendered once per round, the rounds
// interleave all configurations in a rotating order, and the fastest round counts (best of N),
// so a burst of other work slows one sample of each, not one whole configuration.
void run_rounds(const Options& o, const BenchPlan& plan, const std::vector<FrameSetup>& setups, Session& session,
                GridCache& grids, BenchResults& r, std::ostream& err) {
  const size_t nc = plan.configs.size(), nfr = plan.frames.size();
  GlRenderer& renderer = *session.renderer();
  for (size_t c = 0; c < nc; ++c) {  // warm-up: compile, first touch
    session.show(grids(plan.settings[c]));
    GpuTimings t;
    renderer.render(setups[c * nfr], &t);
    r.count_compile(c, t);
  }
  for (int round = 0; round < o.bench_repeat; ++round) {
    for (size_t cc = 0; cc < nc; ++cc) {
      // Rotate the order every round: the first configuration of a round measured ~10% slower
      // (same settings at two positions), so no configuration may always hold that place.
      size_t c = (cc + size_t(round)) % nc;
      session.show(grids(plan.settings[c]));
      for (size_t i = 0; i < nfr; ++i) time_frame(o, renderer, grids, setups[c * nfr + i], c, c * nfr + i, round, r);
    }
    err << "  round " << round + 1 << "/" << o.bench_repeat << " done\n";
  }
}

struct Summary {
  double total = 0, cloud = 0, wall = 0, rmse_base = 0, max_diff = 0, rmse_ref = 0, trips = 0;
  std::map<std::string, std::pair<double, int>> by_view;
};

// The per-configuration sums over the track, and the CSV's rows (when `csv`).
std::vector<Summary> summarize(const Options& o, const BenchPlan& plan, const BenchResults& r,
                               const std::vector<Image>& reference, std::ostream* csv) {
  const std::vector<TrackFrame>& frames = plan.frames;
  const size_t nfr = frames.size();
  std::vector<Summary> sums(plan.configs.size());
  for (size_t c = 0; c < plan.configs.size(); ++c) {
    for (size_t i = 0; i < nfr; ++i) {
      const GpuTimings& mean = r.best[c * nfr + i];
      double wall = r.best_wall[c * nfr + i];
      const Image& img = r.images[c * nfr + i];
      const Image& base = r.images[i];
      double rb = rmse(img, base), md = max_abs_diff(img, base);
      double rr = o.bench_reference > 0 ? rmse(img, reference[i]) : std::nan("");
      Summary& s = sums[c];
      s.total += mean.total_ms, s.cloud += mean.cloud_ms, s.wall += wall, s.rmse_base += rb;
      s.trips += r.trips[c * nfr + i];
      s.max_diff = std::max(s.max_diff, md), s.rmse_ref += o.bench_reference > 0 ? rr : 0;
      s.by_view[frames[i].view].first += mean.total_ms;
      s.by_view[frames[i].view].second += 1;
      if (csv) {
        *csv << '"' << plan.configs[c].name << "\",\"" << frames[i].name << "\"," << frames[i].view << ","
             << mean.total_ms << "," << mean.ground_ms << "," << mean.cloud_ms << "," << mean.post_ms << "," << wall
             << "," << r.trips[c * nfr + i] << "," << rb << "," << md << ",";
        if (o.bench_reference > 0) *csv << rr;
        *csv << "," << r.rebuild_ms[c] << "," << r.tables_ms[c] << "," << r.compile_ms[c] << "," << r.shadow_ms[c]
             << "\n";
      }
    }
  }
  return sums;
}

void print_table(const Options& o, const BenchPlan& plan, const std::vector<Summary>& sums, std::ostream& out) {
  std::vector<std::string> views;
  for (const TrackFrame& f : plan.frames)
    if (std::find(views.begin(), views.end(), f.view) == views.end()) views.push_back(f.view);
  double nf = double(plan.frames.size());
  out << "\n" << std::left << std::setw(18) << "configuration" << std::right << std::setw(11) << "frame ms"
      << std::setw(11) << "clouds ms";
  for (const std::string& v : views) out << std::setw(12) << (cloudgen::printable(v.substr(0, 8)) + " ms");
  out << std::setw(9) << "speed-up" << std::setw(10) << "trips/px" << std::setw(12) << "max|diff|" << std::setw(12)
      << "RMSE base";
  if (o.bench_reference > 0) out << std::setw(12) << "RMSE ref";
  out << "\n";
  out << std::fixed;
  for (size_t c = 0; c < plan.configs.size(); ++c) {
    const Summary& s = sums[c];
    out << std::left << std::setw(18) << cloudgen::printable(plan.configs[c].name) << std::right << std::setprecision(2) << std::setw(11)
        << s.total / nf << std::setw(11) << s.cloud / nf;
    for (const std::string& v : views) {
      auto it = s.by_view.find(v);
      out << std::setw(12) << (it == s.by_view.end() ? 0.0 : it->second.first / it->second.second);
    }
    out << std::setw(8) << (sums[0].total / s.total) << "x" << std::setprecision(1) << std::setw(10) << s.trips / nf
        << std::setprecision(5) << std::setw(12) << s.max_diff
        << std::setw(12) << s.rmse_base / nf;
    if (o.bench_reference > 0) out << std::setw(12) << s.rmse_ref / nf;
    out << "\n";
  }
  out << std::defaultfloat;
  out << "(frame/clouds ms: GPU timer queries, best of the rounds per frame, mean over the track, without the rebuilds of the\n"
         " light volume, the ground shadow map and the atmosphere's tables (CSV: light_volume_ms, shadow_map_ms, atmosphere_ms);\n"
         " speed-up: baseline frame time / this one;\n"
         " trips/px: primary-march loop trips per pixel (large or small steps), a load-independent work count;\n"
         " max|diff| and RMSE base: display image against the baseline configuration, 0..1 scale";
  if (o.bench_reference > 0) out << ";\n RMSE ref: against the CPU reference at " << o.bench_reference << " steps";
  out << ")\n";
}

// The CSV is collected and written at the end through the toolkit's safe writer: an existing
// file is replaced only by a complete one, and a write error is reported (exit 2).
void write_csv(const std::string& path, const std::string& csv_text, std::ostream& out) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  cloudgen::atomic_write(path, [&](const std::string& tmp) { cloudgen::write_file_bytes(tmp, csv_text.data(), csv_text.size()); });
#else
  std::ofstream f(path, std::ios::binary);
  f << csv_text;
  if (!f.flush()) throw IoError("--csv " + path + ": write failed");
#endif
  out << "wrote " << cloudgen::printable(path) << "\n";
}

}  // namespace

int run_bench(const Options& o, Session& session, std::ostream& out, std::ostream& err) {
  const PreparedVolume& vol = session.volume();
  const BenchPlan plan = parse_track(read_track_file(o.bench), o.bench, o, vol);
  out << session.start_headless(o.shader_dir) << "\n"
      << "bench: " << plan.frames.size() << " frames x " << plan.configs.size() << " configurations at " << o.width
      << "x" << o.height << ", best of " << o.bench_repeat << " interleaved rounds\n";
  const std::vector<Image> reference = reference_images(o, plan, vol, out);

  std::ostringstream csv;
  const bool want_csv = !o.csv.empty();
  if (want_csv) {
    csv << "config,frame,view,gpu_total_ms,gpu_ground_ms,gpu_cloud_ms,gpu_post_ms,wall_ms,loop_trips_per_pixel,"
           "rmse_vs_baseline,max_diff_vs_baseline,rmse_vs_reference,light_volume_ms,atmosphere_ms,compile_ms,shadow_map_ms\n";
  }
  const size_t nc = plan.configs.size(), nfr = plan.frames.size();
  GridCache grids(vol, out);
  std::vector<FrameSetup> setups(nc * nfr);
  for (size_t c = 0; c < nc; ++c)
    for (size_t i = 0; i < nfr; ++i) {
      RenderSettings s = plan.settings[c];
      for (const std::string& a : plan.frames[i].sets) apply_setting(s, a);
      setups[c * nfr + i] = make_frame(grids(s), s, plan.frames[i].camera, sun_of(plan, plan.frames[i]), o.width, o.height);
    }
  BenchResults results(nc, nfr);
  run_rounds(o, plan, setups, session, grids, results, err);
  const std::vector<Summary> sums = summarize(o, plan, results, reference, want_csv ? &csv : nullptr);
  print_table(o, plan, sums, out);
  double compile_total = 0;
  for (double ms : results.compile_ms) compile_total += ms;
  out << "GL programs compiled: " << results.linked << " in " << std::fixed << std::setprecision(2)
      << compile_total / 1000 << " s of wall clock, not in the frame times (CSV: compile_ms per configuration)\n"
      << std::defaultfloat;
  if (want_csv) write_csv(o.csv, csv.str(), out);
  return 0;
}

}  // namespace cloudviewer
