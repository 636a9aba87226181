/* Ray casting on the CPU (gi/raytrace.h): the scene placed at time t in one
 * Embree 3 triangle geometry. Placement and validation come first, because
 * Embree silently drops primitives with NaN/Inf corners. */
#include "gi/raytrace.h"

#include <embree3/rtcore.h>

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Coordinates beyond this overflow squared distances in float. */
#define RT_MAX_COORD 1e18f

struct gi_rt {
    const gi_scene *scene;
    RTCDevice device;
    RTCScene rtc;
    RTCGeometry geom; /* NULL for a scene without triangles */
    float *pos;       /* Embree's vertex buffer: world positions, 3 floats a vertex */
    float *nrm;       /* world unit shading normals, 3 floats a vertex */
    uint8_t *single;  /* per triangle: 1 when its material is single-sided (culled from behind) */
    float time;
    int moving; /* some object is animated or has morph targets */
    char version[32];
};

static int finite3(gi_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static int coord_ok(gi_vec3 v)
{
    return finite3(v) && fabsf(v.x) <= RT_MAX_COORD && fabsf(v.y) <= RT_MAX_COORD &&
           fabsf(v.z) <= RT_MAX_COORD;
}

static const char *object_name(const gi_scene *s, uint32_t o)
{
    return s->objects[o].name ? s->objects[o].name : "(unnamed)";
}

static gi_result embree_fail(const gi_rt *rt, const char *what, gi_error *err)
{
    enum RTCError e = rt->device ? rtcGetDeviceError(rt->device) : RTC_ERROR_UNKNOWN;
    if (e == RTC_ERROR_OUT_OF_MEMORY)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: Embree ran out of memory (%s)",
                            what);
    return gi_error_set(err, GI_ERR_IO, "raytrace: Embree failed: %s (error %d)", what, (int)e);
}

/* World positions into pos, world shading normals into nrm (3 floats a
 * vertex each); rejects non-finite results. Every vertex carries its
 * object, so the loop runs over vertices, not over objects' ranges. */
static gi_result place_vertices(const gi_scene *s, float t, float *pos, float *nrm, gi_error *err)
{
    float(*m)[16] = malloc((size_t)(s->object_count ? s->object_count : 1) * sizeof *m);
    float(*nm)[16] = malloc((size_t)(s->object_count ? s->object_count : 1) * sizeof *nm);
    gi_vertex *morphed = NULL;
    gi_result res = GI_OK;
    if (!m || !nm) {
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: out of memory (transforms)");
        goto done;
    }
    for (uint32_t o = 0; o < s->object_count; o++) {
        float inv[16];
        gi_scene_object_transform(s, o, t, m[o]);
        for (int k = 0; k < 16; k++)
            if (!isfinite(m[o][k])) {
                res = gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                   "%s: object %u '%s': transform at t = %g is not finite", s->path,
                                   o, object_name(s, o), (double)t);
                goto done;
            }
        /* Normals by the inverse transpose; a singular transform (scale 0)
         * leaves degenerate triangles that Embree never reports hit. */
        if (gi_mat4_invert(inv, m[o]))
            gi_mat4_transpose(nm[o], inv);
        else
            memcpy(nm[o], m[o], sizeof nm[o]);
    }
    /* Morphing objects: their vertices at t (gi_scene_object_vertices), one
     * object at a time, so that normals are blended as the GPU has them. */
    size_t morph_max = 0;
    for (uint32_t o = 0; o < s->object_count; o++)
        if (s->objects[o].morph_count && s->objects[o].vertex_count > morph_max)
            morph_max = s->objects[o].vertex_count;
    if (morph_max && !(morphed = malloc(morph_max * sizeof *morphed))) {
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: out of memory (morph targets)");
        goto done;
    }
    uint32_t morphed_object = UINT32_MAX;
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        const gi_vertex *gv = &s->vertices[v];
        uint32_t o = gv->object < s->object_count ? gv->object : 0;
        if (s->object_count && s->objects[o].morph_count) {
            if (morphed_object != o) {
                gi_scene_object_vertices(s, o, t, morphed);
                morphed_object = o;
            }
            gv = &morphed[v - s->objects[o].first_vertex];
        }
        gi_vec3 p = s->object_count ? gi_mat4_point(m[o], gi_v3_load(gv->position))
                                    : gi_v3_load(gv->position);
        if (!coord_ok(p)) {
            res = gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                               "%s: object %u '%s': vertex %u is not finite at t = %g (%g %g %g)",
                               s->path, o, s->object_count ? object_name(s, o) : "?",
                               v - (s->object_count ? s->objects[o].first_vertex : 0), (double)t,
                               (double)p.x, (double)p.y, (double)p.z);
            goto done;
        }
        gi_v3_store(p, pos + 3 * (size_t)v);
        gi_vec3 n =
            s->object_count ? gi_mat4_dir(nm[o], gi_v3_load(gv->normal)) : gi_v3_load(gv->normal);
        n = gi_v3_normalize(n);
        if (!finite3(n))
            n = gi_v3(0.0f, 0.0f, 0.0f); /* shading falls back to the geometric normal */
        gi_v3_store(n, nrm + 3 * (size_t)v);
    }
