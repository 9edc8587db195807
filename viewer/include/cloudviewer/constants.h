// The constants shared with the GLSL passes (mode codes, binding points, fixed sizes), from the one
// file both languages read: shaders/constants.glsl. C++ code uses these instead of literals.
#pragma once
#include "../../shaders/constants.glsl"
