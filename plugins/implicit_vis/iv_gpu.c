/* The implicit_vis illumination on the GPU (Sec. 4.3.1): see iv_gpu.h. */
#include "iv_gpu.h"
#include "shaders/iv_bindings.h"

#include "gi/gpu.h"
#include "gi/shader.h"

#include <stdlib.h>
#include <string.h>

/* Most work groups in one dispatch (GL guarantees 65535 per dimension). */
#define IV_MAX_GROUPS 65535u

static GLuint make_static(const void *data, size_t bytes)
{
    GLuint b;
    glCreateBuffers(1, &b);
    glNamedBufferStorage(b, (GLsizeiptr)(bytes ? bytes : 16), data, 0);
    return b;
}

static GLuint make_dynamic(size_t bytes)
{
    GLuint b;
    glCreateBuffers(1, &b);
    glNamedBufferData(b, (GLsizeiptr)(bytes ? bytes : 16), NULL, GL_DYNAMIC_DRAW);
    return b;
}

void iv_gpu_free(iv_gpu *g)
{
    if (!g)
        return;
    GLuint bufs[] = {g->ssbo_elem,   g->ssbo_children, g->ssbo_bins,   g->ssbo_geom,
                     g->ssbo_links,  g->ssbo_off,      g->ssbo_wlinks, g->ssbo_rad[0],
                     g->ssbo_rad[1], g->ssbo_out,      g->ssbo_emit,   g->ssbo_direct};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++)
        if (bufs[i])
            glDeleteBuffers(1, &bufs[i]);
    GLuint progs[] = {g->prog_emit, g->prog_weights, g->prog_pull, g->prog_gather};
    for (size_t i = 0; i < 4; i++)
        if (progs[i])
            glDeleteProgram(progs[i]);
    free(g->level_off), free(g->geom), free(g->links), free(g->off);
    free(g);
}

/* The levels: breadth-first order puts each depth in one run of nodes,
 * the first of depth d at level_off[d]. */
static gi_result find_levels(iv_gpu *g, const iv_hier *h, gi_error *err)
{
    uint8_t *depth = calloc(h->node_count, 1);
    g->level_off = calloc((size_t)h->depth + 2, sizeof *g->level_off);
    if (!depth || !g->level_off) {
        free(depth);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "implicit_vis: out of memory for the GPU illumination");
    }
    for (uint32_t i = 0; i < h->node_count; i++) {
        depth[i] = h->parent[i] < 0 ? 0 : (uint8_t)(depth[h->parent[i]] + 1);
        if (depth[i] >= h->depth || (i > 0 && depth[i] < depth[i - 1])) {
            free(depth);
            return gi_error_set(
                err, GI_ERR_INVALID_ARGUMENT,
                "implicit_vis: the hierarchy's nodes are not in breadth-first order");
        }
    }
    g->levels = h->node_count ? depth[h->node_count - 1] + 1u : 0u;
    for (uint32_t d = 0, i = 0; d <= g->levels; d++) {
        while (i < h->node_count && depth[i] < d)
            i++;
        g->level_off[d] = i;
    }
    free(depth);
    return GI_OK;
}

/* What stays the same every frame, uploaded: per element its albedo,
 * emission, leaf and two-sided emission (IvElem), per node its children,
 * per bin its direction, solid angle and the environment through it; and
 * the staging of the frame's geometry and link offsets. */