done:
    free(m);
    free(nm);
    free(morphed);
    return res;
}

/* The one rule for sides (gi/scene.h): a single-sided triangle seen from
 * its back does not exist for any ray. Embree calls this for every
 * candidate hit of rtcIntersect* and rtcOccluded*; the front is the
 * counter-clockwise side of the world-space corners (a node with a negative
 * determinant mirrors them, which is the winding flip glTF asks for). */
static void cull_back_faces(const struct RTCFilterFunctionNArguments *args)
{
    const gi_rt *rt = args->geometryUserPtr;
    const gi_scene *s = rt->scene;
    /* SOA packets of N lanes (rtcore_ray.h's RTCRayN_* / RTCHitN_* layout;
     * those accessors are C++ only): ray dir_x, y, z at 4N, 5N, 6N floats,
     * hit primID at 5N words. */
    const unsigned n = args->N;
    const float *ray = (const float *)args->ray;
    const unsigned *hit = (const unsigned *)args->hit;
    for (unsigned i = 0; i < n; i++) {
        if (args->valid[i] != -1)
            continue;
        unsigned prim = hit[5 * n + i];
        if (!rt->single[prim])
            continue;
        const uint32_t *idx = s->indices + 3 * (size_t)prim;
        gi_vec3 p0 = gi_v3_load(rt->pos + 3 * (size_t)idx[0]);
        gi_vec3 ng = gi_v3_cross(gi_v3_sub(gi_v3_load(rt->pos + 3 * (size_t)idx[1]), p0),
                                 gi_v3_sub(gi_v3_load(rt->pos + 3 * (size_t)idx[2]), p0));
        gi_vec3 d = gi_v3(ray[4 * n + i], ray[5 * n + i], ray[6 * n + i]);
        if (gi_v3_dot(ng, d) >= 0.0f)
            args->valid[i] = 0;
    }
}

/* Per-triangle single-sided flags and the filter, unless GI_RT_ALL_FACES. */
static gi_result set_culling(gi_rt *rt, unsigned flags, gi_error *err)
{
    const gi_scene *s = rt->scene;
    if (flags & GI_RT_ALL_FACES)
        return GI_OK;
    int any = 0;
    for (uint32_t m = 0; m < s->material_count; m++)
        any |= !s->materials[m].double_sided;
    if (!any)
        return GI_OK;
    rt->single = malloc(s->triangle_count);
    if (!rt->single)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: out of memory (%u triangles)",
                            s->triangle_count);
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        uint32_t m = s->vertices[s->indices[3 * (size_t)t]].material;
        rt->single[t] = m < s->material_count && !s->materials[m].double_sided;
    }
    rtcSetGeometryUserData(rt->geom, rt);
    rtcSetGeometryIntersectFilterFunction(rt->geom, cull_back_faces);
    rtcSetGeometryOccludedFilterFunction(rt->geom, cull_back_faces);
    return GI_OK;
}

