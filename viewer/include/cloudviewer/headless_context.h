// A headless OpenGL 4.5 context through EGL, for --headless, the tests and the bench.
#pragma once
#include <string>

namespace cloudviewer {

/// A headless OpenGL 4.5 core context: EGL device platform when a hardware device is present
/// (NVIDIA), Mesa surfaceless otherwise (CLOUDVIEWER_EGL=device|surfaceless forces one). Throws
/// GlError when none can be created.
class HeadlessContext {
 public:
  HeadlessContext();
  ~HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;
  const std::string& description() const { return description_; }
  void make_current();

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string description_;
};

}  // namespace cloudviewer
