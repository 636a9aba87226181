// AVG construction in a single pass (param voxeliser=single), resolve:
// the fixed-point sums of avg_vox1.frag into the two 3D textures the
// other passes read (sum of normals, count; sum of colours, count), every
// voxel written (empty ones with zeros).
#include "avg_bindings.h"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(std430, binding = AVG_SSBO_VOX_SUMS) readonly buffer AvgVoxSums { int avg_sums[]; };
layout(rgba32f, binding = 0) uniform writeonly image3D u_normal;
layout(rgba32f, binding = 1) uniform writeonly image3D u_colour;

uniform int u_grid_n;

void main()
{
    ivec3 v = ivec3(gl_GlobalInvocationID);
    int n = u_grid_n;
    if (any(greaterThanEqual(v, ivec3(n))))
        return;
    int at = 8 * ((v.z * n + v.y) * n + v.x);
    float count = float(avg_sums[at + 3]);
    vec3 nrm = vec3(avg_sums[at + 0], avg_sums[at + 1], avg_sums[at + 2]) / AVG_VOX_FIXED;
    vec3 col = vec3(avg_sums[at + 4], avg_sums[at + 5], avg_sums[at + 6]) / AVG_VOX_FIXED;
    imageStore(u_normal, v, vec4(nrm, count));
    imageStore(u_colour, v, vec4(col, count));
}
