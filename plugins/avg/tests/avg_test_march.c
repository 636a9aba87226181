/* avg_tests march: rays marched through the AVG on the GPU (Bashford-
 * Rogers et al. 2011 §III-B, shaders/avg_grid.glsl's avg_march) against
 * Embree rays (gi/raytrace.h) in the same scene: the AVG hit voxel lies
 * within one voxel of the real hit. */
#include "avg_tests.h"

#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG

/* Closest point on triangle abc to p (Ericson, Real-Time Collision
 * Detection 5.1.5). */
static gi_vec3 closest_on_triangle(gi_vec3 p, gi_vec3 a, gi_vec3 b, gi_vec3 c)
{
    gi_vec3 ab = gi_v3_sub(b, a), ac = gi_v3_sub(c, a), ap = gi_v3_sub(p, a);
    float d1 = gi_v3_dot(ab, ap), d2 = gi_v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return a;
    gi_vec3 bp = gi_v3_sub(p, b);
    float d3 = gi_v3_dot(ab, bp), d4 = gi_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return gi_v3_add(a, gi_v3_scale(ab, d1 / (d1 - d3)));
    gi_vec3 cp = gi_v3_sub(p, c);
    float d5 = gi_v3_dot(ab, cp), d6 = gi_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return gi_v3_add(a, gi_v3_scale(ac, d2 / (d2 - d6)));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return gi_v3_add(b, gi_v3_scale(gi_v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    float denom = 1.0f / (va + vb + vc);
    return gi_v3_add(a, gi_v3_add(gi_v3_scale(ab, vb * denom), gi_v3_scale(ac, vc * denom)));
}

/* Distance from p to the nearest triangle of the scene at t = 0. */
static float scene_distance(const gi_scene *s, gi_vec3 p)
{
    float best = FLT_MAX;
    for (uint32_t tri = 0; tri < s->triangle_count; tri++) {
        gi_vec3 w[3];
        gi_scene_triangle_world(s, tri, 0.0f, w);
        gi_vec3 q = closest_on_triangle(p, w[0], w[1], w[2]);
        best = fminf(best, gi_v3_length(gi_v3_sub(p, q)));
    }
    return best;
}

static const char *march_src =
    "#define AVG_UNIT_NORMAL 8\n"
    "#define AVG_UNIT_COLOUR 9\n"
    "#include \"avg_grid.glsl\"\n"
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 8) readonly buffer Rays { vec4 rays[]; };\n"
    "layout(std430, binding = 9) writeonly buffer Hits { vec4 hits[]; };\n"
    "uniform uint u_count;\n"
    "void main() {\n"
    "  uint i = gl_GlobalInvocationID.x;\n"
    "  if (i >= u_count) return;\n"
    "  vec3 o = avg_to_grid(rays[2u * i].xyz), d = rays[2u * i + 1u].xyz;\n"
    "  ivec3 c; float t0, t1;\n"
    "  if (avg_march(o, d, c, t0, t1)) hits[i] = vec4(vec3(c), t0 * u_grid_h);\n"
    "  else hits[i] = vec4(-1.0);\n"
    "}\n";

/* Ray origins: random points in the scene's bounds whose own voxel and
 * its neighbours are empty (rays start in free space); directions
 * uniform on the sphere. 8 floats a ray: origin, 0, direction, 0. */
static float *make_rays(const gi_gpu_scene *gs, const avg_grid *g, const float *grid, uint32_t n,
                        uint32_t rays)
{
    float *ray = calloc((size_t)rays * 8, sizeof *ray);
    uint32_t rng = gi_rng_init(7, 0, 1), made = 0;
    while (made < rays) {
        gi_vec3 o;
        for (int a = 0; a < 3; a++)
            (&o.x)[a] =
                gs->bounds[a] + (gs->bounds[3 + a] - gs->bounds[a]) * gi_rng_next_float(&rng);
        int cx = (int)floorf((o.x - g->origin[0]) / g->h),
            cy = (int)floorf((o.y - g->origin[1]) / g->h),
            cz = (int)floorf((o.z - g->origin[2]) / g->h), free_space = 1;
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++)
                    free_space &= grid[4 * (((size_t)(cz + dz) * n + (size_t)(cy + dy)) * n +
                                            (size_t)(cx + dx)) +
                                       3] == 0.0f;
        if (!free_space)
            continue;
        gi_vec3 d = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
        float *r = &ray[8 * (size_t)made++];
        r[0] = o.x, r[1] = o.y, r[2] = o.z, r[4] = d.x, r[5] = d.y, r[6] = d.z;
    }
    return ray;
}

