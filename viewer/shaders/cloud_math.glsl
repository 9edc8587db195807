// The cloud maths both renderers compile, in dependency order (see march.glsl for what each header
// holds): the GL passes through cloud_headers.glsl, after its GLSL-only bindings; the CPU reference
// (src/cpu/cpu_renderer.cpp) inside its C++ class. The one list of them.
#include "common.glsl"
#include "volume_nanovdb.glsl"
#include "phase_lobes.glsl"
#include "phase.glsl"
#include "cloud_type.glsl"
#include "erosion.glsl"
#include "motion.glsl"
#include "curl_distortion.glsl"
#include "medium.glsl"
#include "atmosphere.glsl"
#include "sky_atmosphere.glsl"
#include "lighting.glsl"
#include "march.glsl"
#include "sky.glsl"
#include "compose.glsl"
#include "temporal.glsl"