static gi_result commit(gi_rt *rt, gi_error *err)
{
    if (rt->geom)
        rtcCommitGeometry(rt->geom);
    rtcCommitScene(rt->rtc);
    if (rtcGetDeviceError(rt->device) != RTC_ERROR_NONE)
        return embree_fail(rt, "BVH build", err);
    return GI_OK;
}

gi_result gi_rt_create(const gi_scene *s, float time, gi_rt **out, gi_error *err)
{
    return gi_rt_create_ex(s, time, 0u, out, err);
}

gi_result gi_rt_create_ex(const gi_scene *s, float time, unsigned flags, gi_rt **out, gi_error *err)
{
    if (out)
        *out = NULL;
    const unsigned known = (unsigned)GI_RT_FAST_TRAVERSAL | (unsigned)GI_RT_ALL_FACES;
    if (flags & ~known)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "raytrace: unknown option bits 0x%x",
                            flags & ~known);
    if (!s || !out)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "raytrace: %s is NULL",
                            !s ? "the scene" : "the output pointer");
    if (!isfinite(time))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "raytrace: time %g is not finite",
                            (double)time);
    gi_rt *rt = calloc(1, sizeof *rt);
    if (!rt)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: out of memory");
    rt->scene = s;
    rt->time = time;
    for (uint32_t o = 0; o < s->object_count; o++)
        rt->moving |= s->objects[o].animated != 0 || s->objects[o].morph_count != 0;
    gi_result res = GI_OK;
    rt->device = rtcNewDevice(NULL);
    if (!rt->device) {
        res = gi_error_set(err, GI_ERR_IO, "raytrace: cannot create an Embree device (error %d)",
                           (int)rtcGetDeviceError(NULL));
        goto fail;
    }
    snprintf(rt->version, sizeof rt->version, "embree %d.%d.%d",
             (int)rtcGetDeviceProperty(rt->device, RTC_DEVICE_PROPERTY_VERSION_MAJOR),
             (int)rtcGetDeviceProperty(rt->device, RTC_DEVICE_PROPERTY_VERSION_MINOR),
             (int)rtcGetDeviceProperty(rt->device, RTC_DEVICE_PROPERTY_VERSION_PATCH));
    rt->rtc = rtcNewScene(rt->device);
    if (!rt->rtc) {
        res = embree_fail(rt, "rtcNewScene", err);
        goto fail;
    }
    rtcSetSceneBuildQuality(rt->rtc, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(rt->rtc,
                     flags & GI_RT_FAST_TRAVERSAL ? RTC_SCENE_FLAG_NONE : RTC_SCENE_FLAG_ROBUST);
    rt->nrm = malloc((size_t)(s->vertex_count ? s->vertex_count : 1) * 3 * sizeof(float));
    if (!rt->nrm) {
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: out of memory (%u vertices)",
                           s->vertex_count);
        goto fail;
    }
    if (s->triangle_count > 0) {
        rt->geom = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (!rt->geom) {
            res = embree_fail(rt, "rtcNewGeometry", err);
            goto fail;
        }
        rtcSetGeometryBuildQuality(rt->geom, RTC_BUILD_QUALITY_HIGH);
        /* Embree owns both buffers; they live as long as the geometry. */
        rt->pos = rtcSetNewGeometryBuffer(rt->geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                          3 * sizeof(float), s->vertex_count);
        unsigned *ib = rtcSetNewGeometryBuffer(rt->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                               3 * sizeof(unsigned), s->triangle_count);
        if (!rt->pos || !ib) {
            res = embree_fail(rt, "vertex and index buffers", err);
            goto fail;
        }
        res = place_vertices(s, time, rt->pos, rt->nrm, err);
        if (res != GI_OK)
            goto fail;
        memcpy(ib, s->indices, (size_t)s->triangle_count * 3 * sizeof(unsigned));
        res = set_culling(rt, flags, err);
        if (res != GI_OK)
            goto fail;
        rtcAttachGeometryByID(rt->rtc, rt->geom, 0);
    }
    res = commit(rt, err);
    if (res != GI_OK)
        goto fail;
    *out = rt;
    return GI_OK;
