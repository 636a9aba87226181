/* The `avg` method: Approximate Visibility Grids for interactive indirect
 * illumination (Bashford-Rogers, Debattista, Harvey, Chalmers).
 *
 * Every frame, nothing precomputed (§III):
 *   vox  the scene voxelised into the AVG by the rasteriser (§III-A, avg_grid.c);
 *   tra  light paths traced through the AVG, a VPL on the light and at every
 *        hit (§III-B, shaders/avg_trace.comp), read back and compacted in
 *        slot order (deterministic);
 *   sha  one low-resolution shadow map per VPL in the core's depth atlas,
 *        one instanced draw (§III-C);
 *   ill  G-buffer, the swizzle into M sub-images, each sub-image shaded by
 *        its N_VPL / M VPLs, reassembly, the discontinuity-aware box
 *        filter, times albedo (§III-C, Fig. 4).
 * The VPLs on the lights carry the direct light (Keller's instant
 * radiosity, which the paper builds on), the others the indirect bounces. */
#include "avg.h"
#include "shaders/avg_bindings.h"

#include "gi/log.h"
#include "gi/algo/simplify.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define AVG_BIAS_VOXELS 0.5f /* receiver offset and constant depth bias, in voxel edges */
#define AVG_BIAS_TEXELS 1.0f /* depth bias per unit of distance and slope, in texels of the map */
/* How far a bounce VPL's shadow-map eye moves out along its normal, in
 * voxel edges: the voxel's diagonal. */
#define AVG_EYE_LIFT 1.7320508f

/* Largest surface move the shadow maps' lower-detail copy may make, as a
 * share of each object's extent (meshopt's relative error): half a texel
 * of a 32^2 map seen from one extent away with the 120 degree field of
 * view is about 5 % of it, so the copy stays well inside a texel. */
#define AVG_LOD_ERROR 0.02f

static const gi_param_desc avg_params[] = {
    {"grid", GI_PARAM_INT, 64, 4, 512, GI_QUALITY_UP(1.5), "AVG resolution (Sec. III-A, 64^3)",
     "voxels per axis of the grid"},
    {"vpls", GI_PARAM_INT, 1024, 1, 65536, GI_QUALITY_UP(2), "N_VPL (Sec. IV, 1024)",
     "VPL slots: N_VPL / (B + 1) light paths, each with a VPL on the light and at up to B hits"},
    {"bounces", GI_PARAM_INT, 3, 0, 3, NULL, "bounces (Sec. IV, 3)",
     "indirect bounces B (VPLs at hits 1..B)"},
    {"M", GI_PARAM_INT, 16, 1, 64, NULL, "M (Sec. III-C, 16)",
     "interleaved-sampling subsets, a square number (mx x mx pixel pattern)"},
    {"clamp", GI_PARAM_FLOAT, 1.0, 0.0, 100.0, NULL, "G clamping",
     "the geometry term's distance is clamped below at this many voxel edges"},
    {"visibility", GI_PARAM_BOOL, 1, 0, 1, NULL, "Table I FPS (V) / (NV)",
     "VPL visibility from shadow maps; off: every VPL reaches every point it faces"},
    {"shadow_size", GI_PARAM_INT, 32, 4, 512, NULL, "Sec. III-C (low resolution)",
     "each VPL's shadow map is this many texels square"},
    {"projection", GI_PARAM_ENUM, 0, 0, 0, "auto|paraboloid|perspective", "Sec. IV",
     "shadow-map projection; auto: paraboloid for scenes of small triangles, perspective for large "
     "ones (as the paper)"},
    {"fov", GI_PARAM_FLOAT, 120.0, 10.0, 170.0, NULL, "Sec. IV",
     "field of view of perspective shadow maps, degrees"},
    {"shadow_lod", GI_PARAM_FLOAT, 1.0, 0.01, 1.0, NULL,
     "Sec. V (lower-detail geometry for the maps)",
     "the VPL shadow maps draw a simplified copy of each object with this share of its triangles "
     "(meshoptimizer, surface moved by at most 2 % of the object's size); 1: the scene itself"},
    {"filter", GI_PARAM_BOOL, 1, 0, 1, NULL, "Sec. III-C",
     "discontinuity-aware mx x mx box filter"},
    {"voxeliser", GI_PARAM_ENUM, 0, 0, 0, "conservative|paper|single", "Sec. III-A",
     "exact triangle-box voxels drawn slice by slice (one instance per Z slice), the paper's "
     "epsilon shift and "
     "stand-in triangles (slice by slice), or the exact voxels in a single pass (dominant-axis "
     "projection, "
     "integer atomics)"},
    {"tracing", GI_PARAM_ENUM, 0, 0, 0, "avg|exact", "Fig. 6",
     "VPL paths marched through the AVG on the GPU, or the same paths traced exactly by Embree on "
     "the CPU"},
    {"offset", GI_PARAM_FLOAT, 1.5, 0.0, 8.0, NULL, NULL,
     "ray origins leave a surface this many voxel edges along its normal"},
    {0},
};

