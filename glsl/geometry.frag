#version 450
// The geometry path's outputs with depth and range as interpolated (a pinhole render, where
// that is exact, or a lens whose depth and range are not asked for): glsl/include/
// geometry_outputs.glsl.
#extension GL_GOOGLE_include_directive : require

#include "geometry_outputs.glsl"
