// The viewer's numerical stress table (issue 8): every numeric render.* key at the ends of its
// range and just beyond, and the extreme scenes (sun at and below the horizon, HG g -> +-0.99,
// a camera 100 km away and near 1e7 m, 1-pixel images). Each case is refused up front with the
// allowed range, or renders with no NaN or infinity anywhere and display values in [0, 1].
// The CPU reference renders every case (it runs the same shader text in double); the GL renderer
// renders the extreme scenes, since a float overflow there is what the CPU cannot show.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include "cloudviewer/errors.h"
#include "cloudviewer/image.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"

using namespace cloudviewer;

namespace {

const PreparedVolume& blob() {
  static std::unique_ptr<PreparedVolume> v = std::make_unique<PreparedVolume>(prepare_volume(synthetic_volume("blob"), 8));
  return *v;
}

/// Non-finite values in either image, or display values outside [0, 1].
std::string check(const FrameImages& im) {
  const ImageStats lin = image_stats(im.linear), dis = image_stats(im.display);
  std::ostringstream o;
  if (lin.nonfinite) o << lin.nonfinite << " non-finite linear values; ";
  if (dis.nonfinite) o << dis.nonfinite << " non-finite display values; ";
  if (dis.min < 0 || dis.max > 1) o << "display range [" << dis.min << ", " << dis.max << "]; ";
  return o.str();
}

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

FrameSetup frame(const RenderSettings& s, int w, int h, const Camera* cam = nullptr, const Sun* sun = nullptr) {
  const Camera c = cam ? *cam : default_camera(blob(), 60, double(w) / h);
  return make_frame(blob(), s, c, sun ? *sun : default_sun(c), w, h);
}

}  // namespace

TEST(ViewerStress, EveryRenderKeyAtAndBeyondTheEndsOfItsRange) {
  size_t rendered = 0, refused = 0;
  for (const ParamDef& p : render_params()) {
    if (p.kind != ParamKind::Int && p.kind != ParamKind::Float && p.kind != ParamKind::FloatOrAuto) continue;
    const double step = p.kind == ParamKind::Int ? 1 : std::max(1e-9, std::fabs(p.hi - p.lo) * 1e-6);
    for (double v : {p.lo, p.hi, p.lo - step, p.hi + step}) {
      const bool inside = v >= p.lo && v <= p.hi;
      const std::string value = p.kind == ParamKind::Int ? std::to_string(std::llround(v)) : fmt(v);
      SCOPED_TRACE("render." + p.key + "=" + value);
      RenderSettings s;
      s.steps = 24;  // small, except where the case sets it
      s.light_samples = 3;
      s.shadow_samples = 4;
      try {
        apply_setting(s, p.key + "=" + value);
      } catch (const InputError& e) {
        ++refused;
        EXPECT_FALSE(inside) << "a value inside the range was refused: " << e.what();
        EXPECT_NE(std::string(e.what()).find(p.key), std::string::npos) << e.what();
        continue;
      }
      EXPECT_TRUE(inside) << "a value outside " << p.range << " was accepted";
      if (p.key == "steps" && v > 4096) continue;  // accepted; too slow for a unit test on the CPU
      if (p.key == "light_samples" && v > 64) continue;
      if (p.key == "shadow_samples" && v > 64) continue;
      EXPECT_EQ(check(render_cpu(blob(), frame(s, 24, 14))), "");
      ++rendered;
    }
  }
  std::cout << rendered << " cases rendered, " << refused << " refused up front\n";
  EXPECT_GT(rendered, 40u);
  EXPECT_GT(refused, 40u);
  // Non-finite text is refused for every number.
  for (const char* bad : {"render.g=nan", "render.exposure=inf", "render.steps=1e400", "render.density=-inf"}) {
    RenderSettings s;
    EXPECT_THROW(apply_setting(s, bad), InputError) << bad;
  }
}

TEST(ViewerStress, ExtremeScenesStayFiniteOnTheGpuAndTheCpu) {
  HeadlessContext ctx;
  ctx.make_current();
  GlRenderer gl{ShaderSource()};
  gl.set_volume(blob());
  const Camera base = default_camera(blob(), 60, 32.0 / 18);
  const glm::dvec3 centre = base.target;
  struct Case {
    std::string name;
    std::vector<std::string> sets;
    Camera cam;
    Sun sun;
    int w = 32, h = 18;
  };
  std::vector<Case> cases;
  auto add = [&](std::string name, std::vector<std::string> sets, Camera cam, Sun sun, int w = 32, int h = 18) {
    cases.push_back({std::move(name), std::move(sets), cam, sun, w, h});
  };
  Sun noon{0, 90}, horizon{45, 0}, below{45, -5}, deep{45, -20};
  add("sun at the zenith", {}, base, noon);
  add("sun on the horizon", {}, base, horizon);
  add("sun 5 degrees below the horizon", {}, base, below);
  add("sun 20 degrees below the horizon", {}, base, deep);
  add("HG g = 0.99 looking at the sun", {"render.g=0.99"}, base, Sun{180, 10});
  add("HG g = -0.99", {"render.g=-0.99"}, base, Sun{180, 10});
  Camera far = base;
  far.eye = centre + glm::dvec3(0, 0, -100e3);
  add("camera 100 km away", {"render.max_distance=1e6"}, far, horizon);
  Camera huge = base;
  huge.eye = centre + glm::dvec3(9.9e6, 0, -9.9e6);
  add("camera near 1e7 m", {}, huge, horizon);
  add("1x1 image", {}, base, horizon, 1, 1);
  add("1x9 image", {}, base, horizon, 1, 9);
  add("density 1000, sigma_t 10", {"render.density=1000", "render.sigma_t=10"}, base, horizon);
  add("all lighting off", {"render.light_march=false", "render.ambient=0", "render.sun_intensity=0"}, base, noon);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    RenderSettings s;
    s.steps = 48;
    for (const std::string& a : c.sets) apply_setting(s, a);
    const FrameSetup f = make_frame(blob(), s, c.cam, c.sun, c.w, c.h);
    EXPECT_EQ(check(render_cpu(blob(), f)), "") << "CPU";
    gl.render(f);
    EXPECT_EQ(check(gl.read_back()), "") << "GL";
  }
}
