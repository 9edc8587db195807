// C++ mirrors of the std140 uniform blocks. CloudParams is declared once, in
// shaders/cloud_params.glsl, and included here twice: float (the GPU block) and double (the CPU
// reference). Every member is a vec4, so std140 and the C++ layout agree; the sizes are asserted.
#pragma once
#include <glm/glm.hpp>

namespace cloudviewer {

namespace gpu {
using vec4 = glm::vec4;
#include "../../shaders/cloud_params.glsl"
}  // namespace gpu

namespace ref {
using vec4 = glm::dvec4;
#include "../../shaders/cloud_params.glsl"
}  // namespace ref

constexpr int kCloudParamsVec4 = 20;
static_assert(sizeof(gpu::CloudParams) == kCloudParamsVec4 * 16, "std140 CloudBlock size");
static_assert(sizeof(ref::CloudParams) == kCloudParamsVec4 * 32, "double CloudParams size");

/// std140 FrameBlock (shaders/bindings.glsl, binding 1).
struct FrameBlock {
  glm::mat4 inv_view_proj;  ///< camera-relative world <- clip
  glm::mat4 view_proj;      ///< clip <- camera-relative world
  glm::vec4 viewport;       ///< xy: full size (px); zw: bloom size (px)
  glm::vec4 post;           ///< x: exposure; y: tone map operator; z: bloom strength; w: bloom threshold
};
static_assert(sizeof(FrameBlock) == 160, "std140 FrameBlock size");

/// Converts the double parameters to the GPU block (member-wise, all vec4).
inline gpu::CloudParams to_gpu(const ref::CloudParams& d) {
  gpu::CloudParams f;
  const glm::dvec4* src = reinterpret_cast<const glm::dvec4*>(&d);
  glm::vec4* dst = reinterpret_cast<glm::vec4*>(&f);
  for (int i = 0; i < kCloudParamsVec4; ++i) dst[i] = glm::vec4(src[i]);
  return f;
}
/// The double parameters the GPU actually sees (each value rounded to float), for the reference.
inline ref::CloudParams rounded_to_float(const ref::CloudParams& d) {
  gpu::CloudParams f = to_gpu(d);
  ref::CloudParams r;
  const glm::vec4* src = reinterpret_cast<const glm::vec4*>(&f);
  glm::dvec4* dst = reinterpret_cast<glm::dvec4*>(&r);
  for (int i = 0; i < kCloudParamsVec4; ++i) dst[i] = glm::dvec4(src[i]);
  return r;
}

}  // namespace cloudviewer
