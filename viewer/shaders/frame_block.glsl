// FrameBlock: per-frame camera and post parameters (std140; C++ mirror in include/cloudviewer/params.h).
layout(std140, binding = CV_BINDING_FRAME) uniform FrameBlock {
  mat4 u_inv_view_proj;  // camera-relative world <- clip
  mat4 u_view_proj;      // clip <- camera-relative world
  vec4 u_viewport;       // xy: full-resolution size in pixels; zw: bloom (half) size
  vec4 u_post;           // x: exposure; y: tone map operator (CV_TONEMAP_*); z: bloom strength; w: bloom threshold
  mat4 u_prev_view_proj; // temporal: the previous frame's clip <- this frame's camera-relative world
  vec4 u_temporal;       // temporal: x history valid; y camera and clouds still (read by no shader: the
                         // renderer runs clouds_sparse_held for such frames; kept for the std140 layout);
                         // zw this frame's 4x4 block offset
};