static gi_result avg_create(const gi_host *host, const gi_params *params, void **out)
{
    avg *a = calloc(1, sizeof *a);
    if (!a)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&a->kit, host, gi_avg_shaders) != GI_OK) {
        free(a);
        return GI_ERR_INVALID_ARGUMENT;
    }
    a->grid_n = gi_params_int(params, "grid");
    a->vpls = gi_params_int(params, "vpls");
    a->bounces = gi_params_int(params, "bounces");
    a->M = gi_params_int(params, "M");
    a->clamp = gi_params_float(params, "clamp");
    a->filter = gi_params_bool(params, "filter");
    a->voxeliser = gi_params_enum(params, "voxeliser");
    a->offset = gi_params_float(params, "offset");
    a->tracing = gi_params_enum(params, "tracing");
    a->visibility = gi_params_bool(params, "visibility");
    a->tile = gi_params_int(params, "shadow_size");
    a->projection = gi_params_enum(params, "projection");
    a->fov = gi_params_float(params, "fov");
    a->shadow_lod = gi_params_float(params, "shadow_lod");
    a->mx = (int)lround(sqrt((double)a->M));
    a->paths = ((uint32_t)a->vpls + (uint32_t)a->bounces) / ((uint32_t)a->bounces + 1u);
    if (a->paths == 0)
        a->paths = 1;
    a->slots = a->paths * ((uint32_t)a->bounces + 1u);
    *out = a;
    return GI_OK;
}

static gi_result build_programs(avg *a, gi_error *err)
{
    struct {
        GLuint *p;
        const char *name;
    } list[] = {{&a->prog_trace, "avg_trace.comp"},
                {&a->prog_split, "avg_split.comp"},
                {&a->prog_shade, "avg_shade.comp"},
                {&a->prog_assemble, "avg_assemble.comp"},
                {&a->prog_final, "avg_final.comp"}};
    for (size_t i = 0; i < sizeof list / sizeof list[0]; i++) {
        *list[i].p = gi_program_build_compute(list[i].name, NULL, err);
        if (!*list[i].p)
            return GI_ERR_GL;
    }
    return GI_OK;
}

/* The paper's rule (Sec. IV): paraboloid maps for scenes of small
 * triangles, perspective maps for scenes of large ones, whose straight
 * edges the paraboloid warp would bend. Small: mean edge below 1/16 of the
 * scene's extent. The triangles measured are those the maps draw: the
 * lower-detail copy when there is one (its long edges would be bent). */
static gi_projection choose_projection(avg *a, const gi_scene *s)
{
    if (a->projection == 1)
        return GI_PROJ_PARABOLOID;
    if (a->projection == 2)
        return GI_PROJ_PERSPECTIVE;
    const uint32_t *idx = a->lod ? a->lod->indices : s->indices;
    uint32_t count = a->lod ? a->lod->triangle_count : s->triangle_count;
    double sum = 0.0;
    float m[16];
    uint32_t m_object = UINT32_MAX;
    for (uint32_t t = 0; t < count; t++) {
        gi_vec3 p[3];
        for (int k = 0; k < 3; k++) {
            const gi_vertex *v = &s->vertices[idx[3 * (size_t)t + k]];
            if (v->object != m_object) {
                gi_scene_object_transform(s, v->object, 0.0f, m);
                m_object = v->object;
            }
            p[k] = gi_mat4_point(m, gi_v3_load(v->position));
        }
        for (int e = 0; e < 3; e++)
            sum += gi_v3_length(gi_v3_sub(p[(e + 1) % 3], p[e]));
    }
    float ext = 0.0f;
    for (int i = 0; i < 3; i++)
        ext = fmaxf(ext, s->bounds[3 + i] - s->bounds[i]);
    double mean = count ? sum / (3.0 * count) : 0.0;
    return mean < ext / 16.0 ? GI_PROJ_PARABOLOID : GI_PROJ_PERSPECTIVE;
}

/* The shadow maps' lower-detail copy (param shadow_lod < 1): indices into
 * the scene's own vertices, so rigid motion (object transforms) and morph
 * targets (the vertex buffer rewritten per frame) move it as they move the
 * scene; built again when the caller moves vertices itself. */
static gi_result build_lod(avg *a, const gi_scene *s, gi_error *err)
{
    gi_simplified_free(a->lod);
    a->lod = NULL;
    if (a->shadow_lod >= 1.0f)
        return GI_OK;
    a->lod = gi_simplify_scene(s, a->shadow_lod, AVG_LOD_ERROR, err);
    if (!a->lod) /* the parameter's range leaves only out of memory */
        return GI_ERR_OUT_OF_MEMORY;
    return gi_simplified_upload(a->lod, err);
}

/* §III-C: one shadow map per live VPL, from its position along its normal,
 * all in the atlas in one instanced draw. */