static gi_result upload_static(iv_gpu *g, const iv_hier *h, const iv_links *l, const gi_envmap *env,
                               gi_error *err)
{
    uint32_t *elem = calloc((size_t)h->elem_count * 12 + 1, sizeof(uint32_t));
    uint32_t *children = calloc((size_t)h->node_count * 2 + 1, sizeof(uint32_t));
    float *bins = calloc((size_t)l->bins * 8, sizeof(float));
    g->geom = malloc((size_t)h->node_count * 8 * sizeof(float) + 1);
    g->off = malloc(((size_t)h->elem_count + 1) * 2 * sizeof(uint32_t));
    if (!elem || !children || !bins || !g->geom || !g->off) {
        free(elem), free(children), free(bins);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "implicit_vis: out of memory for the GPU illumination");
    }
    for (uint32_t e = 0; e < h->elem_count; e++) {
        float f[8];
        memcpy(f, &h->elem_albedo[3 * e], 3 * sizeof(float));
        f[3] = 0.0f;
        memcpy(f + 4, &h->elem_emit[3 * e], 3 * sizeof(float));
        f[7] = 0.0f;
        memcpy(&elem[12 * (size_t)e], f, sizeof f);
        elem[12 * (size_t)e + 8] = h->elem_node[e];
        elem[12 * (size_t)e + 9] = h->elem_two_sided_emit[e] ? 1u : 0u;
    }
    for (uint32_t i = 0; i < h->node_count; i++) {
        children[2 * i] = h->first_child[i];
        children[2 * i + 1] = h->child_count[i];
    }
    for (uint32_t b = 0; b < l->bins; b++) {
        memcpy(&bins[8 * b], &l->bin_dir[3 * b], 3 * sizeof(float));
        bins[8 * b + 3] = l->bin_omega[b];
        if (env) /* Sec. 4.4: the environment seen through the bin's centre, as iv_illuminate looks
                    it up */
            gi_envmap_eval(env, gi_v3_load(&l->bin_dir[3 * b]), &bins[8 * b + 4]);
    }
    g->ssbo_elem = make_static(elem, (size_t)h->elem_count * 12 * sizeof(uint32_t));
    g->ssbo_children = make_static(children, (size_t)h->node_count * 2 * sizeof(uint32_t));
    g->ssbo_bins = make_static(bins, (size_t)l->bins * 8 * sizeof(float));
    free(elem), free(children), free(bins);
    return GI_OK;
}

/* The buffers written every frame (the links' grow as needed), and the
 * largest shader storage block this GL allows. */
static void make_frame_buffers(iv_gpu *g, const iv_hier *h)
{
    g->ssbo_geom = make_dynamic((size_t)h->node_count * 8 * sizeof(float));
    g->ssbo_off = make_dynamic(((size_t)h->elem_count + 1) * 2 * sizeof(uint32_t));
    g->ssbo_links = make_dynamic(16);
    g->ssbo_wlinks = make_dynamic(8);
    g->links_gpu = 16;
    for (int i = 0; i < 2; i++)
        g->ssbo_rad[i] = make_dynamic((size_t)h->node_count * 8 * sizeof(float));
    g->ssbo_out = make_dynamic((size_t)h->elem_count * 12 * sizeof(float));
    g->ssbo_emit = make_dynamic((size_t)h->node_count * 8 * sizeof(float));
    g->ssbo_direct = make_dynamic((size_t)h->elem_count * 8 * sizeof(float));
    GLint64 max_block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    g->max_block =
        max_block > 0 ? (size_t)max_block : (size_t)1 << 27; /* GL's minimum: 2^27 bytes */
}

iv_gpu *iv_gpu_create(const iv_hier *h, const iv_links *l, const gi_envmap *env, gi_error *err)
{
    iv_gpu *g = calloc(1, sizeof *g);
    if (!g) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                     "implicit_vis: out of memory for the GPU illumination");
        return NULL;
    }
    g->nodes = h->node_count;
    g->elems = h->elem_count;
    g->bins = l->bins;
    g->n = l->n;
    g->env = env != NULL;
    if (h->node_count >= (1u << 30)) { /* iv_weights.comp keeps a node's side in the top two bits */
        gi_error_set(err, GI_ERR_UNSUPPORTED,
                     "implicit_vis: %u nodes are too many for the GPU illumination (limit 2^30)",
                     h->node_count);
        free(g);
        return NULL;
    }
    if (find_levels(g, h, err) != GI_OK || upload_static(g, h, l, env, err) != GI_OK) {
        iv_gpu_free(g);
        return NULL;
    }
    make_frame_buffers(g, h);
    g->prog_emit = gi_program_build_compute("iv_emit.comp", NULL, err);
    g->prog_weights = g->prog_emit ? gi_program_build_compute("iv_weights.comp", NULL, err) : 0;
    g->prog_pull = g->prog_weights ? gi_program_build_compute("iv_pull.comp", NULL, err) : 0;
    g->prog_gather = g->prog_pull ? gi_program_build_compute("iv_gather.comp", NULL, err) : 0;
    if (!g->prog_gather) {
        iv_gpu_free(g);
        return NULL;
    }
    if (gi_gl_check("implicit_vis: GPU illumination set-up", err) != GI_OK) {
        iv_gpu_free(g);
        return NULL;
    }
    return g;
}

