// What every renderer returns: the display image and the linear HDR image of one frame.
#pragma once
#include "cloudviewer/image.h"

namespace cloudviewer {

struct FrameImages {
  Image display;  ///< sRGB-encoded tone-mapped values in [0,1]
  Image linear;   ///< scene-linear HDR radiance (output=transmittance: T in RGB)
};

}  // namespace cloudviewer
