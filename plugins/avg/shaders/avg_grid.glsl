// The Approximate Visibility Grid (§III-A/B): triangle-box overlap for the
// voxeliser, and lookups and ray marching for the tracer. Grid space is in
// voxel units with the grid's corner at the origin: voxel (i, j, k) is the
// box [i, i+1] x [j, j+1] x [k, k+1].
#ifndef AVG_GRID_GLSL
#define AVG_GRID_GLSL

// Separating-axis test (Akenine-Moeller 2001) of triangle p0 p1 p2 against
// the box centre +- hext.
bool avg_triangle_box(vec3 p0, vec3 p1, vec3 p2, vec3 centre, vec3 hext)
{
    vec3 v0 = p0 - centre, v1 = p1 - centre, v2 = p2 - centre;
    vec3 e[3] = vec3[3](v1 - v0, v2 - v1, v0 - v2);
    // The box's own axes.
    if (max(v0.x, max(v1.x, v2.x)) < -hext.x || min(v0.x, min(v1.x, v2.x)) > hext.x) return false;
    if (max(v0.y, max(v1.y, v2.y)) < -hext.y || min(v0.y, min(v1.y, v2.y)) > hext.y) return false;
    if (max(v0.z, max(v1.z, v2.z)) < -hext.z || min(v0.z, min(v1.z, v2.z)) > hext.z) return false;
    // The triangle's plane.
    vec3 n = cross(e[0], e[1]);
    float r = dot(hext, abs(n));
    float s = dot(n, v0);
    if (s > r || s < -r) return false;
    // The nine edge x axis cross products.
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            vec3 axis = vec3(0.0);
            axis[(j + 1) % 3] = -e[i][(j + 2) % 3];
            axis[(j + 2) % 3] = e[i][(j + 1) % 3];
            // axis = unit_j x e_i
            float a0 = dot(axis, v0), a1 = dot(axis, v1), a2 = dot(axis, v2);
            float rad = dot(hext, abs(axis));
            if (min(a0, min(a1, a2)) > rad || max(a0, max(a1, a2)) < -rad) return false;
        }
    }
    return true;
}

#ifndef AVG_NO_GRID_SAMPLERS
uniform vec3 u_grid_origin;
uniform float u_grid_h;
uniform int u_grid_n;
layout(binding = AVG_UNIT_NORMAL) uniform sampler3D u_grid_normal;
layout(binding = AVG_UNIT_COLOUR) uniform sampler3D u_grid_colour;

vec3 avg_to_grid(vec3 world) { return (world - u_grid_origin) / u_grid_h; }
vec3 avg_to_world(vec3 g) { return g * u_grid_h + u_grid_origin; }

// A voxel is occupied where any triangle wrote into it (count > 0).
bool avg_occupied(ivec3 c) { return texelFetch(u_grid_normal, c, 0).w > 0.0; }
// Normalised (average) normal of the voxel; zero when the sum cancels.
vec3 avg_normal(ivec3 c)
{
    vec3 s = texelFetch(u_grid_normal, c, 0).xyz;
    float l = length(s);
    return l > 1e-6 ? s / l : vec3(0.0);
}
// Average colour of the triangles in the voxel.
vec3 avg_colour(ivec3 c)
{
    vec4 s = texelFetch(u_grid_colour, c, 0);
    return s.w > 0.0 ? s.rgb / s.w : vec3(0.0);
}

// Marches the ray o + t d (grid space, d unit, t >= 0) voxel by voxel
// (Amanatides-Woo traversal: every voxel the ray passes is visited) until
// an occupied voxel. On a hit: the voxel, and the ray parameters where the
// ray enters and leaves it.
bool avg_march(vec3 o, vec3 d, out ivec3 cell, out float t_in, out float t_out)
{
    float n = float(u_grid_n);
    vec3 inv = 1.0 / d; // +-inf on axis-parallel rays is what the slab test wants
    vec3 ta = (vec3(0.0) - o) * inv, tb = (vec3(n) - o) * inv;
    vec3 tmin3 = min(ta, tb), tmax3 = max(ta, tb);
    float t0 = max(max(tmin3.x, tmin3.y), max(tmin3.z, 0.0));
    float t1 = min(min(tmax3.x, tmax3.y), tmax3.z);
    if (!(t0 <= t1))
        return false;
    vec3 p = o + d * t0;
    cell = clamp(ivec3(floor(p)), ivec3(0), ivec3(u_grid_n - 1));
    ivec3 step = ivec3(sign(d));
    vec3 next = vec3(cell) + max(vec3(step), vec3(0.0));
    vec3 tnext = mix((next - o) * inv, vec3(1e30), equal(step, ivec3(0)));
    vec3 tdelta = mix(abs(inv), vec3(1e30), equal(step, ivec3(0)));
    float t = t0;
    for (int i = 0; i < 4 * u_grid_n; i++) {
        float te = min(min(tnext.x, tnext.y), tnext.z);
        if (avg_occupied(cell)) {
            t_in = t;
            t_out = min(te, t1);
            return true;
        }
        if (te >= t1)
            return false;
        t = te;
        if (tnext.x <= tnext.y && tnext.x <= tnext.z) {
            cell.x += step.x;
            tnext.x += tdelta.x;
        } else if (tnext.y <= tnext.z) {
            cell.y += step.y;
            tnext.y += tdelta.y;
        } else {
            cell.z += step.z;
            tnext.z += tdelta.z;
        }
        if (any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, ivec3(u_grid_n))))
            return false;
    }
    return false;
}
#endif
#endif
