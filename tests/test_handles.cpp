// The window's direct handles (issue 45 item 4), their pure parts: the solar position of
// render.time_of_day against known values, and the sun under the cursor (window point -> view
// direction -> azimuth / elevation), the inverse of the sun direction the renderers use.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "../viewer/src/scene/default_view.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

using namespace cloudviewer;

namespace {

constexpr double kEquinox = 81, kJuneSolstice = 172, kDecemberSolstice = 355;

// The hour of sunrise (elevation 0, no refraction) at `lat` on a day of declination `dec`.
double sunrise_hour(double lat, double dec) {
  return 12 - glm::degrees(std::acos(-std::tan(glm::radians(lat)) * std::tan(glm::radians(dec)))) / 15;
}

// Where the sun's direction lands in a width x height window (GLFW's cursor coordinates), through
// the projection both renderers use.
glm::dvec2 window_point(const Camera& cam, int w, int h, const glm::dvec3& dir) {
  const glm::dvec4 clip = view_projection(cam, w, h) * glm::dvec4(dir, 1.0);
  const glm::dvec2 ndc = glm::dvec2(clip) / clip.w;
  return {(ndc.x + 1) * 0.5 * w, (1 - ndc.y) * 0.5 * h};
}

}  // namespace

TEST(SolarPosition, DeclinationIsZeroAtTheEquinoxesAndTiltAtTheSolstices) {
  EXPECT_NEAR(solar_declination_deg(kEquinox), 0, 1e-9);
  EXPECT_NEAR(solar_declination_deg(264), 0, 0.5);  // the September equinox (Cooper's year is 365 days)
  EXPECT_NEAR(solar_declination_deg(kJuneSolstice), 23.45, 0.01);
  EXPECT_NEAR(solar_declination_deg(kDecemberSolstice), -23.45, 0.01);
}

// At the equinox the noon sun stands 90 - |latitude| up, due south north of the equator and due
// north south of it; it rises at 6 due east and sets at 18 due west, everywhere.
TEST(SolarPosition, EquinoxNoonSunriseAndSunset) {
  for (double lat : {0.0, 20.0, 45.0, 60.0, -33.9}) {
    SCOPED_TRACE(lat);
    const Sun noon = solar_sun(lat, kEquinox, 12);
    EXPECT_NEAR(noon.elevation_deg, 90 - std::abs(lat), 1e-9);
    if (lat != 0) {  // due south north of the equator, due north south of it
      EXPECT_NEAR(std::remainder(noon.azimuth_deg, 360.0), lat > 0 ? 180 : 0, 1e-9);
    }
    const Sun rise = solar_sun(lat, kEquinox, 6), set = solar_sun(lat, kEquinox, 18);
    EXPECT_NEAR(rise.elevation_deg, 0, 1e-9);
    EXPECT_NEAR(rise.azimuth_deg, 90, 1e-9);
    EXPECT_NEAR(set.elevation_deg, 0, 1e-9);
    EXPECT_NEAR(set.azimuth_deg, 270, 1e-9);
    EXPECT_NEAR(solar_sun(lat, kEquinox, 0).elevation_deg, -(90 - std::abs(lat)), 1e-9);  // midnight
  }
  // On the equator the equinox sun climbs 15 degrees an hour straight up the east.
  const Sun nine = solar_sun(0, kEquinox, 9);
  EXPECT_NEAR(nine.elevation_deg, 45, 1e-9);
  EXPECT_NEAR(nine.azimuth_deg, 90, 1e-9);
}

