// The viewer's CPU reference compiles the shaders' functions as members of a class (after
// Bruneton's reference/functions.cc): a class that includes shader headers opens with
// CV_GLSL_DOUBLE_TYPES (cloudgen/glsl_prelude.h, the one C++ prelude of the GLSL subset), and the
// parameter-qualifier macros below turn `IN(T)` / `OUT(T)` / `INOUT(T)` into references, so the
// shaders' functions become its members in double precision. The class defines the lookups each
// side implements (texel fetches). Include this header last: it defines IN, OUT and INOUT for the
// rest of the file. (A macro, not a base class, so the classes stay aggregates.)
#pragma once
#include "cloudgen/glsl_prelude.h"

#define IN(x) const x&
#define OUT(x) x&
#define INOUT(x) x&
