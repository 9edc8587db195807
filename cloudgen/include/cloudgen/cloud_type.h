// C++ side of cloud_type.glsl (the cloud-type height gradients shared with the viewer's shaders),
// compiled in double precision with GLSL's smoothstep and mix.
#pragma once
#include <algorithm>

namespace cloudgen {
namespace cloud_type {

using Number = double;
inline Number smoothstep(Number a, Number b, Number x) {
  Number t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}
inline Number mix(Number x, Number y, Number a) { return x * (1 - a) + y * a; }

#include "cloudgen/cloud_type.glsl"

}  // namespace cloud_type
}  // namespace cloudgen