static gi_result shadow_maps(avg *a, gi_error *err)
{
    const gi_depth_atlas_desc *d = gi_depth_atlas_get_desc(a->atlas);
    const float *b = a->kit.scene->bounds;
    float diag = sqrtf((b[3] - b[0]) * (b[3] - b[0]) + (b[4] - b[1]) * (b[4] - b[1]) +
                       (b[5] - b[2]) * (b[5] - b[2]));
    float zfar = 2.0f * diag + 1e-6f, znear = 1e-3f * a->grid->h;
    for (uint32_t j = 0; j < a->vpl_shaded; j++) {
        const avg_vpl *v = &a->cpu_vpls[j];
        gi_vec3 eye = gi_v3_load(v->position), n = gi_v3_load(v->normal);
        /* A bounce VPL lies up to a voxel diagonal past its surface (its
         * position is pushed into the hit voxel, avg_trace.comp); maps kept
         * as the receivers see them (GI_SIDES_RECEIVERS) would hold that
         * surface's back at its eye and shadow everything. Their eye moves
         * out along the normal by the diagonal. */
        if ((v->kind >> 8 & 0xFFu) != 0)
            eye = gi_v3_add(eye, gi_v3_scale(n, AVG_EYE_LIFT * a->grid->h));
        /* A VPL on an area light lies on the light's plane: a paraboloid map
         * would draw the light's own triangles (their corners on the
         * horizon) across the disc. A hundredth of a voxel puts that plane
         * behind the eye, where the hemisphere clips it. */
        else if ((v->kind & 0xFFu) == AVG_VPL_DIFFUSE)
            eye = gi_v3_add(eye, gi_v3_scale(n, 0.01f * a->grid->h));
        gi_vec3 up = fabsf(n.y) < 0.9f ? gi_v3(0, 1, 0) : gi_v3(1, 0, 0);
        gi_depth_view *dv = &a->views[j];
        gi_mat4_look_at(dv->view, eye, gi_v3_add(eye, n), up);
        /* A cube-face VPL of a punctual light (punctual_parts): its face is
         * the 90 degree frustum about the axis n, whose sides the up vector
         * above aligns with the other two axes. */
        float fov = (v->kind & AVG_VPL_FACE) ? 90.0f : a->fov;
        gi_mat4_perspective(dv->proj, fov * GI_PI / 180.0f, 1.0f, znear, zfar);
        dv->projection = d->projection;
        dv->znear = 0.0f;
        dv->zfar = zfar;
    }
    return gi_depth_atlas_render(a->atlas, a->kit.scene, a->views, a->vpl_shaded, err);
}

/* Everything prepare() makes, released before a second prepare() and by destroy(). */
static void release_prepared(avg *a)
{
    avg_grid_free(a->grid);
    avg_exact_free(a->exact);
    gi_depth_atlas_free(a->atlas);
    gi_simplified_free(a->lod);
    a->lod = NULL;
    free(a->views);
    GLuint progs[5] = {a->prog_trace, a->prog_split, a->prog_shade, a->prog_assemble,
                       a->prog_final};
    for (int i = 0; i < 5; i++)
        if (progs[i])
            glDeleteProgram(progs[i]);
    if (a->ssbo_slots)
        glDeleteBuffers(1, &a->ssbo_slots);
    if (a->ssbo_vpls)
        glDeleteBuffers(1, &a->ssbo_vpls);
    free(a->cpu_slots);
    free(a->cpu_vpls);
    free(a->cpu_order);
    a->grid = NULL;
    a->exact = NULL;
    a->atlas = NULL;
    a->views = NULL;
    a->prog_trace = a->prog_split = a->prog_shade = a->prog_assemble = a->prog_final = 0;
    a->ssbo_slots = a->ssbo_vpls = 0;
    a->cpu_slots = a->cpu_vpls = a->cpu_order = NULL;
    a->vpl_count = 0;
}