/* The rays marched through the grid by march_src: per ray the hit voxel
 * and the distance at which the ray enters it, or -1. */
static float *march_on_gpu(const avg_grid *g, const float *ray, uint32_t rays)
{
    gi_error err;
    GLuint prog = gi_program_build_compute_text("avg_tests march", march_src, NULL, &err);
    EXPECT(prog != 0, "%s", err.text);
    GLuint buf[2];
    glCreateBuffers(2, buf);
    glNamedBufferStorage(buf[0], (GLsizeiptr)(rays * 8 * sizeof(float)), ray, 0);
    glNamedBufferStorage(buf[1], (GLsizeiptr)(rays * 4 * sizeof(float)), NULL,
                         GL_DYNAMIC_STORAGE_BIT);
    glUseProgram(prog);
    avg_grid_bind(g, prog, 8, 9);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, buf[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, buf[1]);
    glUniform1ui(glGetUniformLocation(prog, "u_count"), rays);
    glDispatchCompute((rays + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    float *hit = malloc((size_t)rays * 4 * sizeof *hit);
    glGetNamedBufferSubData(buf[1], 0, (GLsizeiptr)(rays * 4 * sizeof(float)), hit);
    glDeleteBuffers(2, buf);
    glDeleteProgram(prog);
    return hit;
}

/* march_case's counts over the rays. */
typedef struct march_tally {
    uint32_t both, near, avg_only, embree_only, neither, late, steep, steep_near, phantom;
} march_tally;

/* The grid never stops a ray in empty space: some surface lies
 * within two voxel diagonals of where the ray enters the hit voxel. */
static int hit_near_surface(const gi_scene *s, const gi_rt *rt, const avg_grid *g, const float *r,
                            float t)
{
    gi_vec3 p = gi_v3(r[0] + r[4] * t, r[1] + r[5] * t, r[2] + r[6] * t);
    int near_surface = 0;
    for (int k = 0; k < 27 && !near_surface; k++) {
        gi_vec3 dir =
            gi_v3((float)(k % 3) - 1.0f, (float)(k / 3 % 3) - 1.0f, (float)(k / 9) - 1.0f);
        if (k == 13)
            continue;
        near_surface = gi_rt_occluded(rt, p, gi_v3_normalize(dir), 0.0f, 2.0f * sqrtf(3.0f) * g->h);
    }
    if (!near_surface) /* probes can pass beside an edge: measure exactly */
        near_surface = scene_distance(s, p) <= 2.0f * sqrtf(3.0f) * g->h;
    return near_surface;
}

/* Ray r (8 floats) and its AVG hit (4 floats) against the Embree hit. */
static void tally_ray(const gi_scene *s, const gi_rt *rt, const avg_grid *g, const float *r,
                      const float *hit, march_tally *c)
{
    gi_rt_hit h;
    int eh =
        gi_rt_intersect(rt, gi_v3(r[0], r[1], r[2]), gi_v3(r[4], r[5], r[6]), 0.0f, INFINITY, &h);
    int ah = hit[3] >= 0.0f;
    if (ah)
        c->phantom += !hit_near_surface(s, rt, g, r, hit[3]);
    if (eh && ah) {
        c->both++;
        int v[3] = {(int)floorf((h.position.x - g->origin[0]) / g->h),
                    (int)floorf((h.position.y - g->origin[1]) / g->h),
                    (int)floorf((h.position.z - g->origin[2]) / g->h)};
        int cheb = 0;
        for (int a = 0; a < 3; a++) {
            int dd = abs(v[a] - (int)hit[a]);
            cheb = dd > cheb ? dd : cheb;
        }
        c->near += cheb <= 1;
        /* A ray grazing a surface runs through its layer of voxels for
         * about h / tan(angle) before it reaches the surface itself; at
         * angles over 15 degrees the hit voxel must be a neighbour. */
        if (fabsf(gi_v3_dot(h.ng, gi_v3(r[4], r[5], r[6]))) > 0.26f) {
            c->steep++;
            c->steep_near += cheb <= 1;
        }
        /* The AVG voxel is entered no later than one voxel diagonal past the real hit. */
        c->late += hit[3] > h.t + sqrtf(3.0f) * g->h;
    } else if (ah) {
        c->avg_only++;
    } else if (eh) {
        c->embree_only++;
    } else {
        c->neither++;
    }
}

static void march_case(gi_gpu *gpu, const char *scene_path, uint32_t n, uint32_t rays)
{
    gi_error err;
    avg_test_fixture fx;
    if (!avg_test_load_fixture(gpu, scene_path, &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    avg_grid *g = avg_grid_create(n, &err);
    gi_rt *rt = NULL;
    /* The truth is the raw geometry, both faces of every triangle
     * (GI_RT_ALL_FACES): the AVG is a side-less occupancy grid (a voxel is
     * full whatever side of the triangle crossed it, §III-A), so what this
     * test measures is where the march stops against the surfaces, not
     * the rule for sides, which a grid cannot hold. */
    if (!g || gi_rt_create_ex(s, 0.0f, GI_RT_ALL_FACES, &rt, &err) != GI_OK) {
        EXPECT(0, "%s", err.text);
        return;
    }
    avg_grid_place(g, gs->bounds);
    EXPECT(avg_grid_voxelise(g, gs, AVG_VOX_CONSERVATIVE, &err) == GI_OK, "%s", err.text);
    float *grid = avg_grid_read(g, 0);
    float *ray = make_rays(gs, g, grid, n, rays);
    float *hit = march_on_gpu(g, ray, rays);
    march_tally c = {0};
    for (uint32_t i = 0; i < rays; i++)
        tally_ray(s, rt, g, &ray[8 * (size_t)i], &hit[4 * (size_t)i], &c);
    printf("march %s n=%u: %u rays: %u hit both (%u = %.2f %% within one voxel; of the %u not "
           "grazing (> 15 deg), "
           "%.2f %%; %u entered late), %u AVG only, %u Embree only (leaks), %u neither; %u AVG "
           "hits far from any surface\n",
           strrchr(scene_path, '/') + 1, n, rays, c.both, c.near,
           100.0 * c.near / (c.both ? c.both : 1), c.steep,
           100.0 * c.steep_near / (c.steep ? c.steep : 1), c.late, c.avg_only, c.embree_only,
           c.neither, c.phantom);
    EXPECT(c.embree_only == 0, "%u rays went through the AVG where Embree hits a surface",
           c.embree_only);
    /* The rest of the non-grazing hits are rays passing within a voxel of an
     * edge, caught by its conservative voxels (counted, not failed). */
    EXPECT(c.steep_near >= c.steep - c.steep / 10,
           "only %u of %u non-grazing hits within one voxel of the real hit", c.steep_near,
           c.steep);
    EXPECT(c.phantom == 0, "%u AVG hits with no surface within two voxel diagonals", c.phantom);
    EXPECT(c.late == 0, "%u AVG hits lie more than a voxel diagonal behind the real surface",
           c.late);
    EXPECT(c.both > rays / 2, "too few hits (%u) for the test to mean anything", c.both);
    free(ray);
    free(hit);
    free(grid);
    gi_rt_free(rt);
    avg_grid_free(g);
    avg_test_free_fixture(&fx);
}

int avg_test_march(gi_gpu *gpu)
{
    march_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", 32, 4096);
    march_case(gpu, GI_SOURCE_DIR "/scenes/u_room.gltf", 48, 4096);
    return gi_test_failed;
}
