// Shared by the libFuzzer targets: an input is either accepted or refused with the typed input
// error (cloudgen::InputError, noise3d::InvalidParameter); any other exception is a bug, reported
// by aborting so libFuzzer saves the input.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>

#include "cloudgen/volume.h"
#include "noise3d/noise3d.h"

namespace fuzz {

inline int guarded(const std::function<void()>& body) {
  try {
    body();
  } catch (const cloudgen::InputError&) {
  } catch (const noise3d::InvalidParameter&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz: unexpected %s: %.300s\n", typeid(e).name(), e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "fuzz: unexpected non-standard exception\n");
    std::abort();
  }
  return 0;
}

}  // namespace fuzz
