// Headless OpenGL 4.5 core context through EGL: the device platform (EGL_EXT_platform_device) on a
// hardware device such as an NVIDIA GPU, else Mesa's surfaceless platform (llvmpipe or a Mesa
// driver). No window system, no display server.
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "cloudviewer/errors.h"
#include "cloudviewer/renderer.h"

namespace cloudviewer {
namespace {

bool has_ext(const char* list, const char* ext) {
  if (!list) return false;
  size_t n = std::strlen(ext);
  for (const char* p = list; (p = std::strstr(p, ext)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

std::string egl_error_string(EGLint e) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "0x%04X", unsigned(e));
  return buf;
}

}  // namespace

HeadlessContext::HeadlessContext() {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!client) throw GlError("EGL: no client extensions (libEGL missing or too old)");
  const char* force = std::getenv("CLOUDVIEWER_EGL");
  std::string want = force ? force : "";
  EGLDisplay dpy = EGL_NO_DISPLAY;
  std::string how;
  // 1. Device platform, preferring a hardware device over Mesa's software device.
  if (want != "surfaceless" && has_ext(client, "EGL_EXT_device_enumeration") &&
      has_ext(client, "EGL_EXT_platform_device")) {
    EGLint count = 0;
    eglQueryDevicesEXT(0, nullptr, &count);
    std::vector<EGLDeviceEXT> devices(size_t(count > 0 ? count : 0));
    if (count > 0) eglQueryDevicesEXT(count, devices.data(), &count);
    for (EGLDeviceEXT dev : devices) {
      const char* dext = eglQueryDeviceStringEXT(dev, EGL_EXTENSIONS);
      bool software = has_ext(dext, "EGL_MESA_device_software");
      if (software && want != "device") continue;
      EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, dev, nullptr);
      if (d == EGL_NO_DISPLAY) continue;
      EGLint major = 0, minor = 0;
      if (!eglInitialize(d, &major, &minor)) continue;
      dpy = d;
      how = std::string("EGL device platform") + (software ? " (software device)" : "");
      break;
    }
  }
  // 2. Mesa surfaceless.
  if (dpy == EGL_NO_DISPLAY && want != "device" && has_ext(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor)) {
      dpy = d;
      how = "EGL Mesa surfaceless platform";
    }
  }
  if (dpy == EGL_NO_DISPLAY)
    throw GlError("EGL: could not open a headless display (neither EGL_EXT_platform_device nor "
                  "EGL_MESA_platform_surfaceless worked; install libegl-mesa0 and libgl1-mesa-dri)");
  if (!eglBindAPI(EGL_OPENGL_API)) throw GlError("EGL: eglBindAPI(EGL_OPENGL_API) failed");
  EGLConfig config = nullptr;
  EGLint n = 0;
  const EGLint cfg_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  if (!eglChooseConfig(dpy, cfg_attribs, &config, 1, &n) || n < 1) config = nullptr;
  if (!config) {
    const EGLint any[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0, EGL_NONE};
    if (!eglChooseConfig(dpy, any, &config, 1, &n) || n < 1) config = nullptr;
  }
  const char* dext = eglQueryString(dpy, EGL_EXTENSIONS);
  if (!config && !has_ext(dext, "EGL_KHR_no_config_context"))
    throw GlError("EGL: no OpenGL-renderable config");
  const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, config ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attribs);
  if (ctx == EGL_NO_CONTEXT)
    throw GlError("EGL: could not create an OpenGL 4.5 core context (error " + egl_error_string(eglGetError()) + ")");
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    eglDestroyContext(dpy, ctx);
    throw GlError("EGL: eglMakeCurrent without a surface failed (error " + egl_error_string(eglGetError()) + ")");
  }
  display_ = dpy;
  context_ = ctx;
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  description_ = how + ", " + (r ? r : "?") + ", " + (v ? v : "?");
}

void HeadlessContext::make_current() {
  eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE, static_cast<EGLContext>(context_));
}

HeadlessContext::~HeadlessContext() {
  EGLDisplay dpy = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(dpy, static_cast<EGLContext>(context_));
  // No eglTerminate: Mesa shares the display between contexts created in one process (tests).
}

}  // namespace cloudviewer