/* Runs the bound program over items first .. first + count - 1, in
 * dispatches of at most IV_MAX_GROUPS work groups, then waits for its
 * buffer writes. */
static void dispatch(GLuint p, uint32_t first, uint32_t count)
{
    GLint lb = glGetUniformLocation(p, "u_base"), lc = glGetUniformLocation(p, "u_count");
    glUniform1ui(lc, first + count);
    for (uint32_t done = 0; done < count;) {
        uint32_t groups = (count - done + IV_GROUP - 1) / IV_GROUP;
        groups = groups > IV_MAX_GROUPS ? IV_MAX_GROUPS : groups;
        glUniform1ui(lb, first + done);
        glDispatchCompute(groups, 1, 1);
        done += groups * IV_GROUP;
    }
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

/* Area-weighted pull-up of the radiance in buffer `rad`, level by level
 * from the deepest inner level to the roots. */
static void pull_up(const iv_gpu *g, GLuint rad)
{
    glUseProgram(g->prog_pull);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_RAD_DST, rad);
    for (uint32_t d = g->levels; d-- > 0;)
        if (g->level_off[d + 1] > g->level_off[d])
            dispatch(g->prog_pull, g->level_off[d], g->level_off[d + 1] - g->level_off[d]);
}

/* The traced direct irradiance (6 per element) as IvRad records (front, back). */
static gi_result upload_direct(iv_gpu *g, const float *direct, gi_error *err)
{
    float *o = calloc((size_t)g->elems * 8 + 1, sizeof(float));
    if (!o)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "implicit_vis: out of memory");
    for (uint32_t e = 0; e < g->elems; e++) {
        memcpy(&o[8 * (size_t)e], &direct[6 * (size_t)e], 3 * sizeof(float));
        memcpy(&o[8 * (size_t)e + 4], &direct[6 * (size_t)e + 3], 3 * sizeof(float));
    }
    glNamedBufferSubData(g->ssbo_direct, 0, (GLsizeiptr)((size_t)g->elems * 8 * sizeof(float)), o);
    free(o);
    return GI_OK;
}

/* The frame's node geometry and the flattened links, to the GPU: only
 * when the links were rebuilt (links_current). */
static gi_result upload_links(iv_gpu *g, const iv_links *l, const iv_hier *h, gi_error *err)
{
    /* the frame's geometry: position and area, mean normal */
    for (uint32_t i = 0; i < g->nodes; i++) {
        float *o = &g->geom[8 * (size_t)i];
        memcpy(o, &h->pos[3 * i], 3 * sizeof(float));
        o[3] = h->area[i];
        memcpy(o + 4, &h->nrm[3 * i], 3 * sizeof(float));
        o[7] = 0.0f;
    }
    glNamedBufferSubData(g->ssbo_geom, 0, (GLsizeiptr)((size_t)g->nodes * 8 * sizeof(float)),
                         g->geom);
    /* the links, flattened */
    size_t nlinks = (size_t)l->leaf_off[g->elems] + l->light_off[g->elems];
    size_t words = 4 * (nlinks ? nlinks : 1);
    if (words * sizeof(uint32_t) > g->max_block)
        return gi_error_set(
            err, GI_ERR_UNSUPPORTED,
            "implicit_vis: %zu links need %.0f MiB in one GPU buffer, more than this GL's limit of "
            "%.0f MiB: lower N or use illum=cpu",
            nlinks, (double)(words * sizeof(uint32_t)) / (1 << 20),
            (double)g->max_block / (1 << 20));
    if (words > g->links_cap) {
        uint32_t *nl = realloc(g->links, words * sizeof(uint32_t));
        if (!nl)
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                                "implicit_vis: out of memory for %zu links", nlinks);
        g->links = nl;
        g->links_cap = words;
    }
    iv_links_pack(l, h, g->links, g->off);
    if (words * sizeof(uint32_t) > g->links_gpu) {
        g->links_gpu = words * sizeof(uint32_t) + words * sizeof(uint32_t) / 4;
        glNamedBufferData(g->ssbo_links, (GLsizeiptr)g->links_gpu, NULL, GL_DYNAMIC_DRAW);
        glNamedBufferData(g->ssbo_wlinks, (GLsizeiptr)(g->links_gpu / 2), NULL, GL_DYNAMIC_DRAW);
    }
    glNamedBufferSubData(g->ssbo_links, 0, (GLsizeiptr)(words * sizeof(uint32_t)), g->links);
    glNamedBufferSubData(g->ssbo_off, 0,
                         (GLsizeiptr)(((size_t)g->elems + 1) * 2 * sizeof(uint32_t)), g->off);
    return GI_OK;
}

