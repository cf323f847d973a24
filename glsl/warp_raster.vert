#version 450
// One triangle that covers the whole framebuffer: the rasterizer then runs the fragment
// shader once per output pixel, which on lavapipe costs less per pixel than a compute
// invocation (see glsl/warp_raster.frag).

void main() {
    vec2 corner = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
