// The renderers, one include for the programs around them: the GL renderer, the CPU reference and
// path tracer, the headless context. Each concept has its own header; this one declares nothing.
#pragma once
#include "cloudviewer/cpu_renderer.h"
#include "cloudviewer/frame_images.h"
#include "cloudviewer/gl_renderer.h"
#include "cloudviewer/headless_context.h"
#include "cloudviewer/ms_diffusion.h"
#include "cloudviewer/shader_source.h"
