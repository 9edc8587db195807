// render.volume=nanovdb: where the shaders read the grids' words (cloud_bindings.glsl). 0: a
// shader storage buffer; 1: an RGBA32UI buffer texture, for grids larger than a storage block
// (128 MiB on llvmpipe). GlRenderer::set_volume replaces this file's text and rebuilds the
// programs when the choice changes: a run-time branch per word read cost 60% of the frame.
#define CV_NANOVDB_BUFFER_TEXTURE 0
