// C++ side of erosion.glsl (the detail erosion shared with the viewer's shaders), in double
// precision: cloudgen's baked VDB density and the viewer's eroded distance field.
#pragma once
#include <algorithm>

#include "cloudgen/glsl_prelude.h"

namespace cloudgen {

namespace erosion_glsl {
// Internal linkage: the GLSL text defines plain functions, and every includer gets its own copy.
namespace {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"  // each includer uses some of the functions
CV_GLSL_DOUBLE_TYPES;
CV_GLSL_BUILTINS;
#include "cloudgen/erosion.glsl"
#pragma GCC diagnostic pop
}  // namespace
}  // namespace erosion_glsl

/// The viewer's erosion of base density `base` by detail channels g, b, a at height fraction `h`
/// (0 at the bottom of the cloud's box, 1 at its top): cloudgen/erosion.glsl, as the viewer's
/// cloud_density (medium.glsl) applies it, only when all three detail channels exist.
inline double eroded_density(double base, double g, double b, double a, double h, double erosion) {
  if (!(erosion > 0) || !(base > 0)) return std::max(base, 0.0);
  const double e = erosion_glsl::erosion_threshold(erosion_glsl::erosion_detail(g, b, a), h, erosion);
  return erosion_glsl::eroded_base(base, e);
}

}  // namespace cloudgen
