#version 450
// The floor every warp is measured against: imageLoad -> imageStore, nothing else.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) uniform readonly image2D source;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D target;
layout(push_constant) uniform Push { uvec4 sizes; } pc;
void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (id.x >= int(pc.sizes.z) || id.y >= int(pc.sizes.w)) return;
    imageStore(target, id, imageLoad(source, id));
}