// The solstices: noon elevation 90 - lat +- 23.45, the long and short days' sunrise at
// 12 - acos(-tan lat tan dec) / 15 (4:17 and 7:43 at 45 N), the sun overhead on the tropic and
// up all day beyond the polar circle.
TEST(SolarPosition, SolsticeValues) {
  EXPECT_NEAR(solar_sun(45, kJuneSolstice, 12).elevation_deg, 90 - 45 + 23.45, 0.01);
  EXPECT_NEAR(solar_sun(45, kDecemberSolstice, 12).elevation_deg, 90 - 45 - 23.45, 0.01);
  EXPECT_NEAR(solar_sun(-45, kDecemberSolstice, 12).elevation_deg, 90 - 45 + 23.45, 0.01);
  EXPECT_NEAR(solar_sun(23.45, kJuneSolstice, 12).elevation_deg, 90, 0.01);
  const double long_day = sunrise_hour(45, solar_declination_deg(kJuneSolstice));
  const double short_day = sunrise_hour(45, solar_declination_deg(kDecemberSolstice));
  EXPECT_NEAR(long_day, 4 + 17 / 60.0, 0.02);
  EXPECT_NEAR(short_day, 7 + 43 / 60.0, 0.02);
  EXPECT_NEAR(solar_sun(45, kJuneSolstice, long_day).elevation_deg, 0, 1e-6);
  EXPECT_NEAR(solar_sun(45, kDecemberSolstice, short_day).elevation_deg, 0, 1e-6);
  EXPECT_NEAR(solar_sun(45, kJuneSolstice, 24 - long_day).elevation_deg, 0, 1e-6);
  // The June sun rises north of east at 45 N; in December south of east.
  EXPECT_LT(solar_sun(45, kJuneSolstice, long_day).azimuth_deg, 90);
  EXPECT_GT(solar_sun(45, kDecemberSolstice, short_day).azimuth_deg, 90);
  // The midnight sun at 70 N in June: lat + dec - 90 = 3.45 degrees up, due north.
  EXPECT_NEAR(solar_sun(70, kJuneSolstice, 0).elevation_deg, 70 + 23.45 - 90, 0.01);
  EXPECT_NEAR(std::remainder(solar_sun(70, kJuneSolstice, 0).azimuth_deg, 360.0), 0, 1e-9);
}

// Morning suns are in the east half of the sky, afternoon suns in the west, mirror images about noon.
TEST(SolarPosition, MorningEastAfternoonWestSymmetricAboutNoon) {
  for (double h = 0.5; h < 12; h += 0.5) {
    const Sun am = solar_sun(52, 120, 12 - h), pm = solar_sun(52, 120, 12 + h);
    EXPECT_GT(am.azimuth_deg, 0);
    EXPECT_LT(am.azimuth_deg, 180);
    EXPECT_NEAR(pm.azimuth_deg, 360 - am.azimuth_deg, 1e-9) << h;
    EXPECT_NEAR(pm.elevation_deg, am.elevation_deg, 1e-9) << h;
    EXPECT_LT(solar_sun(52, 120, 12 - h).elevation_deg, solar_sun(52, 120, 12.25 - h).elevation_deg) << h;
  }
}

// render.time_of_day drives the sun of every frame that resolves one (headless, window start,
// --lighting-json): over the view's sun, under --sun; auto leaves the view's.
TEST(SolarPosition, TimeOfDayReplacesTheViewsSunButNotTheFlag) {
  Options o;
  o.view.sun_azimuth = 50;
  o.view.sun_elevation = 30;
  const Camera cam;
  EXPECT_EQ(default_view_sun(o, cam).azimuth_deg, 50);
  apply_setting(o.settings, "render.time_of_day=18.5");
  apply_setting(o.settings, "render.latitude=47");
  apply_setting(o.settings, "render.day_of_year=200");
  const Sun tod = default_view_sun(o, cam), want = solar_sun(47, 200, 18.5);
  EXPECT_EQ(tod.azimuth_deg, want.azimuth_deg);
  EXPECT_EQ(tod.elevation_deg, want.elevation_deg);
  EXPECT_GT(tod.azimuth_deg, 270);  // a summer evening: north of west
  o.sun = Sun{10, 20};
  EXPECT_EQ(default_view_sun(o, cam).azimuth_deg, 10);
  o.sun.reset();
  apply_setting(o.settings, "render.time_of_day=auto");
  EXPECT_EQ(default_view_sun(o, cam).elevation_deg, 30);
  EXPECT_EQ(render_param("time_of_day").get(o.settings), "auto");
  EXPECT_THROW(apply_setting(o.settings, "render.time_of_day=25"), InputError);
  EXPECT_THROW(apply_setting(o.settings, "render.latitude=91"), InputError);
  EXPECT_THROW(apply_setting(o.settings, "render.day_of_year=0"), InputError);
}

