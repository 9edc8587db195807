// The C++ side of the GLSL subset the shared shader headers are written in, after Bruneton's
// reference/functions.cc: the one place that says how a .glsl file compiles as C++ in double
// precision (shaders/prelude_glsl.glsl is the GLSL side). A scope that includes shared GLSL text
// opens with
//   CV_GLSL_DOUBLE_TYPES;  GLSL's type names as glm's double types (a class or a namespace), and
//   CV_GLSL_BUILTINS;      GLSL's built-in functions (a namespace; a class finds them through
//                          `using namespace glm` around it).
// The viewer's CPU reference adds the parameter qualifiers IN/OUT/INOUT (viewer/src/cpu/glsl_cpp.h).
// glm's mix, clamp and smoothstep evaluate GLSL's formulas in the same order, so both sides round
// alike.
#pragma once
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#define CV_GLSL_DOUBLE_TYPES \
  using Number = double;     \
  using vec2 = glm::dvec2;   \
  using vec3 = glm::dvec3;   \
  using vec4 = glm::dvec4;   \
  using mat4 = glm::dmat4;   \
  using ivec2 = glm::ivec2;  \
  using ivec3 = glm::ivec3;  \
  using uint = uint32_t

#define CV_GLSL_BUILTINS \
  using glm::abs;        \
  using glm::clamp;      \
  using glm::floor;      \
  using glm::fract;      \
  using glm::max;        \
  using glm::min;        \
  using glm::mix;        \
  using glm::smoothstep; \
  using std::cos;        \
  using std::exp;        \
  using std::sin;        \
  using std::sqrt
