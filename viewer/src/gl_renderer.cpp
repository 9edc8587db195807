// OpenGL 4.5 deferred renderer: ground pass (HDR + distance), full-screen cloud pass, bloom
// (half resolution, separable Gaussian), tone map + sRGB. GPU timer queries around every pass.
#include <array>
#include <vector>
#include <cstring>

#include <epoxy/gl.h>

#include "cloudviewer/errors.h"
#include "cloudviewer/renderer.h"

namespace cloudviewer {
namespace {

GLuint make_texture_2d(GLenum internal, int w, int h) {
  GLuint t;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, internal, w, h);
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return t;
}

void check_fbo(GLuint fbo, const char* what) {
  GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw GlError(std::string("framebuffer '") + what + "' incomplete (status 0x" + std::to_string(status) + ")");
}

GLuint link_program(const ShaderSource& src, const std::string& vs, const std::string& fs) {
  GLuint v = compile_shader_stage(GL_VERTEX_SHADER, src, vs);
  GLuint f = 0;
  try {
    f = compile_shader_stage(GL_FRAGMENT_SHADER, src, fs);
  } catch (...) {
    glDeleteShader(v);
    throw;
  }
  GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    glGetProgramInfoLog(p, sizeof(log), nullptr, log);
    glDeleteProgram(p);
    throw ShaderError("shader link error (" + vs + " + " + fs + "):\n" + log, fs, 0);
  }
  return p;
}

constexpr int kGroundGrid = 96;  // ground cells per side in layer mode (curved Earth)

}  // namespace

struct GlRenderer::Impl {
  ShaderSource shaders;
  GLuint prog_ground = 0, prog_cloud = 0, prog_bright = 0, prog_blur = 0, prog_tonemap = 0;
  GLuint tex_volume = 0, tex_occ = 0, tex_mie = 0, tex_coverage = 0;
  GLsizei ground_vertices = 0;
  GLuint ubo_cloud = 0, ubo_frame = 0;
  GLuint vao_empty = 0, vao_ground = 0, vbo_ground = 0;
  int w = 0, h = 0, bw = 0, bh = 0;
  GLuint fbo_scene = 0, tex_scene_color = 0, tex_scene_distance = 0, tex_scene_depth = 0;
  GLuint fbo_hdr = 0, tex_hdr = 0;
  GLuint fbo_bloom[2] = {0, 0}, tex_bloom[2] = {0, 0};
  GLuint fbo_final = 0, tex_display = 0, tex_linear = 0;
  std::array<GLuint, 5> queries{};
  bool have_volume = false;

