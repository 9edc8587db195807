// Everything a pass that marches the clouds needs: the GLSL-only parameter blocks and bindings,
// then the cloud maths the CPU reference compiles too (cloud_math.glsl).
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "cloud_params.glsl"
#include "modes.glsl"
#include "frame_block.glsl"
#include "cloud_bindings.glsl"
#include "atmosphere_params.glsl"
#include "atmosphere_bindings.glsl"
#include "cloud_math.glsl"