static gi_result avg_prepare(void *inst, const gi_gpu_scene *scene)
{
    avg *a = inst;
    gi_error err;
    release_prepared(a);
    gi_kit_prepare(&a->kit, scene);
    /* Checked here rather than in create(), where the host has no instance
     * to ask for the message. */
    if (a->mx * a->mx != a->M) {
        return gi_kit_fail(&a->kit, GI_ERR_INVALID_ARGUMENT,
                           "M=%d is not a square number (1, 4, 9, 16, 25, 36, 49 or 64)", a->M);
    }
    /* Directional light and the environment, which the caps leave out, the
     * host names (gibench render warns, a study marks the cell n/a). */
    if (scene->light_count > AVG_MAX_PUNCTUAL)
        a->kit.host->log(a->kit.host, GI_LOG_WARN,
                         "only the first %d of %u punctual lights emit VPLs", AVG_MAX_PUNCTUAL,
                         scene->light_count);
    /* Before the grid's textures are made: at grid=512 they are 4 GiB. */
    if (a->voxeliser == AVG_VOX_SINGLE && avg_grid_check_single((uint32_t)a->grid_n, &err) != GI_OK)
        return gi_kit_fail_with(&a->kit, GI_ERR_INVALID_ARGUMENT, &err);
    a->grid = avg_grid_create((uint32_t)a->grid_n, &err);
    if (!a->grid)
        return gi_kit_fail_with(&a->kit, GI_ERR_GL, &err);
    a->grid->host = a->kit.host; /* the long draws stop on a cancel (issue 32) */
    if (build_programs(a, &err) != GI_OK)
        return gi_kit_fail_with(&a->kit, GI_ERR_GL, &err);
    if (a->visibility) {
        gi_result r = build_lod(a, scene->scene, &err);
        if (r != GI_OK)
            return gi_kit_fail_with(&a->kit, r, &err);
        /* No culling, and single-sided faces as the receivers see them (the
         * one rule for sides, gi/scene.h): a VPL's light reaches a point
         * unless a ray from the point toward the VPL meets a surface, as the
         * reference traces it; a closed object's map holds its far side. */
        gi_depth_atlas_desc d = {.tile = (uint32_t)a->tile,
                                 .capacity = a->slots,
                                 .projection = choose_projection(a, scene->scene),
                                 .metric = GI_DEPTH_RADIAL,
                                 .cull = 0,
                                 .receiver_side = GI_SIDES_RECEIVERS};
        if (a->lod && a->projection == 1)
            a->kit.host->log(a->kit.host, GI_LOG_WARN,
                             "shadow_lod=%g with projection=paraboloid: the warp bends the "
                             "simplified copy's long "
                             "edges (projection=auto or perspective avoids it)",
                             (double)a->shadow_lod);
        a->atlas = gi_depth_atlas_create(&d, &err);
        if (!a->atlas)
            return gi_kit_fail_with(&a->kit, GI_ERR_INVALID_ARGUMENT, &err);
        gi_depth_atlas_set_geometry(a->atlas, a->lod ? a->lod->ibo : 0,
                                    a->lod ? a->lod->triangle_count : 0);
        gi_depth_atlas_set_host(a->atlas, a->kit.host);
        a->views = calloc(a->slots, sizeof *a->views);
        if (!a->views)
            return gi_kit_fail(&a->kit, GI_ERR_OUT_OF_MEMORY,
                               "avg: out of memory for the shadow-map views");
    }
    if (a->tracing == 1) {
        a->exact = avg_exact_create(scene, &err);
        if (!a->exact)
            return gi_kit_fail_with(&a->kit, GI_ERR_INVALID_ARGUMENT, &err);
    }
    a->cpu_slots = calloc(a->slots, sizeof *a->cpu_slots);
    a->cpu_vpls = calloc(a->slots, sizeof *a->cpu_vpls);
    a->cpu_order = calloc(a->slots, sizeof *a->cpu_order);
    if (!a->cpu_slots || !a->cpu_vpls || !a->cpu_order)
        return gi_kit_fail(&a->kit, GI_ERR_OUT_OF_MEMORY, "avg: out of memory for the VPL slots");
    glCreateBuffers(1, &a->ssbo_slots);
    glNamedBufferStorage(a->ssbo_slots, (GLsizeiptr)(a->slots * sizeof(avg_vpl)), NULL,
                         GL_DYNAMIC_STORAGE_BIT);
    glCreateBuffers(1, &a->ssbo_vpls);
    glNamedBufferStorage(a->ssbo_vpls, (GLsizeiptr)(a->slots * sizeof(avg_vpl)), NULL,
                         GL_DYNAMIC_STORAGE_BIT);
    if (gi_gl_check("avg: prepare", &err) != GI_OK)
        return gi_kit_fail_with(&a->kit, GI_ERR_GL, &err);
    return GI_OK;
}

static gi_result avg_update(void *inst, const gi_gpu_scene *scene, const gi_changes *changes)
{
    /* Everything is rebuilt every frame (§III). The shadow maps'
     * lower-detail copy follows transforms and morph targets by itself;
     * vertices the caller moved (a scene without morph targets that
     * reports new vertices) change the copy's shape, so it is made again. */
    avg *a = inst;
    gi_kit_update(&a->kit, scene, changes);
    if (a->lod && (changes->flags & GI_CHANGED_VERTICES) && !gi_scene_deforms(scene->scene)) {
        gi_error err;
        gi_result r = build_lod(a, scene->scene, &err);
        if (r != GI_OK)
            return gi_kit_fail_with(&a->kit, r, &err);
        gi_depth_atlas_set_geometry(a->atlas, a->lod ? a->lod->ibo : 0,
                                    a->lod ? a->lod->triangle_count : 0);
    }
    return GI_OK;
}

