// `cloudgen phase`: a phase-function table for renderers (angle_deg,r,g,b per steradian,
// normalised to 1 over the sphere), from the Lorenz-Mie solution for a cloud's droplets or from
// one of the analytic approximations.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/phase.h"
#include "cloudgen/schema.h"
#include "commands.h"

namespace cloudgen::cli {
namespace {

struct PhaseArgs {
  std::string model = "mie", out;
  double radius = 10, variance = 0.111, g = -2, g2 = -0.3, w = 0.97;
  int samples = 0;
  bool quiet = false;
};

void run_phase(const PhaseArgs& a) {
  if (a.out.empty()) throw InputError("-o/--output: give the table's file name, e.g. -o phase.csv");
  OutputBatch batch;
  batch.claim(a.out, "the phase table");
  const std::vector<double> angles = phase::table_angles();
  std::vector<std::array<double, 3>> rgb(angles.size());
  std::string summary;
  auto grey = [&](auto f) {
    for (size_t i = 0; i < angles.size(); ++i) {
      const double v = f(std::cos(angles[i] * M_PI / 180));
      rgb[i] = {v, v, v};
    }
  };
  if (a.model == "mie") {
    const double nm[3] = {650, 550, 450};
    for (int c = 0; c < 3; ++c) {
      const phase::BulkPhase b = phase::mie_population({a.radius, a.variance, a.samples}, nm[c], angles);
      for (size_t i = 0; i < angles.size(); ++i) rgb[i][c] = b.value[i];
      char buf[120];
      std::snprintf(buf, sizeof buf, "%s%.0f nm: g %.4f, Qext %.4f", c ? "; " : "", nm[c], b.g, b.qext_effective);
      summary += buf;
    }
  } else if (a.model == "hg") {
    const double g = a.g > -2 ? a.g : 0.86;
    if (!(std::fabs(g) < 1)) throw InputError("--g: " + shortest_text(g) + " must be in (-1, 1)");
    grey([&](double c) { return phase::henyey_greenstein(g, c); });
    summary = "g " + shortest_text(g);
  } else if (a.model == "two-lobe-hg") {
    const double g = a.g > -2 ? a.g : 0.9;
    if (!(std::fabs(g) < 1) || !(std::fabs(a.g2) < 1) || !(a.w >= 0 && a.w <= 1))
      throw InputError("--g and --g2 must be in (-1, 1) and --weight in [0, 1]");
    grey([&](double c) { return phase::two_lobe_hg(g, a.g2, a.w, c); });
    summary = "g1 " + shortest_text(g) + ", g2 " + shortest_text(a.g2) + ", weight " + shortest_text(a.w);
  } else {
    const phase::DraineHgFit f = phase::draine_hg_fit(2 * a.radius);
    grey([&](double c) { return phase::draine_hg(f, c); });
    char buf[160];
    std::snprintf(buf, sizeof buf, "droplet diameter %.1f um: g_HG %.4f, g_D %.4f, alpha %.2f, w_D %.4f", 2 * a.radius,
                  f.g_hg, f.g_d, f.alpha, f.w_d);
    summary = buf;
  }
  std::ostringstream o;
  o.precision(9);
  o << "angle_deg,r,g,b\n";
  for (size_t i = 0; i < angles.size(); ++i)
    o << angles[i] << "," << rgb[i][0] << "," << rgb[i][1] << "," << rgb[i][2] << "\n";
  const std::string text = o.str();
  batch.stage(a.out, [&](const std::string& tmp) { write_file_bytes(tmp, text.data(), text.size()); });
  if (g_cancel) throw Cancelled();
  batch.commit();
  if (!a.quiet)
    std::fprintf(stderr, "wrote %s: %s phase, %zu angles, per steradian, normalised to 1; %s\n", printable(a.out).c_str(),
                 a.model.c_str(), angles.size(), summary.c_str());
}

}  // namespace

void add_phase_command(CLI::App& app, std::function<void()>& run) {
  auto a = std::make_shared<PhaseArgs>();
  CLI::App* c = app.add_subcommand("phase", "Write a phase-function table (angle_deg,r,g,b) for cloud droplets.");
  c->footer(
      "Models: mie (Lorenz-Mie over a modified-gamma droplet size distribution at 650/550/450 nm, water\n"
      "1.331-1.337), hg (Henyey-Greenstein), two-lobe-hg, draine-hg (Jendersie & d'Eon 2023's fit, from the\n"
      "droplet diameter 2 x --effective-radius). Values are per steradian and integrate to 1 over the\n"
      "sphere; 2251 angles, 0.01 degree steps up to 5 degrees (the forward peak is ~1e6 times the side).\n\n"
      "Examples:\n"
      "  cloudgen phase --model mie --effective-radius 10 -o out/mie.csv       # cloud default, g ~ 0.86\n"
      "  cloudgen phase --model draine-hg --effective-radius 10 -o out/dhg.csv\n"
      "  cloudgen phase --model hg --g 0.86 -o out/hg.csv");
  c->add_option("--model", a->model, "mie | hg | two-lobe-hg | draine-hg")
      ->check(CLI::IsMember({"mie", "hg", "two-lobe-hg", "draine-hg"}));
  c->add_option("--effective-radius", a->radius, "Droplet effective radius in um, 0.5..100 (default 10; draine-hg: 2.5..25)")
      ->check(CLI::Range(0.5, 100.0));
  c->add_option("--effective-variance", a->variance, "Size distribution's effective variance, 0.01..0.3 (default 0.111)")
      ->check(CLI::Range(0.01, 0.3));
  c->add_option("--g", a->g, "hg: asymmetry (default 0.86); two-lobe-hg: the forward lobe's g (default 0.9)");
  c->add_option("--g2", a->g2, "two-lobe-hg: the backward lobe's g (default -0.3)");
  c->add_option("--weight", a->w, "two-lobe-hg: weight of the forward lobe (default 0.97: g 0.864 as Mie's 10 um cloud)");
  c->add_option("--samples", a->samples, "mie: droplet radii in the size quadrature (0 = from the size parameter)")
      ->check(CLI::Range(0, 20000));
  c->add_option("-o,--output", a->out, "Output table (.csv)")->required();
  c->add_flag("-q,--quiet", a->quiet, "No summary line");
  c->callback([a, &run] { run = [a] { run_phase(*a); }; });
}

}  // namespace cloudgen::cli
