// `cloudgen flowmap`: the procedural flow map (motion.glsl's curl of a three-wave stream function)
// written as the PNG a flow-map image is read from (motion.flow_map), a start for painting one.
#include <cstdio>

#include "cloudgen/io.h"
#include "cloudgen/motion.h"
#include "cloudgen/printable.h"
#include "commands.h"

namespace cloudgen::cli {
namespace {

struct FlowmapArgs {
  std::string out, size = "256x64";
  bool quiet = false;
};

void run_flowmap(const FlowmapArgs& a) {
  int w = 0, h = 0;
  char tail = 0;
  const int most = kFlowMapMaxSide;
  if (std::sscanf(a.size.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 2 || h < 2 || w > most || h > most)
    throw InputError("--size " + printable(a.size) + ": expected WIDTHxHEIGHT, each 2.." + std::to_string(most) +
                     " (e.g. 256x64)");
  const std::string ext = a.out.size() >= 4 ? a.out.substr(a.out.size() - 4) : "";
  if (ext != ".png" && ext != ".PNG") throw InputError("-o " + printable(a.out) + ": a flow map is written as .png");
  OutputBatch batch;
  batch.claim(a.out, "the flow map");
  batch.stage(a.out, [&](const std::string& tmp) { write_flow_map_png(tmp, w, h); });
  if (g_cancel) throw Cancelled();
  batch.commit();
  if (!a.quiet)
    std::fprintf(stderr,
                 "wrote %s: %dx%d 16-bit flow map (x = flow phase, wraps; y = height, top row = top of the layer; "
                 "R = up, G = forward, value * 2 - 1); use it with --set motion.flow_map=%s\n",
                 printable(a.out).c_str(), w, h, printable(a.out).c_str());
}

}  // namespace

void add_flowmap_command(CLI::App& app, std::function<void()>& run) {
  auto a = std::make_shared<FlowmapArgs>();
  CLI::App* c = app.add_subcommand("flowmap", "Write the procedural flow map as a PNG to paint over (motion.flow_map).");
  c->footer(
      "A flow map moves the clouds over time: at time t it is looked up at the phases\n"
      "frac(t * motion.flow_speed) and that + 0.5, blended so that the flow never jumps, and scaled by\n"
      "the height fraction and motion.flow_up / motion.flow_forward (metres). Layout: x = the flow phase\n"
      "(one cycle, the left edge follows the right), y = the height fraction (top row = top of the\n"
      "layer), R = up and G = forward as value * 2 - 1 (0.5 = no flow), 8 or 16 bits.\n\n"
      "Examples:\n"
      "  cloudgen flowmap -o out/flow.png                 # the built-in flow, 256x64, 16-bit\n"
      "  cloudviewer cloud.vdb --set motion.flow_map=out/flow.png --time 30 --out t30.png\n"
      "  cloudgen generate cumulus --set motion.flow_map=out/flow.png --frames 1:48 --fps 24 \\\n"
      "      -o out/cloud_####.vdb");
  c->add_option("-o,--output", a->out, "Output image (.png)")->required();
  c->add_option("--size", a->size, "WIDTHxHEIGHT in texels (default 256x64)");
  c->add_flag("-q,--quiet", a->quiet, "No summary line");
  c->callback([a, &run] { run = [a] { run_flowmap(*a); }; });
}

}  // namespace cloudgen::cli
