// `cloudgen generate PRESET --frames A:B --fps F [--loop] -o out/cloud_####.vdb`: the preset's
// static volume is generated once, then each frame is baked from it (cloudgen/sequence.h) and
// staged; every frame of the run is published together at the end, or none.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>

#include "cloudgen/cli_parse.h"
#include "cloudgen/sequence.h"
#include "cloudgen/weather_map.h"
#include "cloudgen/printable.h"
#include "commands.h"

namespace cloudgen::cli {

namespace {

/// Every staged frame holds one open file until the batch commits (the all-or-nothing rule), so a
/// long sequence needs as many descriptors: raise the soft limit to the hard one, and refuse up
/// front, naming the limit, when even that is too small.
void ensure_descriptors(int64_t frames) {
  struct rlimit rl;
  if (::getrlimit(RLIMIT_NOFILE, &rl) != 0) return;
  const rlim_t need = rlim_t(frames) + 64;
  if (rl.rlim_cur != RLIM_INFINITY && rl.rlim_cur < need) {
    struct rlimit up = rl;
    up.rlim_cur = rl.rlim_max == RLIM_INFINITY ? need : std::min<rlim_t>(rl.rlim_max, std::max<rlim_t>(need, rl.rlim_cur));
    ::setrlimit(RLIMIT_NOFILE, &up);
    ::getrlimit(RLIMIT_NOFILE, &rl);
  }
  if (rl.rlim_cur != RLIM_INFINITY && rl.rlim_cur < need)
    throw InputError("--frames: " + std::to_string(frames) + " frames are staged as open files until all are complete, "
                     "but this process may open only " + std::to_string(uint64_t(rl.rlim_cur)) +
                     " files (ulimit -n, hard limit " +
                     (rl.rlim_max == RLIM_INFINITY ? std::string("unlimited") : std::to_string(uint64_t(rl.rlim_max))) +
                     "); raise the limit or bake the range in parts");
}
}  // namespace

void run_generate_sequence(const Preset& p, const std::string& preset_path, const GenerateArgs& a) {
  if (a.frames.empty())
    throw InputError(std::string(a.loop ? "--loop" : "--fps") +
                     ": only for sequences; add --frames A:B (e.g. --frames 1:48 --fps 24 -o out/cloud_####.vdb)");
  const FrameRange r = parse_frames(a.frames);
  const double fps = a.fps.empty() ? 24.0 : parse_fps(a.fps);
  if (a.outputs.size() != 1)
    throw InputError("-o: --frames writes one VDB sequence; give a single -o such as out/cloud_####.vdb (got " +
                     std::to_string(a.outputs.size()) + ")");
  const std::string& pattern = a.outputs[0];
  const Format f = a.format.empty() ? format_from_path(pattern) : parse_format(a.format);
  if (f != Format::Vdb)
    throw InputError("-o " + printable(pattern) + ": --frames writes OpenVDB frames; the output must be a .vdb (got " +
                     format_name(f) + ")");
  if (!has_frame_pattern(pattern) && r.count() > 1)
    throw InputError("-o " + printable(pattern) + ": --frames " + a.frames + " is " + std::to_string(r.count()) +
                     " frames, and the file name has no run of # for the frame number; use e.g. out/cloud_####.vdb "
                     "(Blender's volume-sequence naming: #### = the zero-padded frame number)");
  if (!a.region.empty()) throw InputError("--region: not available with --frames (each frame moves the whole volume)");
  if (mpi_requested(a.mpi)) throw InputError("--mpi: sequences are baked by one process; run without --mpi or mpirun");

  const ExportOptions& eo = p.export_options;
  MotionBox box;
  box.dims = p.resolution;
  box.voxel_size = p.voxel_size;
  box.origin = p.origin;
  box.tiles_xz = p.tiling;
  MotionParams m = p.motion;
  const double duration = double(r.count()) / fps;
  std::vector<std::string> notes;
  if (a.loop) m = loop_motion(m, duration, box, &notes);
  if (!a.quiet)
    for (const auto& n : notes) std::fprintf(stderr, "--loop: %s\n", n.c_str());

  ensure_descriptors(r.count());
  OutputBatch batch;
  batch.protect(preset_path, "the input preset " + preset_path);
  if (p.weather_map) batch.protect(p.weather_map->path, "the preset's weather map " + p.weather_map->path);
  for (int64_t fr = r.first; fr <= r.last; ++fr)
    batch.claim(frame_path(pattern, fr), "frame " + std::to_string(fr) + " of the sequence");

  const bool detail = needs_detail(f, eo);
  int channels = 1;
  if (detail)
    for (int c = 1; c < 4; ++c) channels += p.channels[c].enabled;
  const uint64_t need = memory_estimate(p, detail) + frame_memory_estimate(box, m, r, fps, channels);
  const uint64_t limit = parse_bytes(a.max_memory, "--max-memory");
  if (need > limit)
    throw InputError(preset_path + ": the volume and its largest frame need about " + human_bytes(need) +
                     ", more than --max-memory " + a.max_memory + " (lower /resolution or use --resolution N)");

  GenerateOptions go;
  go.threads = a.threads;
  go.detail = detail;
  go.skip_empty = !a.no_skip;
  go.cancel = &g_cancel;
  go.progress = progress_bar("generate", a.quiet);
  GenerateStats st;
  const Volume v = generate(p, go, &st);

  auto bar = progress_bar("frames", a.quiet);
  double bake_s = 0, write_s = 0;
  for (int64_t fr = r.first; fr <= r.last; ++fr) {
    if (g_cancel) throw Cancelled();
    const auto t0 = std::chrono::steady_clock::now();
    MotionFrame mf = bake_frame(v, m, fr, fps, a.threads);
    mf.range = r;
    mf.loop = a.loop;
    const auto t1 = std::chrono::steady_clock::now();
    write_vdb_frame(mf, frame_path(pattern, fr), eo, batch);
    const auto t2 = std::chrono::steady_clock::now();
    bake_s += std::chrono::duration<double>(t1 - t0).count();
    write_s += std::chrono::duration<double>(t2 - t1).count();
    if (bar) bar(double(fr - r.first + 1) / double(r.count()));
    if (fr == r.first) test_hold("frames");
  }
  test_hold("commit");
  if (g_cancel) throw Cancelled();
  batch.commit();
  if (!a.quiet || a.stats) {
    const double n = double(r.count());
    std::fprintf(stderr,
                 "wrote %lld frame(s) %s .. %s (vdb, %g fps, t = %g .. %g s): %ux%ux%u voxels, generate %.3f s, "
                 "per frame: displace %.3f s, write %.3f s\n",
                 static_cast<long long>(r.count()), printable(frame_path(pattern, r.first)).c_str(),
                 printable(frame_path(pattern, r.last)).c_str(), fps, double(r.first) / fps, double(r.last) / fps,
                 v.dims[0], v.dims[1], v.dims[2], st.seconds, bake_s / n, write_s / n);
  }
}

}  // namespace cloudgen::cli