  void delete_programs() {
    for (GLuint* p : {&prog_ground, &prog_cloud, &prog_bright, &prog_blur, &prog_tonemap})
      if (*p) glDeleteProgram(*p), *p = 0;
  }
  void build_programs() {
    GLuint g = 0, c = 0, b = 0, bl = 0, t = 0;
    try {
      g = link_program(shaders, "ground.vert", "ground.frag");
      c = link_program(shaders, "fullscreen.vert", "cloud.frag");
      b = link_program(shaders, "fullscreen.vert", "bloom_bright.frag");
      bl = link_program(shaders, "fullscreen.vert", "bloom_blur.frag");
      t = link_program(shaders, "fullscreen.vert", "tonemap.frag");
    } catch (...) {
      for (GLuint p : {g, c, b, bl, t})
        if (p) glDeleteProgram(p);
      throw;
    }
    delete_programs();
    prog_ground = g, prog_cloud = c, prog_bright = b, prog_blur = bl, prog_tonemap = t;
  }
  void delete_targets() {
    GLuint fbos[] = {fbo_scene, fbo_hdr, fbo_bloom[0], fbo_bloom[1], fbo_final};
    GLuint texs[] = {tex_scene_color, tex_scene_distance, tex_scene_depth, tex_hdr, tex_bloom[0], tex_bloom[1], tex_display, tex_linear};
    for (GLuint f : fbos)
      if (f) glDeleteFramebuffers(1, &f);
    for (GLuint t : texs)
      if (t) glDeleteTextures(1, &t);
    fbo_scene = fbo_hdr = fbo_bloom[0] = fbo_bloom[1] = fbo_final = 0;
    tex_scene_color = tex_scene_distance = tex_scene_depth = tex_hdr = tex_bloom[0] = tex_bloom[1] = tex_display = tex_linear = 0;
  }
  void resize(int width, int height) {
    if (width == w && height == h) return;
    delete_targets();
    w = width, h = height;
    bw = std::max(1, w / 2), bh = std::max(1, h / 2);
    tex_scene_color = make_texture_2d(GL_RGBA32F, w, h);
    tex_scene_distance = make_texture_2d(GL_R32F, w, h);
    tex_scene_depth = make_texture_2d(GL_DEPTH_COMPONENT32F, w, h);
    glCreateFramebuffers(1, &fbo_scene);
    glNamedFramebufferTexture(fbo_scene, GL_COLOR_ATTACHMENT0, tex_scene_color, 0);
    glNamedFramebufferTexture(fbo_scene, GL_COLOR_ATTACHMENT1, tex_scene_distance, 0);
    glNamedFramebufferTexture(fbo_scene, GL_DEPTH_ATTACHMENT, tex_scene_depth, 0);
    GLenum two[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(fbo_scene, 2, two);
    check_fbo(fbo_scene, "scene");
    tex_hdr = make_texture_2d(GL_RGBA32F, w, h);
    glCreateFramebuffers(1, &fbo_hdr);
    glNamedFramebufferTexture(fbo_hdr, GL_COLOR_ATTACHMENT0, tex_hdr, 0);
    check_fbo(fbo_hdr, "hdr");
    for (int i = 0; i < 2; ++i) {
      tex_bloom[i] = make_texture_2d(GL_RGBA32F, bw, bh);
      glCreateFramebuffers(1, &fbo_bloom[i]);
      glNamedFramebufferTexture(fbo_bloom[i], GL_COLOR_ATTACHMENT0, tex_bloom[i], 0);
      check_fbo(fbo_bloom[i], "bloom");
    }
    tex_display = make_texture_2d(GL_RGBA32F, w, h);
    tex_linear = make_texture_2d(GL_RGBA32F, w, h);
    glCreateFramebuffers(1, &fbo_final);
    glNamedFramebufferTexture(fbo_final, GL_COLOR_ATTACHMENT0, tex_display, 0);
    glNamedFramebufferTexture(fbo_final, GL_COLOR_ATTACHMENT1, tex_linear, 0);
    glNamedFramebufferDrawBuffers(fbo_final, 2, two);
    check_fbo(fbo_final, "final");
  }
  void fullscreen(GLuint prog, GLuint fbo, int vw, int vh) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, vw, vh);
    glUseProgram(prog);
    glBindVertexArray(vao_empty);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
};