gi_result iv_gpu_illuminate(iv_gpu *g, const iv_links *l, const iv_hier *h, uint32_t bounces,
                            uint32_t punctual, const float *direct, gi_error *err)
{
    if (direct) {
        gi_result r = upload_direct(g, direct, err);
        if (r != GI_OK)
            return r;
    }
    if (!g->links_current) {
        gi_result r = upload_links(g, l, h, err);
        if (r != GI_OK)
            return r;
        g->links_current = 1;
    }

    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_ELEM, g->ssbo_elem);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_CHILDREN, g->ssbo_children);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_BINS, g->ssbo_bins);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_GEOM, g->ssbo_geom);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_LINKS, g->ssbo_links);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_LINK_OFF, g->ssbo_off);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_WLINKS, g->ssbo_wlinks);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_ELEM_LIGHT, g->ssbo_out);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_DIRECT, g->ssbo_direct);

    /* bounce 0: the emission, pulled up */
    int cur = 0;
    glUseProgram(g->prog_emit);
    glUniform1ui(glGetUniformLocation(g->prog_emit, "u_bins"), g->bins);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_RAD_DST, g->ssbo_rad[cur]);
    dispatch(g->prog_emit, 0, g->elems);
    glUseProgram(g->prog_weights);
    glUniform1ui(glGetUniformLocation(g->prog_weights, "u_light_base"), l->leaf_off[g->elems]);
    dispatch(g->prog_weights, 0, g->elems);
    pull_up(g, g->ssbo_rad[cur]);
    if (g->keep_emit) { /* the emission, pulled up, for the glossy display's direct light */
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glCopyNamedBufferSubData(g->ssbo_rad[cur], g->ssbo_emit, 0, 0,
                                 (GLsizeiptr)((size_t)g->nodes * 8 * sizeof(float)));
    }
    GLuint p = g->prog_gather;
    for (uint32_t k = 0; k <= bounces; k++) {
        glUseProgram(p);
        glUniform1ui(glGetUniformLocation(p, "u_n"), g->n);
        glUniform1ui(glGetUniformLocation(p, "u_bins"), g->bins);
        glUniform1i(glGetUniformLocation(p, "u_direct"), k == 0);
        glUniform1ui(glGetUniformLocation(p, "u_light_base"), l->leaf_off[g->elems]);
        glUniform1i(glGetUniformLocation(p, "u_env"), g->env);
        glUniform1i(glGetUniformLocation(p, "u_env_share"), iv_env_partial(l));
        glUniform1ui(glGetUniformLocation(p, "u_punctual"), k == 0 ? punctual : 0u);
        glUniform1i(glGetUniformLocation(p, "u_traced"), direct != NULL);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_RAD_SRC, g->ssbo_rad[cur]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_RAD_DST, g->ssbo_rad[1 - cur]);
        dispatch(p, 0, g->elems);
        cur = 1 - cur;
        if (k < bounces)
            pull_up(g, g->ssbo_rad[cur]);
    }
    glUseProgram(0);
    return gi_gl_check("implicit_vis: GPU illumination", err);
}

void iv_gpu_read(const iv_gpu *g, float *e_out)
{
    float *o = malloc((size_t)g->elems * 12 * sizeof(float) + 1);
    if (!o) {
        memset(e_out, 0, (size_t)g->elems * 6 * sizeof(float));
        return;
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(g->ssbo_out, 0, (GLsizeiptr)((size_t)g->elems * 12 * sizeof(float)), o);
    for (uint32_t e = 0; e < g->elems; e++) {
        memcpy(&e_out[6 * (size_t)e], &o[12 * (size_t)e], 3 * sizeof(float));
        memcpy(&e_out[6 * (size_t)e + 3], &o[12 * (size_t)e + 4], 3 * sizeof(float));
    }
    free(o);
}

void iv_gpu_bind_direct(const iv_gpu *g)
{
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_ELEM, g->ssbo_elem);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_BINS, g->ssbo_bins);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_GEOM, g->ssbo_geom);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_LINKS, g->ssbo_links);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_LINK_OFF, g->ssbo_off);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_WLINKS, g->ssbo_wlinks);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_RAD_SRC, g->ssbo_emit);
}
