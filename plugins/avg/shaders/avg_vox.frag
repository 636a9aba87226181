// AVG construction (§III-A), fragment stage: adds the triangle's normal and
// colour (and a count of 1 in alpha) to the voxel with additive blending;
// readers normalise by the count. In the conservative mode a fragment is
// kept only where the triangle overlaps the voxel's box (separating axes).
#define AVG_NO_GRID_SAMPLERS
#include "avg_grid.glsl"

flat in vec3 g_normal;
flat in vec3 g_colour;
flat in vec3 g_p0;
flat in vec3 g_p1;
flat in vec3 g_p2;

uniform int u_mode;

layout(location = 0) out vec4 o_normal;
layout(location = 1) out vec4 o_colour;

void main()
{
    if (u_mode == 0) {
        vec3 centre = vec3(floor(gl_FragCoord.xy) + 0.5, float(gl_Layer) + 0.5);
        if (!avg_triangle_box(g_p0, g_p1, g_p2, centre, vec3(0.5 + 1e-4)))
            discard;
    }
    o_normal = vec4(g_normal, 1.0);
    o_colour = vec4(g_colour, 1.0);
}
