#version 450
// Heidrich et al. Sec. 3.1 and 3.5: one cell's perspective image is morphed onto the film grid its
// rays were shot from (texture coordinates = where the rays meet the virtual image plane),
// and weighted by the radiometric term W_i(x') at the grid vertices, interpolated linearly
// between them ("Gouraud-shaded grid of textured polygons having W_i as alpha").

layout(push_constant) uniform FilmPush {
    // Film width, height (pixels), unused, unused.
    vec4 film_size;
    // Which channels this draw adds to: Heidrich et al. traced one wavelength for all three;
    // with chromatic aberration each channel has its own projections.
    vec4 channel_mask;
} push;

layout(location = 0) in vec2 film_px;  // OpenCV pixel coordinates on the film
layout(location = 1) in vec2 cell_uv;  // 0..1 across the cell's render
layout(location = 2) in float weight;

layout(location = 0) out vec2 v_uv;
layout(location = 1) noperspective out float v_weight;

void main() {
    vec2 ndc = (film_px + 0.5) / push.film_size.xy * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.0, 1.0);
    v_uv = cell_uv;
    v_weight = weight;
}
