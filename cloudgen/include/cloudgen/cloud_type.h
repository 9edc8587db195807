// C++ side of cloud_type.glsl (the cloud-type height gradients shared with the viewer's shaders),
// compiled in double precision (cloudgen/glsl_prelude.h).
#pragma once
#include "cloudgen/glsl_prelude.h"

namespace cloudgen {
namespace cloud_type {

CV_GLSL_DOUBLE_TYPES;
CV_GLSL_BUILTINS;

#include "cloudgen/cloud_type.glsl"

}  // namespace cloud_type
}  // namespace cloudgen
