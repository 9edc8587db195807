// C++ mirrors of the std140 uniform blocks. CloudParams is declared once, in
// shaders/cloud_params.glsl, and included here twice: float (the GPU block) and double (the CPU
// reference). Its members come in 16-byte groups, so std140 and the C++ layout agree; the sizes are
// asserted here and the offsets against the driver's in the tests (ViewerGl.CloudBlockLayout...).
#pragma once
#include <glm/glm.hpp>

namespace cloudviewer {

namespace gpu {
using Number = float;
using vec3 = glm::vec3;
using vec4 = glm::vec4;
#include "../../shaders/cloud_params.glsl"
}  // namespace gpu

namespace ref {
using Number = double;
using vec3 = glm::dvec3;
using vec4 = glm::dvec4;
#include "../../shaders/cloud_params.glsl"
}  // namespace ref

/// Scalars in CloudParams: 39 groups of 16 bytes (std140), each a vec3 + one scalar or four scalars.
constexpr int kCloudParamsScalars = 156;
static_assert(sizeof(gpu::CloudParams) == kCloudParamsScalars * 4, "std140 CloudBlock size (no padding)");
static_assert(sizeof(ref::CloudParams) == kCloudParamsScalars * 8, "double CloudParams size (no padding)");
static_assert(sizeof(gpu::CloudParams) % 16 == 0, "std140 rounds a struct to 16 bytes");

/// std140 FrameBlock (shaders/frame_block.glsl, binding CV_BINDING_FRAME).
struct FrameBlock {
  glm::mat4 inv_view_proj;  ///< camera-relative world <- clip
  glm::mat4 view_proj;      ///< clip <- camera-relative world
  glm::vec4 viewport;       ///< xy: full size (px); zw: bloom size (px)
  glm::vec4 post;           ///< x: exposure; y: tone map operator (CV_TONEMAP_*); z: bloom strength; w: bloom threshold
  glm::mat4 prev_view_proj; ///< temporal: previous frame's clip <- this frame's camera-relative world
  glm::vec4 temporal;       ///< temporal: x history valid; y still (unread: clouds_sparse_held serves it); zw block offset
};
static_assert(sizeof(FrameBlock) == 240, "std140 FrameBlock size");

/// Converts the double parameters to the GPU block, scalar by scalar (both structs are arrays of
/// scalars without padding, asserted above).
inline gpu::CloudParams to_gpu(const ref::CloudParams& d) {
  gpu::CloudParams f;
  const double* src = reinterpret_cast<const double*>(&d);
  float* dst = reinterpret_cast<float*>(&f);
  for (int i = 0; i < kCloudParamsScalars; ++i) dst[i] = float(src[i]);
  return f;
}
/// The double parameters the GPU actually sees (each value rounded to float), for the reference.
inline ref::CloudParams rounded_to_float(const ref::CloudParams& d) {
  gpu::CloudParams f = to_gpu(d);
  ref::CloudParams r;
  const float* src = reinterpret_cast<const float*>(&f);
  double* dst = reinterpret_cast<double*>(&r);
  for (int i = 0; i < kCloudParamsScalars; ++i) dst[i] = double(src[i]);
  return r;
}

}  // namespace cloudviewer
