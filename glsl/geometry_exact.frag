#version 450
// The geometry path's outputs with depth and range exact per pixel through the lens
// (glsl/include/geometry_outputs.glsl): the camera's inverse model is compiled in, so only a
// pipeline that writes depth or range through a lens uses this module.
#extension GL_GOOGLE_include_directive : require
// Per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model
#define VKL_EXACT_DEPTH

#include "geometry_outputs.glsl"
