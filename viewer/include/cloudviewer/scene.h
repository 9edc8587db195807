// What a frame is made of, one include for the programs around it: the input, the prepared volume
// and its distance field, camera and sun, the Mie table, the coverage map and the frame set-up.
// Each concept has its own header; this one declares nothing.
#pragma once
#include "cloudviewer/camera.h"
#include "cloudviewer/coverage_map.h"
#include "cloudviewer/distance_field.h"
#include "cloudviewer/frame.h"
#include "cloudviewer/input.h"
#include "cloudviewer/memory_budget.h"
#include "cloudviewer/mie_table.h"
#include "cloudviewer/nano_atlas.h"
#include "cloudviewer/prepared_volume.h"