// sun_toward is Sun::direction's inverse, on the whole sphere of directions.
TEST(SunHandle, SunTowardInvertsTheSunDirection) {
  for (double az = -175; az <= 180; az += 25)
    for (double el = -85; el <= 85; el += 17) {
      const Sun s = sun_toward(Sun{az, el}.direction() * 3.0);
      EXPECT_NEAR(s.azimuth_deg, az, 1e-9) << az << " " << el;
      EXPECT_NEAR(s.elevation_deg, el, 1e-9) << az << " " << el;
    }
  // Compass directions: -z north (0), +x east (90), +z south (180); straight up the zenith.
  EXPECT_NEAR(sun_toward({1, 0, 0}).azimuth_deg, 90, 1e-12);
  EXPECT_NEAR(std::abs(sun_toward({0, 0, 1}).azimuth_deg), 180, 1e-12);
  EXPECT_NEAR(sun_toward({0, 1, 0}).elevation_deg, 90, 1e-12);
  // Below the handle's range: the elevation stops at its end, the azimuth stays the cursor's.
  const Sun low = sun_toward(Sun{120, -40}.direction(), kSunHandleMinElevation, kSunHandleMaxElevation);
  EXPECT_EQ(low.elevation_deg, kSunHandleMinElevation);
  EXPECT_NEAR(low.azimuth_deg, 120, 1e-9);
}

// A sun drawn where the renderer's projection puts it comes back from its window point: pixel ->
// direction -> azimuth / elevation recovers the sun, for cameras looking every way and windows of
// every shape; the window's centre is the camera's forward direction.
TEST(SunHandle, WindowPointToSunInvertsTheProjection) {
  struct View {
    glm::dvec3 eye, target;
    double fov;
    int w, h;
  };
  const View views[] = {{{0, 100, -2000}, {0, 300, 0}, 60, 320, 180},
                        {{2100, 1100, -1900}, {2100, 450, 1500}, 50, 160, 90},
                        {{500, 20, 500}, {-300, 900, 100}, 75, 200, 200},
                        {{0, 0, 0}, {1, -0.2, 1}, 30, 320, 240}};
  for (const View& v : views) {
    Camera cam;
    cam.eye = v.eye, cam.target = v.target, cam.fov_y_deg = v.fov;
    const glm::dvec3 forward = glm::normalize(v.target - v.eye);
    const glm::dvec3 centre = view_direction(cam, v.w, v.h, v.w / 2.0, v.h / 2.0);
    EXPECT_NEAR(glm::length(centre - forward), 0, 1e-9);
    // Up in the window is up in the world (y decreases toward the top of the window).
    EXPECT_GT(view_direction(cam, v.w, v.h, v.w / 2.0, 0).y, centre.y);
    int seen = 0;
    for (double daz = -40; daz <= 40; daz += 10)
      for (double del = -20; del <= 20; del += 10) {
        const Sun look = sun_toward(forward);
        const Sun sun{look.azimuth_deg + daz, std::clamp(look.elevation_deg + del, -80.0, 80.0)};
        const glm::dvec2 p = window_point(cam, v.w, v.h, sun.direction());
        if (p.x < 0 || p.x > v.w || p.y < 0 || p.y > v.h) continue;  // out of the window
        ++seen;
        const Sun back = sun_toward(view_direction(cam, v.w, v.h, p.x, p.y));
        EXPECT_NEAR(std::remainder(back.azimuth_deg - sun.azimuth_deg, 360.0), 0, 1e-7) << daz << " " << del;
        EXPECT_NEAR(back.elevation_deg, sun.elevation_deg, 1e-7) << daz << " " << del;
      }
    EXPECT_GT(seen, 8);
  }
}
