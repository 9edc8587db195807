// Everything an atmosphere pass needs, in dependency order (src/atmosphere.cpp includes the same
// shared headers inside its C++ class).
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "atmosphere_params.glsl"
#include "atmosphere_bindings.glsl"
#include "atmosphere.glsl"