void avg_light_table_build(const gi_gpu_scene *gs, avg_light_table *t)
{
    memset(t, 0, sizeof *t);
    double power[1 + AVG_MAX_PUNCTUAL];
    uint32_t np = gs->light_count < AVG_MAX_PUNCTUAL ? gs->light_count : AVG_MAX_PUNCTUAL;
    power[0] = gs->emitter_count > 0 ? gs->emitter_power : 0.0;
    if (np > 0) {
        gi_gpu_light lights[AVG_MAX_PUNCTUAL];
        glGetNamedBufferSubData(gs->ssbo_lights, 0, (GLsizeiptr)(np * sizeof(gi_gpu_light)),
                                lights);
        for (uint32_t l = 0; l < np; l++) {
            double lum = gi_luminance(lights[l].intensity);
            double p = 0.0;
            if (lights[l].type == GI_LIGHT_POINT)
                p = 4.0 * GI_PI * lum;
            else if (lights[l].type == GI_LIGHT_SPOT) /* cone solid angle to the ramp's middle */
                p = 2.0 * GI_PI * (1.0 - 0.5 * (lights[l].cos_inner + lights[l].cos_outer)) * lum;
            power[1 + l] = p > 0.0 ? p : 0.0;
        }
    }
    double total = 0.0;
    for (uint32_t l = 0; l <= np; l++)
        total += power[l];
    if (!(total > 0.0))
        return;
    t->count = 1 + np;
    double run = 0.0;
    for (uint32_t l = 0; l <= np; l++) {
        run += power[l];
        t->pdf[l] = (float)(power[l] / total);
        t->cdf[l] = (float)(run / total);
    }
    t->cdf[np] = 1.0f;
}

static uint32_t pow2_mask(uint32_t n)
{
    uint32_t m = 1;
    while (m < n)
        m <<= 1;
    return m - 1;
}

