// VPL tracing through the AVG (§III-B, Fig. 3). One invocation per light
// path i; the path owns VPL slots i (B + 1) .. i (B + 1) + B: slot 0 the VPL
// on the light (Keller's instant radiosity: it carries the direct light),
// slot k the VPL at the k-th hit. Unused slots keep power 0.
//  - light choice: the stratified number (i + 0.5) / paths in the CDF of the
//    lights' power (area lights as one group, the emitter CDF inside it);
//  - area lights: a point uniform on the chosen emissive triangle and a
//    cosine-distributed direction (quasi-random pairs 0 and 1) about its
//    front normal, or for a double-sided emitter about the face the path's
//    parity picks;
//  - point lights: a uniform direction; spot lights: uniform in the cone
//    (their VPLs' cover and share are set on the CPU, avg.c punctual_parts);
//  - marching through the grid to the first voxel holding a normal; the
//    VPL's colour is the voxel's average colour, its normal the voxel's
//    average normal turned toward the ray, its position a random distance
//    into the voxel along the ray (pair 2k+1 .x);
//  - next bounce: cosine sampling about that normal (pair 2k), Russian
//    roulette with survival max(colour) (pair 2k+1 .y), up to B hits.
#include "avg_bindings.h"
#define AVG_UNIT_NORMAL AVG_TEX_GRID_NORMAL
#define AVG_UNIT_COLOUR AVG_TEX_GRID_COLOUR
#include "scene.glsl"
#include "sampling.glsl"
#include "avg_grid.glsl"
#include "avg_vpl.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = AVG_SSBO_SLOTS) writeonly buffer AvgSlots { AvgVpl slots[]; };

uniform uint u_paths;
uniform uint u_bounces;
uniform uint u_qr_mask;
uniform uint u_seed; // the run's seed: other seeds, other (equally fixed) VPLs
uniform float u_offset;          // ray origins move this many voxels along the normal
uniform int u_light_count;       // entries: 0 = all area lights, 1 + l = punctual light l
uniform float u_light_cdf[65];
uniform float u_light_pdf[65];

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= u_paths)
        return;
    uint base = i * (u_bounces + 1u);
    AvgVpl none;
    none.position = vec3(0.0); none.kind = 0u; none.normal = vec3(0.0, 1.0, 0.0); none.cos_inner = 0.0;
    none.power = vec3(0.0); none.cos_outer = 0.0; none.spot_dir = vec3(0.0); none.range = 0.0;
    for (uint k = 0u; k <= u_bounces; k++)
        slots[base + k] = none;
    if (u_light_count <= 0)
        return;

    float N = float(u_paths);
    float u = (float(i) + 0.5) / N;
    int l = 0;
    while (l < u_light_count - 1 && u_light_cdf[l] <= u)
        l++;
    float pl = u_light_pdf[l];
    if (!(pl > 0.0))
        return;
    float lo = l > 0 ? u_light_cdf[l - 1] : 0.0;

    AvgVpl v = none;
    vec3 origin, dir, flux, axis;
    vec2 q0 = avg_qr(i, 0u, u_qr_mask, u_seed), q1 = avg_qr(i, 1u, u_qr_mask, u_seed);
    if (l == 0) {
        uint e = gi_emitter_find(clamp((u - lo) / pl, 0.0, GI_ONE_MINUS_EPSILON));
        GiEmitter em = gi_emitters[e];
        vec3 p0, p1, p2;
        gi_triangle_world(em.triangle, p0, p1, p2);
        vec3 bc = gi_sample_uniform_triangle(q0.x, q0.y);
        vec3 ng = cross(p1 - p0, p2 - p0);
        float area = 0.5 * length(ng);
        if (!(area > 0.0) || !(em.pdf > 0.0))
            return;
        GiMaterial lm = gi_materials[gi_triangle_material(em.triangle)];
        axis = ng / (2.0 * area);
        float pdf_area = pl * em.pdf / area;
        v.position = bc.x * p0 + bc.y * p1 + bc.z * p2;
        v.power = lm.emission * GI_PI / (pdf_area * N);
        // A double-sided emitter emits from both faces (glTF doubleSided):
        // the path leaves from the face its parity picks, at twice the
        // power, so that its VPL (one hemisphere, one shadow map) and its
        // bounces cover both sides.
        bool two = (lm.flags & GI_MATERIAL_DOUBLE_SIDED) != 0u;
        if (two) {
            v.power *= 2.0;
            if ((i & 1u) != 0u)
                axis = -axis;
        }
        v.kind = AVG_VPL_DIFFUSE | (two ? 0x10000u : 0u);
        v.normal = axis;
        flux = v.power;
        dir = gi_to_world(gi_sample_cosine_hemisphere(q1.x, q1.y), axis);
        origin = avg_to_grid(v.position) + axis * u_offset;
    } else {
        GiLight L = gi_lights[l - 1];
        vec3 I = L.intensity / (pl * N);
        v.position = L.position;
        v.range = L.range;
        v.spot_dir = L.direction;
        bool spot = L.type == GI_LIGHT_SPOT;
        v.kind = spot ? AVG_VPL_SPOT : AVG_VPL_POINT;
        v.cos_inner = L.cos_inner;
        v.cos_outer = L.cos_outer;
        // The light's own intensity and its entry in the kind: the CPU
        // (avg.c, punctual_parts) gives each VPL of the light the part of
        // its directions that one shadow map covers and its share.
        v.normal = spot ? L.direction : vec3(0.0, 1.0, 0.0);
        v.power = L.intensity;
        v.kind |= uint(l) << 24;
        if (spot) {
            vec3 w = gi_to_world(gi_sample_uniform_cone(q1.x, q1.y, L.cos_outer), L.direction);
            dir = w;
            flux = I * gi_spot_falloff(dot(w, L.direction), L.cos_inner, L.cos_outer) /
                   gi_uniform_cone_pdf(L.cos_outer);
        } else {
            dir = gi_sample_uniform_sphere(q1.x, q1.y);
            flux = I / gi_uniform_sphere_pdf();
        }
        origin = avg_to_grid(v.position);
    }
    slots[base] = v;

    for (uint k = 1u; k <= u_bounces; k++) {
        ivec3 cell;
        float t_in, t_out;
        if (!avg_march(origin, dir, cell, t_in, t_out))
            return;
        vec2 qp = avg_qr(i, 2u * k + 1u, u_qr_mask, u_seed);
        vec3 x = origin + dir * mix(t_in, t_out, qp.x); // pushed into the voxel
        vec3 c = avg_colour(cell);
        vec3 n = avg_normal(cell);
        if (dot(n, n) == 0.0)
            n = -dir;
        if (dot(n, dir) > 0.0)
            n = -n;
        AvgVpl h = none;
        h.position = avg_to_world(x);
        h.kind = AVG_VPL_DIFFUSE | (k << 8);
        h.normal = n;
        h.power = flux * c;
        slots[base + k] = h;
        if (k == u_bounces)
            return;
        float q = min(max(c.r, max(c.g, c.b)), 1.0);
        if (!(qp.y < q))
            return;
        flux *= c / q;
        vec2 qd = avg_qr(i, 2u * k, u_qr_mask, u_seed);
        dir = gi_to_world(gi_sample_cosine_hemisphere(qd.x, qd.y), n);
        origin = x + n * u_offset;
    }
}
