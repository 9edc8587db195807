// The volume storage the cloud programs are compiled for (cloud_bindings.glsl). CV_NANOVDB 0:
// the dense RGBA texture, 1: NanoVDB grids (render.volume=nanovdb), read from a shader storage
// buffer (CV_NANOVDB_BUFFER_TEXTURE 0) or, for grids larger than a storage block (128 MiB on
// llvmpipe), an RGBA32UI buffer texture (1); CV_NANOVDB_ATLAS 1: the grids' brick atlas instead
// (render.nanovdb_lookup=atlas: a 3D texture the texture unit filters, no tree or buffer reads).
// GlRenderer replaces this file's text and rebuilds the programs when the choice changes:
// run-time branches on the storage cost 60% of the nanovdb frame and made llvmpipe's dense
// programs 4x slower.
#define CV_NANOVDB 0
#define CV_NANOVDB_BUFFER_TEXTURE 0
#define CV_NANOVDB_ATLAS 0
