// FrameBlock: per-frame camera and post parameters (std140; C++ mirror in include/cloudviewer/params.h).
layout(std140, binding = CV_BINDING_FRAME) uniform FrameBlock {
  mat4 u_inv_view_proj;  // camera-relative world <- clip
  mat4 u_view_proj;      // clip <- camera-relative world
  vec4 u_viewport;       // xy: full-resolution size in pixels; zw: bloom (half) size
  vec4 u_post;           // x: exposure; y: tone map operator (CV_TONEMAP_*); z: bloom strength; w: bloom threshold
};
