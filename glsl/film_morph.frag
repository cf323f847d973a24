#version 450
// Adds one cell's weighted slice of the light field into the film (additive blending into a
// float image: the accumulation buffer of Heidrich et al. Sec. 3.5).

layout(push_constant) uniform FilmPush {
    vec4 film_size;
    vec4 channel_mask;
} push;

layout(set = 0, binding = 0) uniform sampler2D cell_image;

layout(location = 0) in vec2 v_uv;
layout(location = 1) noperspective in float v_weight;

layout(location = 0) out vec4 out_radiance;

void main() {
    // Alpha collects the weight alone, whatever the scene's coverage: the relative
    // illumination of the film (its vignetting), which a plan without vignetting divides out.
    out_radiance = vec4(texture(cell_image, v_uv).rgb, 1.0) * (v_weight * push.channel_mask);
}
