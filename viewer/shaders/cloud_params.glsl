// CloudParams: the std140 uniform block of the cloud, ground and shadow passes, shared with C++.
// Every member is a vec4, so the std140 layout is the tight C++ layout: the C++ side includes this
// file twice (float for the GPU block, double for the CPU reference) and static_asserts the size
// (filament UibStructs.h pattern; see include/cloudviewer/params.h). Positions are relative to the
// camera (metres), so a camera kilometres from the origin does not lose float precision.
struct CloudParams {
  vec4 volume_min;     // xyz: volume min corner relative to the camera (m); w: voxel size (m)
  vec4 volume_size;    // xyz: volume extent (m); w: 1 when x and z wrap (tileable texture)
  vec4 volume_dims;    // xyz: voxel counts; w: 1 when G/B/A detail channels are present
  vec4 occ_dims;       // xyz: coarse occupancy cells; w: coarse cell edge (voxels)
  vec4 sun_dir;        // xyz: unit vector toward the sun; w: sun radiance scale
  vec4 sun_color;      // rgb: sun colour; w: ambient scale
  vec4 ambient_color;  // rgb: ambient (sky) radiance colour; w: single-scattering albedo
  vec4 medium;         // x: sigma_t per metre at density 1; y: detail erosion [0,1]; z: density multiplier; w: powder c
  vec4 march;          // x: small step (m); y: small steps per large step (integer); z: max distance (m); w: max iterations
  vec4 march2;         // x: adaptive on; y: adaptive start distance (m); z: adaptive growth (1/m); w: occupancy skipping on
  vec4 light;          // x: 0 off, 1 light march, 2 light march skipping empty cells; y: samples; z: first step (m); w: step growth
  vec4 phase;          // x: 0 isotropic ("none"), 1 Henyey-Greenstein, 2 Mie table; y: HG g; z: Mie table size; w: powder strength
  vec4 control;        // x: jitter on; y: frame index; z: exact (texelFetch) trilinear filtering; w: output 0 radiance, 1 transmittance
  vec4 ground;         // x: ground height relative to camera (m); y: ground albedo; z: ground on; w: ground half-extent (m)
  vec4 camera_world;   // xyz: camera world position modulo 1024 m (ground pattern phase); w: shadow march samples
  vec4 sky;            // rgb: zenith sky radiance; w: sun disc radiance scale
  // Layer mode (the tileable texture repeated over a spherical shell; parabolic Earth, see
  // layer_altitude): all distances in metres, horizontal offsets already reduced modulo their period.
  vec4 layer;          // x: 1 in layer mode; y: layer bottom altitude; z: layer top altitude; w: Earth radius
  vec4 layer2;         // x: camera altitude above the ground; y, z: camera x, z modulo the tile; w: unused
  vec4 layer3;         // x, z: tile size in x and z; y: unused; w: coverage map period (m)
  vec4 layer4;         // x, y: camera x, z modulo the coverage period; z: coverage bias; w: cloud type (-1 = map)
};