/* §III-B on the GPU: one invocation per path through the AVG. */
static gi_result trace_avg(avg *a, const avg_light_table *lt, uint32_t seed, gi_error *err)
{
    GLuint p = a->prog_trace;
    glUseProgram(p);
    gi_gpu_scene_bind(a->kit.scene);
    avg_grid_bind(a->grid, p, AVG_TEX_GRID_NORMAL, AVG_TEX_GRID_COLOUR);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, AVG_SSBO_SLOTS, a->ssbo_slots);
    glUniform1ui(glGetUniformLocation(p, "u_paths"), a->paths);
    glUniform1ui(glGetUniformLocation(p, "u_bounces"), (GLuint)a->bounces);
    glUniform1ui(glGetUniformLocation(p, "u_qr_mask"), pow2_mask(a->paths));
    glUniform1ui(glGetUniformLocation(p, "u_seed"), seed);
    glUniform1f(glGetUniformLocation(p, "u_offset"), a->offset);
    glUniform1i(glGetUniformLocation(p, "u_light_count"), (GLint)lt->count);
    glUniform1fv(glGetUniformLocation(p, "u_light_cdf"), 65, lt->cdf);
    glUniform1fv(glGetUniformLocation(p, "u_light_pdf"), 65, lt->pdf);
    glDispatchCompute((a->paths + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(0);
    glGetNamedBufferSubData(a->ssbo_slots, 0, (GLsizeiptr)(a->slots * sizeof(avg_vpl)),
                            a->cpu_slots);
    return gi_gl_check("avg: VPL tracing", err);
}

/* Live VPLs (non-zero power) in slot order: the same list every frame for
 * the same scene. */
static void compact(avg *a)
{
    a->vpl_count = a->vpl_whole = a->vpl_shaded = 0;
    for (uint32_t s = 0; s < a->slots; s++) {
        const float *pw = a->cpu_slots[s].power;
        if (pw[0] > 0.0f || pw[1] > 0.0f || pw[2] > 0.0f)
            a->cpu_vpls[a->vpl_count++] = a->cpu_slots[s];
    }
}

/* What one VPL's shadow map covers of a punctual light's directions, F
 * parts of the sphere: 1 for a spot whose cone the map holds, else 2
 * hemispheres (paraboloid maps, or no maps) or 6 cube faces (perspective
 * maps of 90 degrees). The paper's VPLs lie on area lights and shine
 * through a cosine, so a perspective map that misses the edge of their
 * hemisphere loses little (§IV: "lack of visibility information at the
 * edges ... not too noticeable due to the reduction in radiance from the
 * cosine"); a point light has no cosine, and every direction outside its
 * VPLs' maps passed every occluder (issue 28). */
static uint32_t punctual_cover(const avg *a, const avg_vpl *v)
{
    int perspective =
        a->atlas && gi_depth_atlas_get_desc(a->atlas)->projection == GI_PROJ_PERSPECTIVE;
    float half = perspective ? 0.5f * a->fov * GI_PI / 180.0f : 0.5f * GI_PI;
    if ((v->kind & 0xFFu) == AVG_VPL_SPOT && v->cos_outer >= cosf(half))
        return 1;
    return perspective ? 6 : 2;
}

/* The VPLs on punctual lights (kind's entry, written by the tracers with the
 * light's intensity I). All of a light's VPLs lie at the light, so its n
 * maps hold F distinct pictures (punctual_cover): the light's first F VPLs
 * take parts 0 .. F-1 of its directions, each with the whole intensity I,
 * and are shaded at every pixel, outside the interleaving and the filter
 * (AVG_VPL_WHOLE; §III-C's subsets and filter average out the differences
 * between VPL subsets, and these add up to the light's direct light
 * exactly); its other VPLs would repeat them and get no power. The list is
 * reordered: the whole VPLs first (vpl_whole), then the rest in slot order
 * (interleaved, vpl_shaded in all with maps), then the powerless ones. */
static void punctual_parts(avg *a)
{
    uint32_t seen[1 + AVG_MAX_PUNCTUAL] = {0}, n_whole = 0, n_dead = 0;
    for (uint32_t j = 0; j < a->vpl_count; j++) {
        avg_vpl *v = &a->cpu_vpls[j];
        uint32_t l = v->kind >> 24;
        if (l == 0 || l > AVG_MAX_PUNCTUAL)
            continue;
        uint32_t F = punctual_cover(a, v), part = seen[l]++;
        if (part >= F) {
            memset(v->power, 0, sizeof v->power);
            n_dead++;
            continue;
        }
        v->kind |= AVG_VPL_WHOLE;
        n_whole++;
        if (F == 6) {
            memset(v->normal, 0, sizeof v->normal);
            v->normal[part / 2] = (part & 1u) ? -1.0f : 1.0f;
            v->kind |= AVG_VPL_FACE;
        } else if (F == 2 && part == 1) {
            for (int k = 0; k < 3; k++)
                v->normal[k] = -v->normal[k];
        }
    }
    /* Stable partition (the read-back slots stay as the tracer wrote them). */
    uint32_t at[3] = {0, n_whole, a->vpl_count - n_dead};
    for (uint32_t j = 0; j < a->vpl_count; j++) {
        const avg_vpl *v = &a->cpu_vpls[j];
        int dead = !(v->power[0] > 0.0f || v->power[1] > 0.0f || v->power[2] > 0.0f);
        int group = (v->kind & AVG_VPL_WHOLE) ? 0 : (dead && (v->kind >> 24) != 0 ? 2 : 1);
        a->cpu_order[at[group]++] = *v;
    }
    if (n_whole + n_dead > 0)
        memcpy(a->cpu_vpls, a->cpu_order, a->vpl_count * sizeof *a->cpu_vpls);
    a->vpl_whole = n_whole;
    a->vpl_shaded = a->vpl_count - n_dead;
    if (a->vpl_count)
        glNamedBufferSubData(a->ssbo_vpls, 0, (GLsizeiptr)(a->vpl_count * sizeof(avg_vpl)),
                             a->cpu_vpls);
}

/* Diagnostics: with GIBENCH_AVG_VPLS=FILE every frame (re)writes FILE as
 * CSV, one live VPL a line (position, normal, power, bounce: 0 on the
 * light), so that where the VPLs land can be counted
 * (plugins/avg/vpl_regions.py). A file that cannot be written is reported
 * once per frame as a warning and does not stop the render. */
static void dump_vpls(const avg *a)
{
    const char *path = getenv("GIBENCH_AVG_VPLS");
    if (!path || !*path)
        return;
    FILE *f = fopen(path, "w");
    if (!f) {
        gi_log(GI_LOG_WARN, "avg: cannot write GIBENCH_AVG_VPLS file '%s'", path);
        return;
    }
    fprintf(f, "x,y,z,nx,ny,nz,r,g,b,bounce\n");
    for (uint32_t i = 0; i < a->vpl_count; i++) {
        const avg_vpl *v = &a->cpu_vpls[i];
        fprintf(f, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%u\n", v->position[0],
                v->position[1], v->position[2], v->normal[0], v->normal[1], v->normal[2],
                v->power[0], v->power[1], v->power[2], (v->kind >> 8) & 0xffu);
    }
    if (fclose(f) != 0)
        gi_log(GI_LOG_WARN, "avg: cannot write GIBENCH_AVG_VPLS file '%s'", path);
}

/* The split images (M sub-images of ceil(w / mx) x ceil(h / mx)) and the
 * indirect image, as the kit's scratch textures. */
static void size_scratch(avg *a, uint32_t w, uint32_t h)
{
    uint32_t mx = (uint32_t)a->mx;
    a->split_w = (w + mx - 1) / mx;
    a->split_h = (h + mx - 1) / mx;
    a->tex_split_pos =
        gi_kit_scratch_texture(&a->kit, 0, GL_RGBA32F, a->split_w * mx, a->split_h * mx);
    a->tex_split_nrm =
        gi_kit_scratch_texture(&a->kit, 1, GL_RGBA32F, a->split_w * mx, a->split_h * mx);
    a->tex_split_out =
        gi_kit_scratch_texture(&a->kit, 2, GL_RGBA32F, a->split_w * mx, a->split_h * mx);
    a->tex_indirect = gi_kit_scratch_texture(&a->kit, 3, GL_RGBA32F, w, h);
    a->tex_split_whole =
        gi_kit_scratch_texture(&a->kit, 4, GL_RGBA32F, a->split_w * mx, a->split_h * mx);
    a->tex_whole = gi_kit_scratch_texture(&a->kit, 5, GL_RGBA32F, w, h);
}

/* §III-C: split, shade per subset, reassemble, filter, albedo. */
static gi_result illuminate(avg *a, const gi_view *view, const gi_target *target, gi_error *err)
{
    gi_result r = gi_gbuffer_render(a->kit.gbuffer, a->kit.scene, view->view, view->proj, err);
    if (r != GI_OK)
        return r;
    GLint size[2] = {(GLint)view->width, (GLint)view->height};
    GLint sub[2] = {(GLint)a->split_w, (GLint)a->split_h};
    GLuint sw = a->split_w * (GLuint)a->mx, sh = a->split_h * (GLuint)a->mx;

    GLuint p = a->prog_split;
    glUseProgram(p);
    gi_gbuffer_bind(a->kit.gbuffer, GI_TEX_GBUFFER_POSITION);
    glBindImageTexture(0, a->tex_split_pos, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, a->tex_split_nrm, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2iv(glGetUniformLocation(p, "u_size"), 1, size);
    glUniform2iv(glGetUniformLocation(p, "u_sub"), 1, sub);
    glUniform1i(glGetUniformLocation(p, "u_mx"), a->mx);
    glDispatchCompute((sw + 7) / 8, (sh + 7) / 8, 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);

    p = a->prog_shade;
    glUseProgram(p);
    glBindTextureUnit(AVG_TEX_SPLIT_POS, a->tex_split_pos);
    glBindTextureUnit(AVG_TEX_SPLIT_NRM, a->tex_split_nrm);
    glBindImageTexture(0, a->tex_split_out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, a->tex_split_whole, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, AVG_SSBO_VPLS, a->ssbo_vpls);
    glUniform2iv(glGetUniformLocation(p, "u_sub"), 1, sub);
    glUniform1i(glGetUniformLocation(p, "u_mx"), a->mx);
    glUniform1ui(glGetUniformLocation(p, "u_count"), a->vpl_shaded);
    glUniform1ui(glGetUniformLocation(p, "u_whole"), a->vpl_whole);
    float dmin = a->clamp * a->grid->h;
    glUniform1f(glGetUniformLocation(p, "u_dmin2"), dmin * dmin);
    glUniform1i(glGetUniformLocation(p, "u_visibility"), a->atlas != NULL);
    if (a->atlas) {
        glBindTextureUnit(AVG_TEX_ATLAS, gi_depth_atlas_texture(a->atlas));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, AVG_SSBO_ATLAS_VIEWS,
                         gi_depth_atlas_views_buffer(a->atlas));
        /* Depth bias for maps of `tile` texels: half a voxel plus a share
         * of the distance that grows as the maps get coarser (and with the
         * slope, in the shader). */
        glUniform1f(glGetUniformLocation(p, "u_bias_abs"), AVG_BIAS_VOXELS * a->grid->h);
        glUniform1f(glGetUniformLocation(p, "u_bias_rel"), AVG_BIAS_TEXELS / (float)a->tile);
    }
    glDispatchCompute((sw + 7) / 8, (sh + 7) / 8, 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);

    p = a->prog_assemble;
    glUseProgram(p);
    glBindTextureUnit(AVG_TEX_SPLIT_OUT, a->tex_split_out);
    glBindTextureUnit(AVG_TEX_SPLIT_WHOLE, a->tex_split_whole);
    glBindImageTexture(0, a->tex_indirect, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, a->tex_whole, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2iv(glGetUniformLocation(p, "u_size"), 1, size);
    glUniform2iv(glGetUniformLocation(p, "u_sub"), 1, sub);
    glUniform1i(glGetUniformLocation(p, "u_mx"), a->mx);
    glDispatchCompute((view->width + 7) / 8, (view->height + 7) / 8, 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);

    p = a->prog_final;
    glUseProgram(p);
    gi_gbuffer_bind(a->kit.gbuffer, GI_TEX_GBUFFER_POSITION);
    glBindTextureUnit(AVG_TEX_INDIRECT, a->tex_indirect);
    glBindTextureUnit(AVG_TEX_WHOLE, a->tex_whole);
    glBindImageTexture(1, target->texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2iv(glGetUniformLocation(p, "u_size"), 1, size);
    glUniform1i(glGetUniformLocation(p, "u_mx"), a->mx);
    glUniform1i(glGetUniformLocation(p, "u_filter"), a->filter);
    glUniform1f(glGetUniformLocation(p, "u_normal_dot"), 0.9f);
    /* A neighbour counts while it is within twice the window's width on a
     * surface facing the camera at the pixel's depth. */
    float footprint = 2.0f * tanf(0.5f * view->yfov) / (float)view->height;
    glUniform1f(glGetUniformLocation(p, "u_max_dist"), 2.0f * (float)a->mx * footprint);
    glDispatchCompute((view->width + 7) / 8, (view->height + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_TEXTURE_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    glUseProgram(0);
    return gi_gl_check("avg: shading", err);
}

static gi_result avg_render(void *inst, const gi_view *view, const gi_target *target)
{
    avg *a = inst;
    const gi_host *host = a->kit.host;
    gi_error err;
    gi_result r = gi_kit_frame_begin(&a->kit, view, GI_KIT_GBUFFER);
    if (r != GI_OK)
        return r;
    size_scratch(a, view->width, view->height);

    /* The grid is built with exact tracing too: it places the grid and sets
     * the clamping distance, so that both tracings shade alike. */
    host->stage_begin(host, "vox");
    avg_grid_place(a->grid, a->kit.scene->bounds);
    r = avg_grid_voxelise(a->grid, a->kit.scene, (avg_vox_mode)a->voxeliser, &err);
    host->stage_end(host, "vox");
    if (r != GI_OK)
        return gi_kit_fail_with(&a->kit, r, &err);

    host->stage_begin(host, "tra");
    avg_light_table lt;
    avg_light_table_build(a->kit.scene, &lt);
    if (a->exact) {
        avg_trace_desc td = {a->paths, (uint32_t)a->bounces, a->offset, view->seed};
        r = avg_exact_trace(a->exact, a->kit.scene, &lt, &td, a->cpu_slots, &err);
    } else {
        r = trace_avg(a, &lt, view->seed, &err);
    }
    if (r == GI_OK) {
        compact(a);
        punctual_parts(a);
        dump_vpls(a);
    }
    host->stage_end(host, "tra");
    if (r != GI_OK)
        return gi_kit_fail_with(&a->kit, r, &err);

    if (a->atlas) {
        host->stage_begin(host, "sha");
        r = shadow_maps(a, &err);
        host->stage_end(host, "sha");
        if (r != GI_OK)
            return gi_kit_fail_with(&a->kit, r, &err);
    }

    host->stage_begin(host, "ill");
    r = illuminate(a, view, target, &err);
    host->stage_end(host, "ill");
    if (r != GI_OK)
        return gi_kit_fail_with(&a->kit, r, &err);

    host->stat(host, "vpls_live", (double)a->vpl_count);
    host->stat(host, "vpls_shaded", (double)a->vpl_shaded);
    host->stat(host, "light_paths", (double)a->paths);
    host->stat(host, "voxel_size", (double)a->grid->h);
    /* Kept for rendering: the grid's two RGBA32F 3D textures, the live VPLs
     * and the shadow-map atlas (rebuilt each frame, but held). */
    double grid_bytes = 2.0 * 16.0 * (double)a->grid->n * (double)a->grid->n * (double)a->grid->n;
    double vpl_bytes = (double)a->vpl_count * (double)sizeof(avg_vpl);
    double atlas_bytes = a->atlas ? (double)gi_depth_atlas_bytes(a->atlas) : 0.0;
    host->stat(host, "data_bytes_grid", grid_bytes);
    host->stat(host, "data_bytes_atlas", atlas_bytes);
    host->stat(host, "data_bytes", grid_bytes + vpl_bytes + atlas_bytes);
    if (a->atlas)
        host->stat(host, "shadow_paraboloid",
                   (double)(gi_depth_atlas_get_desc(a->atlas)->projection == GI_PROJ_PARABOLOID));
    if (a->atlas)
        host->stat(host, "shadow_triangles",
                   (double)(a->lod ? a->lod->triangle_count : a->kit.scene->triangle_count));
    return GI_OK;
}

static void avg_destroy(void *inst)
{
    avg *a = inst;
    if (!a)
        return;
    gi_kit_free(&a->kit);
    release_prepared(a);
    free(a);
}

static const char *avg_last_error(void *inst)
{
    return inst ? gi_kit_last_error(&((avg *)inst)->kit) : "";
}

GI_METHOD_EXPORT(avg, .id = "avg",
                 .title = "Approximate Visibility Grids for Interactive Indirect Illumination",
                 .citation = "Bashford-Rogers, Debattista, Harvey, Chalmers. VS-Games 2011",
                 .version = "0.1",
                 .caps = GI_CAP_DIRECT | GI_CAP_INDIRECT | GI_CAP_AREA_LIGHTS |
                         GI_CAP_POINT_LIGHTS | GI_CAP_RIGID_MOTION | GI_CAP_DEFORMATION |
                         GI_CAP_TEXTURES,
                 .max_bounces = 3, .params = avg_params, .debug_buffers = avg_debug_buffers,
                 .debug_buffer = avg_debug_buffer);
