// The C++ side of the GLSL subset the shared headers are written in (shaders/prelude_glsl.glsl is
// the GLSL side), after Bruneton's reference/functions.cc: a class that includes shader headers
// opens with CV_GLSL_DOUBLE_TYPES (GLSL's type names as glm's double types), and the parameter-
// qualifier macros below turn `IN(T)` / `OUT(T)` / `INOUT(T)` into references, so the shaders'
// functions become its members in double precision. The class defines the lookups each side
// implements (texel fetches). Include this header last: it defines IN, OUT and INOUT for the rest
// of the file. (A macro, not a base class, so the classes stay aggregates.)
#pragma once
#include <cstdint>

#include <glm/glm.hpp>

#define CV_GLSL_DOUBLE_TYPES     \
  using Number = double;         \
  using vec2 = glm::dvec2;       \
  using vec3 = glm::dvec3;       \
  using vec4 = glm::dvec4;       \
  using mat4 = glm::dmat4;       \
  using ivec2 = glm::ivec2;      \
  using ivec3 = glm::ivec3;      \
  using uint = uint32_t

#define IN(x) const x&
#define OUT(x) x&
#define INOUT(x) x&
