/* Lower-detail index lists of the scene (simplify.h), by meshoptimizer. */
#include "gi/algo/simplify.h"

#include <math.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

/* meshopt_generateShadowIndexBufferMulti takes at most 16 streams: the
 * position and up to 15 morph displacements. */
#define SIMPLIFY_MAX_STREAMS 16

/* One object's triangles simplified into out (room for all of them), as
 * indices into the whole scene's vertex array; returns the triangle count
 * and the relative error meshopt reports. */
static uint32_t simplify_object(const gi_scene *s, const gi_object *o, float ratio, float max_error,
                                uint32_t *out, uint32_t *scratch, float *positions, float *error)
{
    size_t index_count = (size_t)o->triangle_count * 3;
    *error = 0.0f;
    const uint32_t *src = &s->indices[(size_t)o->first_triangle * 3];
    if (ratio >= 1.0f || o->triangle_count == 0) {
        memcpy(out, src, index_count * sizeof *out);
        return o->triangle_count;
    }
    /* Object-local indices and positions (the rest pose). */
    uint32_t *local = scratch, *merged = scratch + index_count;
    for (size_t i = 0; i < index_count; i++)
        local[i] = src[i] - o->first_vertex;
    for (uint32_t v = 0; v < o->vertex_count; v++)
        memcpy(&positions[3 * (size_t)v], s->vertices[o->first_vertex + v].position,
               3 * sizeof(float));
    /* Merge vertices at equal positions (and equal morph displacements, so
     * that merged vertices keep moving together). */
    if (o->morph_count + 1 <= SIMPLIFY_MAX_STREAMS) {
        struct meshopt_Stream streams[SIMPLIFY_MAX_STREAMS];
        streams[0] = (struct meshopt_Stream){positions, 3 * sizeof(float), 3 * sizeof(float)};
        for (uint32_t k = 0; k < o->morph_count; k++)
            streams[1 + k] =
                (struct meshopt_Stream){&o->morph_positions[(size_t)k * o->vertex_count * 3],
                                        3 * sizeof(float), 3 * sizeof(float)};
        meshopt_generateShadowIndexBufferMulti(merged, local, index_count, o->vertex_count, streams,
                                               1 + o->morph_count);
    } else {
        memcpy(merged, local, index_count * sizeof *merged);
    }
    size_t target = (size_t)ceil((double)ratio * (double)o->triangle_count) * 3;
    size_t n = meshopt_simplify(out, merged, index_count, positions, o->vertex_count,
                                3 * sizeof(float), target, max_error, 0, error);
    for (size_t i = 0; i < n; i++)
        out[i] += o->first_vertex;
    return (uint32_t)(n / 3);
}

gi_simplified *gi_simplify_scene(const gi_scene *s, float ratio, float max_error, gi_error *err)
{
    if (!(ratio > 0.0f && ratio <= 1.0f) || !(max_error >= 0.0f)) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "simplify: ratio %g must be in (0, 1] and max_error %g >= 0", (double)ratio,
                     (double)max_error);
        return NULL;
    }
    gi_simplified *m = calloc(1, sizeof *m);
    uint32_t max_tris = 0, max_verts = 0;
    for (uint32_t i = 0; i < s->object_count; i++) {
        max_tris =
            s->objects[i].triangle_count > max_tris ? s->objects[i].triangle_count : max_tris;
        max_verts = s->objects[i].vertex_count > max_verts ? s->objects[i].vertex_count : max_verts;
    }
    uint32_t *scratch = malloc(((size_t)max_tris * 6 + 1) * sizeof *scratch);
    float *positions = malloc(((size_t)max_verts * 3 + 1) * sizeof *positions);
    if (m) {
        m->indices = malloc(((size_t)s->triangle_count * 3 + 1) * sizeof *m->indices);
        m->object_first = calloc(s->object_count + 1, sizeof *m->object_first);
        m->object_count = calloc(s->object_count + 1, sizeof *m->object_count);
    }
    if (!m || !scratch || !positions || !m->indices || !m->object_first || !m->object_count) {
        free(scratch);
        free(positions);
        gi_simplified_free(m);
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "simplify: out of memory");
        return NULL;
    }
    for (uint32_t i = 0; i < s->object_count; i++) {
        float e = 0.0f;
        m->object_first[i] = m->triangle_count;
        m->object_count[i] =
            simplify_object(s, &s->objects[i], ratio, max_error,
                            &m->indices[(size_t)m->triangle_count * 3], scratch, positions, &e);
        m->triangle_count += m->object_count[i];
        m->max_error = fmaxf(m->max_error, e);
    }
    free(scratch);
    free(positions);
    return m;
}

gi_result gi_simplified_upload(gi_simplified *m, gi_error *err)
{
    if (m->ibo)
        glDeleteBuffers(1, &m->ibo);
    glCreateBuffers(1, &m->ibo);
    glNamedBufferStorage(m->ibo,
                         (GLsizeiptr)(((size_t)m->triangle_count * 3 + 1) * sizeof *m->indices),
                         m->indices, 0);
    return gi_gl_check("simplify: upload", err);
}

void gi_simplified_free(gi_simplified *m)
{
    if (!m)
        return;
    if (m->ibo)
        glDeleteBuffers(1, &m->ibo);
    free(m->indices);
    free(m->object_first);
    free(m->object_count);
    free(m);
}

void gi_simplified_draw(const gi_simplified *m, const gi_gpu_scene *gs, GLsizei instances)
{
    gi_gpu_scene_draw_indices(gs, m->ibo, m->triangle_count * 3, instances);
}