GlRenderer::GlRenderer(ShaderSource shaders) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.shaders = std::move(shaders);
  m.build_programs();
  glCreateBuffers(1, &m.ubo_cloud);
  glNamedBufferStorage(m.ubo_cloud, sizeof(gpu::CloudParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateBuffers(1, &m.ubo_frame);
  glNamedBufferStorage(m.ubo_frame, sizeof(FrameBlock), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateVertexArrays(1, &m.vao_empty);
  glCreateVertexArrays(1, &m.vao_ground);
  glCreateBuffers(1, &m.vbo_ground);
  glNamedBufferStorage(m.vbo_ground, sizeof(float) * 3 * 6 * kGroundGrid * kGroundGrid, nullptr, GL_DYNAMIC_STORAGE_BIT);
  glVertexArrayVertexBuffer(m.vao_ground, 0, m.vbo_ground, 0, sizeof(float) * 3);
  glEnableVertexArrayAttrib(m.vao_ground, 0);
  glVertexArrayAttribFormat(m.vao_ground, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(m.vao_ground, 0, 0);
  glCreateQueries(GL_TIMESTAMP, GLsizei(m.queries.size()), m.queries.data());
  // Mie table (1D float texture, fetched by index and interpolated by hand).
  const std::vector<float>& mie = mie_phase_table();
  glCreateTextures(GL_TEXTURE_1D, 1, &m.tex_mie);
  glTextureStorage1D(m.tex_mie, 1, GL_R32F, GLsizei(mie.size()));
  glTextureSubImage1D(m.tex_mie, 0, 0, GLsizei(mie.size()), GL_RED, GL_FLOAT, mie.data());
  glTextureParameteri(m.tex_mie, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_mie, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  const std::vector<float>& cov = coverage_map();
  glCreateTextures(GL_TEXTURE_2D, 1, &m.tex_coverage);
  glTextureStorage2D(m.tex_coverage, 1, GL_RG32F, 256, 256);
  glTextureSubImage2D(m.tex_coverage, 0, 0, 0, 256, 256, GL_RG, GL_FLOAT, cov.data());
  glTextureParameteri(m.tex_coverage, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_coverage, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

GlRenderer::~GlRenderer() {
  Impl& m = *impl_;
  m.delete_programs();
  m.delete_targets();
  GLuint texs[] = {m.tex_volume, m.tex_occ, m.tex_mie, m.tex_coverage};
  for (GLuint t : texs)
    if (t) glDeleteTextures(1, &t);
  glDeleteBuffers(1, &m.ubo_cloud);
  glDeleteBuffers(1, &m.ubo_frame);
  glDeleteBuffers(1, &m.vbo_ground);
  glDeleteVertexArrays(1, &m.vao_empty);
  glDeleteVertexArrays(1, &m.vao_ground);
  glDeleteQueries(GLsizei(m.queries.size()), m.queries.data());
}

void GlRenderer::reload_shaders() { impl_->build_programs(); }

std::string GlRenderer::renderer_string() const {
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(r ? r : "?") + " / " + (v ? v : "?");
}

void GlRenderer::set_volume(const PreparedVolume& vol) {
  Impl& m = *impl_;
  if (m.tex_volume) glDeleteTextures(1, &m.tex_volume);
  if (m.tex_occ) glDeleteTextures(1, &m.tex_occ);
  GLint max3d = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
  for (int i = 0; i < 3; ++i)
    if (vol.dims[i] > max3d)
      throw InputError("volume dimension " + std::to_string(vol.dims[i]) + " exceeds GL_MAX_3D_TEXTURE_SIZE " + std::to_string(max3d));
  glCreateTextures(GL_TEXTURE_3D, 1, &m.tex_volume);
  glTextureStorage3D(m.tex_volume, 1, GL_RGBA32F, vol.dims[0], vol.dims[1], vol.dims[2]);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage3D(m.tex_volume, 0, 0, 0, 0, vol.dims[0], vol.dims[1], vol.dims[2], GL_RGBA, GL_FLOAT, vol.rgba.data());
  glTextureParameteri(m.tex_volume, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(m.tex_volume, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  GLint wrap_xz = vol.tiles ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  glTextureParameteri(m.tex_volume, GL_TEXTURE_WRAP_S, wrap_xz);
  glTextureParameteri(m.tex_volume, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTextureParameteri(m.tex_volume, GL_TEXTURE_WRAP_R, wrap_xz);
  std::vector<uint8_t> occ(vol.occ.size());
  for (size_t i = 0; i < occ.size(); ++i) occ[i] = vol.occ[i] ? 255 : 0;
  glCreateTextures(GL_TEXTURE_3D, 1, &m.tex_occ);
  glTextureStorage3D(m.tex_occ, 1, GL_R8, vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  glTextureSubImage3D(m.tex_occ, 0, 0, 0, 0, vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2], GL_RED, GL_UNSIGNED_BYTE, occ.data());
  glTextureParameteri(m.tex_occ, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_occ, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  m.have_volume = true;
  if (glGetError() != GL_NO_ERROR) throw GlError("uploading the volume textures failed (out of GPU memory?)");
}

void GlRenderer::render(const FrameSetup& f, GpuTimings* timings) {
  Impl& m = *impl_;
  if (!m.have_volume) throw GlError("GlRenderer::render before set_volume");
  m.resize(f.width, f.height);
  gpu::CloudParams cp = to_gpu(f.params);
  glNamedBufferSubData(m.ubo_cloud, 0, sizeof(cp), &cp);
  FrameBlock fb;
  fb.inv_view_proj = glm::mat4(f.inv_view_proj);
  fb.view_proj = glm::mat4(f.view_proj);
  fb.viewport = glm::vec4(m.w, m.h, m.bw, m.bh);
  fb.post = glm::vec4(float(f.settings.exposure), float(int(f.settings.tonemap)), float(f.settings.bloom),
                      float(f.settings.bloom_threshold));
  glNamedBufferSubData(m.ubo_frame, 0, sizeof(fb), &fb);
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, m.ubo_cloud);
  glBindBufferBase(GL_UNIFORM_BUFFER, 1, m.ubo_frame);
  glBindTextureUnit(0, m.tex_volume);
  glBindTextureUnit(1, m.tex_occ);
  glBindTextureUnit(2, m.tex_mie);
  glBindTextureUnit(5, m.tex_coverage);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_FRAMEBUFFER_SRGB);

  glQueryCounter(m.queries[0], GL_TIMESTAMP);
  // Ground pass: HDR radiance + distance, depth tested.
  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo_scene);
  glViewport(0, 0, m.w, m.h);
  const float zero[4] = {0, 0, 0, 0}, far_distance[4] = {1e30f, 0, 0, 0};
  glClearNamedFramebufferfv(m.fbo_scene, GL_COLOR, 0, zero);
  glClearNamedFramebufferfv(m.fbo_scene, GL_COLOR, 1, far_distance);
  const float one = 1.0f;
  glClearNamedFramebufferfv(m.fbo_scene, GL_DEPTH, 0, &one);
  if (f.params.ground.z > 0.5) {
    double y = f.params.ground.x, r = f.ground_half_extent;
    std::vector<float> verts;
    if (f.params.layer.x > 0.5) {
      // Curved Earth: altitude 0 of the parabolic model, y = -h_cam - (x^2 + z^2) / 2R.
      const int n = kGroundGrid;
      auto vertex = [&](int i, int j) {
        double x = -r + 2 * r * i / n, z = -r + 2 * r * j / n;
        verts.insert(verts.end(), {float(x), float(y - (x * x + z * z) / (2 * f.params.layer.w)), float(z)});
      };
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1);
          vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1);
        }
    } else {
      float fy = float(y), fr = float(r);
      verts = {-fr, fy, -fr, fr, fy, -fr, fr, fy, fr, -fr, fy, -fr, fr, fy, fr, -fr, fy, fr};
    }
    m.ground_vertices = GLsizei(verts.size() / 3);
    glNamedBufferSubData(m.vbo_ground, 0, GLsizeiptr(verts.size() * sizeof(float)), verts.data());
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glUseProgram(m.prog_ground);
    glBindVertexArray(m.vao_ground);
    glDrawArrays(GL_TRIANGLES, 0, m.ground_vertices);
    glDisable(GL_DEPTH_TEST);
  }
  glQueryCounter(m.queries[1], GL_TIMESTAMP);
  // Cloud pass.
  glBindTextureUnit(3, m.tex_scene_color);
  glBindTextureUnit(4, m.tex_scene_distance);
  m.fullscreen(m.prog_cloud, m.fbo_hdr, m.w, m.h);
  glQueryCounter(m.queries[2], GL_TIMESTAMP);
  // Bloom at half resolution.
  if (f.settings.bloom > 0) {
    glBindTextureUnit(3, m.tex_hdr);
    m.fullscreen(m.prog_bright, m.fbo_bloom[0], m.bw, m.bh);
    glUseProgram(m.prog_blur);
    glProgramUniform2i(m.prog_blur, 0, 1, 0);
    glBindTextureUnit(3, m.tex_bloom[0]);
    m.fullscreen(m.prog_blur, m.fbo_bloom[1], m.bw, m.bh);
    glProgramUniform2i(m.prog_blur, 0, 0, 1);
    glBindTextureUnit(3, m.tex_bloom[1]);
    m.fullscreen(m.prog_blur, m.fbo_bloom[0], m.bw, m.bh);
  }
  glQueryCounter(m.queries[3], GL_TIMESTAMP);
  glBindTextureUnit(3, m.tex_hdr);
  glBindTextureUnit(4, m.tex_bloom[0]);
  m.fullscreen(m.prog_tonemap, m.fbo_final, m.w, m.h);
  glQueryCounter(m.queries[4], GL_TIMESTAMP);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  GLenum err = glGetError();
  if (err != GL_NO_ERROR) throw GlError("OpenGL error 0x" + std::to_string(err) + " while rendering");
  if (timings) {
    GLuint64 t[5];
    for (int i = 0; i < 5; ++i) glGetQueryObjectui64v(m.queries[size_t(i)], GL_QUERY_RESULT, &t[i]);
    timings->ground_ms = double(t[1] - t[0]) * 1e-6;
    timings->cloud_ms = double(t[2] - t[1]) * 1e-6;
    timings->post_ms = double(t[4] - t[2]) * 1e-6;
    timings->total_ms = double(t[4] - t[0]) * 1e-6;
  }
}

FrameImages GlRenderer::read_back() {
  Impl& m = *impl_;
  FrameImages out{Image(m.w, m.h), Image(m.w, m.h)};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo_final);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, m.w, m.h, GL_RGBA, GL_FLOAT, out.display.rgba.data());
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, m.w, m.h, GL_RGBA, GL_FLOAT, out.linear.rgba.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  return out;
}

void GlRenderer::present(int ww, int wh) {
  Impl& m = *impl_;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo_final);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, m.w, m.h, 0, 0, ww, wh, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

Image GlRenderer::read_window(int ww, int wh) {
  Image img(ww, wh);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, ww, wh, GL_RGBA, GL_FLOAT, img.rgba.data());
  return img;
}

}  // namespace cloudviewer