fail:
    gi_rt_free(rt);
    return res;
}

/* Re-places every vertex at `time` and rebuilds; `force` even when
 * nothing moves (the caller changed the scene's vertices). */
static gi_result replace(gi_rt *rt, float time, int force, gi_error *err)
{
    if (!rt)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "raytrace: the gi_rt is NULL");
    if (!isfinite(time))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "raytrace: time %g is not finite",
                            (double)time);
    if (!rt->geom || (!force && (!rt->moving || time == rt->time))) {
        rt->time = time;
        return GI_OK;
    }
    /* Placed into scratch first so that a failure leaves the old placement. */
    const gi_scene *s = rt->scene;
    size_t n = (size_t)s->vertex_count * 3;
    float *pos = malloc(n * sizeof *pos), *nrm = malloc(n * sizeof *nrm);
    gi_result res = GI_OK;
    if (!pos || !nrm)
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "raytrace: out of memory (%u vertices)",
                           s->vertex_count);
    else
        res = place_vertices(s, time, pos, nrm, err);
    if (res == GI_OK) {
        memcpy(rt->pos, pos, n * sizeof *pos);
        memcpy(rt->nrm, nrm, n * sizeof *nrm);
        rtcUpdateGeometryBuffer(rt->geom, RTC_BUFFER_TYPE_VERTEX, 0);
        res = commit(rt, err);
        if (res == GI_OK)
            rt->time = time;
    }
    free(pos);
    free(nrm);
    return res;
}

gi_result gi_rt_set_time(gi_rt *rt, float time, gi_error *err)
{
    return replace(rt, time, 0, err);
}

gi_result gi_rt_refresh(gi_rt *rt, gi_error *err)
{
    return replace(rt, rt ? rt->time : 0.0f, 1, err);
}

void gi_rt_free(gi_rt *rt)
{
    if (!rt)
        return;
    if (rt->geom)
        rtcReleaseGeometry(rt->geom);
    if (rt->rtc)
        rtcReleaseScene(rt->rtc);
    if (rt->device)
        rtcReleaseDevice(rt->device);
    free(rt->nrm);
    free(rt->single);
    free(rt);
}

static inline gi_vec3 vertex(const gi_rt *rt, uint32_t v)
{
    return gi_v3_load(rt->pos + 3 * (size_t)v);
}

/* rtcIntersect1 on one ray; 1 on a hit. */
static inline int intersect1(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax,
                             struct RTCRayHit *rh)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rh->ray.org_x = o.x;
    rh->ray.org_y = o.y;
    rh->ray.org_z = o.z;
    rh->ray.tnear = tmin;
    rh->ray.dir_x = d.x;
    rh->ray.dir_y = d.y;
    rh->ray.dir_z = d.z;
    rh->ray.time = 0.0f;
    rh->ray.tfar = tmax;
    rh->ray.mask = ~0u;
    rh->ray.id = 0;
    rh->ray.flags = 0;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rt->rtc, &ctx, rh);
    return rh->hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

int gi_rt_intersect_tuv(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax, float *t,
                        float *u, float *v, uint32_t *triangle)
{
    assert(rt && t && u && v && triangle);
    struct RTCRayHit rh;
    if (!intersect1(rt, o, d, tmin, tmax, &rh))
        return 0;
    *t = rh.ray.tfar;
    *u = rh.hit.u;
    *v = rh.hit.v;
    *triangle = rh.hit.primID;
    return 1;
}

void gi_rt_intersect8_tuv(const gi_rt *rt, uint32_t n, const gi_vec3 *o, const gi_vec3 *d,
                          const float *tmin, const float *tmax, int *hit, float *t, float *u,
                          float *v, uint32_t *triangle)
{
    assert(rt && n <= 8 && o && d && tmin && tmax && hit && t && u && v && triangle);
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    struct RTCRayHit8 rh;
    int valid[8];
    for (uint32_t i = 0; i < 8; i++) {
        uint32_t k = i < n ? i : 0; /* lanes past n repeat ray 0, masked off */
        valid[i] = i < n ? -1 : 0;
        rh.ray.org_x[i] = o[k].x;
        rh.ray.org_y[i] = o[k].y;
        rh.ray.org_z[i] = o[k].z;
        rh.ray.tnear[i] = tmin[k];
        rh.ray.dir_x[i] = d[k].x;
        rh.ray.dir_y[i] = d[k].y;
        rh.ray.dir_z[i] = d[k].z;
        rh.ray.time[i] = 0.0f;
        rh.ray.tfar[i] = tmax[k];
        rh.ray.mask[i] = ~0u;
        rh.ray.id[i] = i;
        rh.ray.flags[i] = 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, rt->rtc, &ctx, &rh);
    for (uint32_t i = 0; i < n; i++) {
        hit[i] = rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        t[i] = rh.ray.tfar[i];
        u[i] = rh.hit.u[i];
        v[i] = rh.hit.v[i];
        triangle[i] = rh.hit.primID[i];
    }
}

int gi_rt_intersect(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax, gi_rt_hit *hit)
{
    assert(rt && hit);
    struct RTCRayHit rh;
    if (!intersect1(rt, o, d, tmin, tmax, &rh))
        return 0;
    const gi_scene *s = rt->scene;
    uint32_t tri = rh.hit.primID;
    const uint32_t *idx = s->indices + 3 * (size_t)tri;
    gi_vec3 p0 = vertex(rt, idx[0]), p1 = vertex(rt, idx[1]), p2 = vertex(rt, idx[2]);
    float b0 = 1.0f - rh.hit.u - rh.hit.v;
    gi_vec3 c = gi_v3_cross(gi_v3_sub(p1, p0), gi_v3_sub(p2, p0));
    float len = gi_v3_length(c);
    hit->t = rh.ray.tfar;
    hit->object = s->vertices[idx[0]].object;
    hit->triangle = tri;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->position = gi_v3_add(gi_v3_add(gi_v3_scale(p0, b0), gi_v3_scale(p1, rh.hit.u)),
                              gi_v3_scale(p2, rh.hit.v));
    hit->ng = len > 0.0f && isfinite(len) ? gi_v3_scale(c, 1.0f / len) : gi_v3(0.0f, 0.0f, 1.0f);
    return 1;
}

int gi_rt_occluded(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax)
{
    assert(rt);
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    r.org_x = o.x;
    r.org_y = o.y;
    r.org_z = o.z;
    r.tnear = tmin;
    r.dir_x = d.x;
    r.dir_y = d.y;
    r.dir_z = d.z;
    r.time = 0.0f;
    r.tfar = tmax;
    r.mask = ~0u;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(rt->rtc, &ctx, &r);
    return r.tfar < 0.0f; /* Embree sets -inf on a hit */
}

const float *gi_rt_positions(const gi_rt *rt)
{
    return rt->pos;
}

const float *gi_rt_normals(const gi_rt *rt)
{
    return rt->nrm;
}

float gi_rt_time(const gi_rt *rt)
{
    return rt->time;
}

const gi_scene *gi_rt_scene(const gi_rt *rt)
{
    return rt->scene;
}

const char *gi_rt_version(const gi_rt *rt)
{
    return rt->version;
}
