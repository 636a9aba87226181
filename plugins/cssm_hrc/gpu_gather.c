/* cssm_hrc's per-pixel final gather as a GL compute pass (gather=gpu;
 * Ritschel et al. 2008, §4: "HRC on the GPU", the stack-less traversal of
 * §4.2 / Fig. 10 that exists so that the gather runs in a shader). The
 * hierarchy's nodes (as the C traversal reads them, float or packed and
 * decoded), the leaves, the atlas texels with their cube-map eyes and the
 * six faces' compressed CSSM go into buffers the shaders read as buffer
 * images (cssm_bindings.h says why); shaders/cssm_gather.comp gathers
 * every pixel every frame with the frame's jitter and averages the frames,
 * one program per set of the options compiled in (program_for). The C
 * path (final_gather.c) stays as the oracle (gather=cpu). */
#include "cssm_hrc.h"

#include "shaders/cssm_bindings.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One node as cssm_traverse.glsl's CssmNode lays it out (std430). */
typedef struct gpu_node {
    float c_r[4], p_area[4], n_cone[4], I[4];
    int32_t link[4];
    uint32_t rep[4];
    int32_t walk[4]; /* left, right, the probability of left (float bits), first leaf */
} gpu_node;

typedef struct gpu_texel {
    float p_area[4], n[4], eye[4]; /* eye w: the sequence index's bits */
} gpu_texel;

enum { BUF_NODES, BUF_LEAVES, BUF_TEXELS, BUF_OFFSETS, BUF_Z_AVG, BUF_I_END, BUF_STATS };

/* The buffer textures the shaders read as images (cssm_bindings.h), in
 * the order of gpu_buf, the stats' slot taken by the albedo: units and
 * formats. */
enum { TEX_ALBEDO = BUF_STATS };
static const GLuint tex_unit[CSSM_GPU_BUFFERS] = {
    CSSM_IMG_NODES, CSSM_IMG_LEAVES, CSSM_IMG_TEXELS, CSSM_IMG_OFFSETS,
    CSSM_IMG_Z_AVG, CSSM_IMG_I_END,  CSSM_IMG_ALBEDO};
static const GLenum tex_format[CSSM_GPU_BUFFERS] = {GL_RGBA32UI, GL_R32UI, GL_RGBA32UI, GL_R32UI,
                                                    GL_R32UI,    GL_R32UI, GL_RGBA32UI};

/* Each buffer texture attached to its buffer again (after the buffers'
 * storage was made anew) and bound to its image unit. */
static void bind_textures(cssm_hrc *c)
{
    if (!c->gpu_tex[0])
        glCreateTextures(GL_TEXTURE_BUFFER, CSSM_GPU_BUFFERS, c->gpu_tex);
    for (int k = 0; k < CSSM_GPU_BUFFERS; k++) {
        GLuint buf = k == TEX_ALBEDO ? c->gpu_bounce_buf[0] : c->gpu_buf[k];
        if (!buf)
            continue;
        glTextureBuffer(c->gpu_tex[k], tex_format[k], buf);
        glBindImageTexture(tex_unit[k], c->gpu_tex[k], 0, GL_FALSE, 0, GL_READ_ONLY, tex_format[k]);
    }
}

const char *cssm_gpu_unsupported(const cssm_hrc *c, const gi_scene *s)
{
    if (c->mode == 1)
        return "mode=texels (its per-pixel part; the per-texel gather runs as a pass)";
    if (c->indirect == 1)
        return "indirect=mc";
    if (c->direct == 1)
        return "direct=csm";
    if (c->motion.moving >= 0)
        return "moving objects";
    if (c->shadow_count)
        return "punctual lights";
    if (c->texel_E || (s->has_environment && s->envmap))
        return "an environment";
    return NULL;
}

void cssm_gpu_free(cssm_hrc *c)
{
    for (int k = 0; k < CSSM_GPU_PROGS; k++)
        if (c->gpu_prog[k])
            glDeleteProgram(c->gpu_prog[k]);
    for (int k = 0; k < CSSM_GPU_PROGS; k++)
        if (c->gpu_bounce_prog[k])
            glDeleteProgram(c->gpu_bounce_prog[k]);
    glDeleteBuffers(CSSM_GPU_BUFFERS, c->gpu_buf);
    glDeleteTextures(CSSM_GPU_BUFFERS, c->gpu_tex);
    memset(c->gpu_tex, 0, sizeof c->gpu_tex);
    glDeleteBuffers(2, c->gpu_bounce_buf);
    memset(c->gpu_prog, 0, sizeof c->gpu_prog);
    memset(c->gpu_bounce_prog, 0, sizeof c->gpu_bounce_prog);
    memset(c->gpu_bounce_buf, 0, sizeof c->gpu_bounce_buf);
    memset(c->gpu_buf, 0, sizeof c->gpu_buf);
}

static void upload(GLuint buf, size_t bytes, const void *data)
{
    /* an empty buffer still binds: one zero word */
    static const uint32_t zero[4] = {0};
    const GLsizeiptr n = bytes ? (GLsizeiptr)bytes : (GLsizeiptr)sizeof zero;
    GLint64 have = -1;
    glGetNamedBufferParameteri64v(buf, GL_BUFFER_SIZE, &have);
    if (have == (GLint64)n) /* same size (the nodes of each bounce and frame): keep the storage */
        glNamedBufferSubData(buf, 0, n, bytes ? data : zero);
    else
        glNamedBufferData(buf, n, bytes ? data : zero, GL_STATIC_DRAW);
}

/* The nodes a gather reads (node_L, or the packed nodes ct), decoded as
 * the C traversal decodes them, and the leaves: for the final gather light
 * set 0 (emission + reflected, as final_gather.c's gather(c, 0, ...)), for
 * a bounce the previous bounce pulled. */
static gi_result upload_nodes(cssm_hrc *c, const float *node_L, const cssm_ctree *ct)
{
    const uint32_t n = c->tree.count;
    gpu_node *g = calloc(n, sizeof *g);
    if (!g)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for the nodes");
    for (uint32_t i = 0; i < n; i++) {
        cssm_node_view v;
        cssm_node_fetch(&c->tree, node_L, ct, (int32_t)i, &v);
        gpu_node *d = &g[i];
        memcpy(d->c_r, (float[4]){v.c.x, v.c.y, v.c.z, v.r}, sizeof d->c_r);
        memcpy(d->p_area, (float[4]){v.p.x, v.p.y, v.p.z, v.area}, sizeof d->p_area);
        memcpy(d->n_cone, (float[4]){v.n.x, v.n.y, v.n.z, v.cos_cone}, sizeof d->n_cone);
        memcpy(d->I, (float[4]){v.I[0], v.I[1], v.I[2], gi_luminance(v.I)}, sizeof d->I);
        memcpy(d->link, (int32_t[4]){v.child, v.skip, (int32_t)v.first, (int32_t)v.count},
               sizeof d->link);
        d->rep[0] = v.rep;
        d->walk[0] = v.child, d->walk[3] = (int32_t)v.first;
        if (v.child >= 0) { /* pick_leaf's choice at this node, computed as hrc.c does */
            cssm_node_view l, r;
            cssm_node_fetch(&c->tree, node_L, ct, v.child, &l);
            cssm_node_fetch(&c->tree, node_L, ct, l.skip, &r);
            float il = fmaxf(0.0f, gi_luminance(l.I)), ir = fmaxf(0.0f, gi_luminance(r.I));
            float pl = il + ir > 0.0f ? il / (il + ir) : l.area / fmaxf(l.area + r.area, FLT_MIN);
            d->walk[1] = l.skip;
            memcpy(&d->walk[2], &pl, sizeof pl);
        }
    }
    upload(c->gpu_buf[BUF_NODES], n * sizeof *g, g);
    free(g);
    const uint32_t *leaves = ct ? ct->leaves : c->tree.leaves;
    upload(c->gpu_buf[BUF_LEAVES], c->atlas.count * sizeof *leaves, leaves);
    return GI_OK;
}

/* The texels (position, area, normal, cube-map eye and sequence index) and
 * the six faces' codec data, concatenated face after face. */
static gi_result upload_maps(cssm_hrc *c)
{
    const cssm_atlas *a = &c->atlas;
    const cssm_maps *m = &c->maps;
    gpu_texel *t = calloc(a->count, sizeof *t);
    if (!t)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for the maps");
    for (uint32_t i = 0; i < a->count; i++) {
        const cssm_texel *x = &a->texels[i];
        float seq;
        memcpy(&seq, &m->seq[i], sizeof seq);
        memcpy(t[i].p_area, (float[4]){x->p.x, x->p.y, x->p.z, x->area}, sizeof t[i].p_area);
        memcpy(t[i].n, (float[4]){x->n.x, x->n.y, x->n.z, 0.0f}, sizeof t[i].n);
        memcpy(t[i].eye, (float[4]){m->eye[i].x, m->eye[i].y, m->eye[i].z, seq}, sizeof t[i].eye);
    }
    upload(c->gpu_buf[BUF_TEXELS], a->count * sizeof *t, t);
    free(t);
    size_t noff = 0, nseg = 0;
    for (int f = 0; f < 6; f++) {
        c->gpu_off_base[f] = (uint32_t)noff;
        c->gpu_seg_base[f] = (uint32_t)nseg;
        noff += (size_t)m->face[f].M * m->face[f].M + 1;
        nseg += m->face[f].segment_count;
    }
    GLuint bufs[3] = {c->gpu_buf[BUF_OFFSETS], c->gpu_buf[BUF_Z_AVG], c->gpu_buf[BUF_I_END]};
    size_t sizes[3] = {noff * sizeof(uint32_t), nseg * sizeof(float), nseg * sizeof(uint32_t)};
    for (int k = 0; k < 3; k++)
        glNamedBufferData(bufs[k], (GLsizeiptr)sizes[k], NULL, GL_STATIC_DRAW);
    for (int f = 0; f < 6; f++) {
        const gi_csm_data *d = &m->face[f];
        size_t no = (size_t)d->M * d->M + 1, ns = d->segment_count;
        glNamedBufferSubData(bufs[0], (GLintptr)(c->gpu_off_base[f] * sizeof(uint32_t)),
                             (GLsizeiptr)(no * sizeof(uint32_t)), d->offsets);
        if (!ns)
            continue;
        glNamedBufferSubData(bufs[1], (GLintptr)(c->gpu_seg_base[f] * sizeof(float)),
                             (GLsizeiptr)(ns * sizeof(float)), d->z_avg);
        glNamedBufferSubData(bufs[2], (GLintptr)(c->gpu_seg_base[f] * sizeof(uint32_t)),
                             (GLsizeiptr)(ns * sizeof(uint32_t)), d->i_end);
    }
    return GI_OK;
}

/* Any receiver with a Phong lobe: a material with ks (the G-buffer's
 * phong texture is the material's ks). */
static int scene_glossy(const cssm_hrc *c)
{
    const gi_scene *s = c->kit.scene ? c->kit.scene->scene : NULL;
    if (!s)
        return 1;
    for (uint32_t m = 0; m < s->material_count; m++)
        for (int k = 0; k < 3; k++)
            if (s->materials[m].ks[k] != 0.0f)
                return 1;
    return 0;
}

/* The program of one set of the options that are defines (issue 29: on
 * llvmpipe a branch no lane takes still costs its body, so the options'
 * branches are compiled out): built on first use, kept in progs[index]. */
static GLuint program_for(GLuint *progs, const char *comp, int pcf, int jitter, int rep_centroid,
                          int glossy, gi_error *err)
{
    const int index = pcf | jitter << 1 | rep_centroid << 2 | glossy << 3;
    if (!progs[index]) {
        char defines[160];
        snprintf(defines, sizeof defines,
                 "#define CSSM_PCF %d\n#define CSSM_JITTER %d\n#define CSSM_REP_CENTROID %d\n"
                 "#define CSSM_GLOSSY %d\n",
                 pcf, jitter, rep_centroid, glossy);
        progs[index] = gi_program_build_compute(comp, defines, err);
    }
    return progs[index];
}

/* The texels, their albedo and the six CSSM faces, uploaded once per
 * prepare or update (c->gpu_maps_ok; cssm_lighting clears it), shared by
 * the final gather and the bounces; the buffers made on first use. */
static gi_result maps_setup(cssm_hrc *c)
{
    if (!c->gpu_buf[0])
        glCreateBuffers(CSSM_GPU_BUFFERS, c->gpu_buf);
    if (!c->gpu_bounce_buf[0])
        glCreateBuffers(2, c->gpu_bounce_buf);
    if (c->gpu_maps_ok)
        return GI_OK;
    const cssm_atlas *a = &c->atlas;
    float *alb = calloc(8 * (size_t)a->count + 4, sizeof *alb);
    if (!alb)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for the maps");
    for (uint32_t i = 0; i < a->count; i++) { /* albedo, then Phong ks and exponent */
        memcpy(&alb[8 * i], a->texels[i].albedo, 3 * sizeof(float));
        memcpy(&alb[8 * i + 4], a->texels[i].ks, 3 * sizeof(float));
        alb[8 * i + 7] = a->texels[i].exponent;
    }
    upload(c->gpu_bounce_buf[0], 8 * (size_t)a->count * sizeof *alb, alb);
    free(alb);
    glNamedBufferData(c->gpu_bounce_buf[1], (GLsizeiptr)(3 * (size_t)a->count + 4) * 4, NULL,
                      GL_DYNAMIC_READ);
    gi_result r = upload_maps(c);
    if (r != GI_OK)
        return r;
    c->gpu_maps_ok = 1;
    return GI_OK;
}

/* The buffers: the maps when the scene or materials changed, the nodes
 * when the lighting did (every frame with bounces_every=frame). */
static gi_result gpu_setup(cssm_hrc *c)
{
    gi_error err;
    gi_result r = maps_setup(c);
    if (r != GI_OK)
        return r;
    if (c->gpu_dirty) {
        r = upload_nodes(c, c->node_L, c->nodes ? &c->ct[0] : NULL);
        if (r != GI_OK)
            return r;
        c->gpu_dirty = 0;
    }
    return gi_gl_check("cssm_hrc: gpu gather upload", &err) == GI_OK
               ? GI_OK
               : gi_kit_fail_with(&c->kit, GI_ERR_GL, &err);
}

static void set_uniforms(const cssm_hrc *c, GLuint p, const cssm_gather_opts o)
{
    glUniform1f(glGetUniformLocation(p, "u_lim"), cssm_refine_limit(o.threshold));
    glUniform1f(glGetUniformLocation(p, "u_scale"), exp2f(o.exposure));
    glUniform1ui(glGetUniformLocation(p, "u_max_cut"), o.max_cut);
    glUniform1f(glGetUniformLocation(p, "u_clamp"), o.clamp);
    glUniform1f(glGetUniformLocation(p, "u_bias"), o.bias);
    glUniform1f(glGetUniformLocation(p, "u_lift"), 2.0f * c->maps.znear);
    glUniform1ui(glGetUniformLocation(p, "u_M"), c->maps.M);
    glUniform1uiv(glGetUniformLocation(p, "u_off_base"), 6, c->gpu_off_base);
    glUniform1uiv(glGetUniformLocation(p, "u_seg_base"), 6, c->gpu_seg_base);
}

gi_result cssm_gpu_final_gather(cssm_hrc *c, const gi_view *view, const gi_target *target,
                                int random, cssm_gather_stats *st)
{
    gi_result r = gpu_setup(c);
    if (r != GI_OK)
        return r;
    const cssm_gather_opts o = cssm_hrc_gather_opts(c, view->exposure, NULL);
    gi_error err;
    const GLuint p = program_for(c->gpu_prog, "cssm_gather.comp", o.pcf != 0, random != 0,
                                 o.rep_centroid != 0, scene_glossy(c), &err);
    if (!p)
        return gi_kit_fail_with(&c->kit, GI_ERR_GL, &err);
    const gi_host *host = c->kit.host;
    host->stage_begin(host, "final_gather");
    glUseProgram(p);
    gi_kit_bind(&c->kit, p, view, target);
    set_uniforms(c, p, o);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_SSBO_STATS, c->gpu_buf[BUF_STATS]);
    bind_textures(c);
    const uint32_t zero[4] = {0};
    glNamedBufferData(c->gpu_buf[BUF_STATS], sizeof zero, zero, GL_DYNAMIC_READ);
    gi_kit_dispatch_8x8(view->width, view->height);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT |
                    GL_BUFFER_UPDATE_BARRIER_BIT);
    glUseProgram(0);
    uint32_t got[4];
    glGetNamedBufferSubData(c->gpu_buf[BUF_STATS], 0, sizeof got, got);
    host->stage_end(host, "final_gather");
    st->nodes += got[0];
    st->receivers += got[1];
    st->clamped += got[2];
    if (gi_gl_check("cssm_hrc: gpu gather", &err) != GI_OK)
        return gi_kit_fail_with(&c->kit, GI_ERR_GL, &err);
    return GI_OK;
}

/* One per-texel pass of cssm_bounce.comp over the nodes in the node
 * buffer: program p (its defines chosen by the caller), o's options, texel
 * t's generator gi_rng_init(t, frame, stream), eye for the glossy texels
 * (NULL: a diffuse bounce); the radiance read back into out[3 N] and the
 * counts added to st. */
static gi_result texel_pass(cssm_hrc *c, GLuint p, const cssm_gather_opts *o, uint32_t frame,
                            uint32_t stream, const gi_vec3 *eye, float *out, cssm_gather_stats *st,
                            gi_error *err)
{
    glUseProgram(p);
    glUniform1ui(glGetUniformLocation(p, "u_count"), c->atlas.count);
    glUniform1f(glGetUniformLocation(p, "u_lim"), cssm_refine_limit(o->threshold));
    glUniform1f(glGetUniformLocation(p, "u_scale"), exp2f(o->exposure));
    glUniform1ui(glGetUniformLocation(p, "u_max_cut"), o->max_cut);
    glUniform1f(glGetUniformLocation(p, "u_clamp"), o->clamp);
    glUniform1f(glGetUniformLocation(p, "u_bias"), o->bias);
    glUniform1f(glGetUniformLocation(p, "u_lift"), 2.0f * c->maps.znear);
    glUniform1ui(glGetUniformLocation(p, "u_M"), c->maps.M);
    glUniform1uiv(glGetUniformLocation(p, "u_off_base"), 6, c->gpu_off_base);
    glUniform1uiv(glGetUniformLocation(p, "u_seg_base"), 6, c->gpu_seg_base);
    glUniform1ui(glGetUniformLocation(p, "u_frame"), frame);
    glUniform1ui(glGetUniformLocation(p, "u_stream"), stream);
    if (eye)
        glUniform3f(glGetUniformLocation(p, "u_eye"), eye->x, eye->y, eye->z);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_SSBO_STATS, c->gpu_buf[BUF_STATS]);
    bind_textures(c);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_SSBO_OUT, c->gpu_bounce_buf[1]);
    const uint32_t zero[4] = {0};
    glNamedBufferData(c->gpu_buf[BUF_STATS], sizeof zero, zero, GL_DYNAMIC_READ);
    glDispatchCompute((c->atlas.count + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glUseProgram(0);
    glGetNamedBufferSubData(c->gpu_bounce_buf[1], 0,
                            (GLsizeiptr)(3 * (size_t)c->atlas.count * sizeof *out), out);
    uint32_t got[4];
    glGetNamedBufferSubData(c->gpu_buf[BUF_STATS], 0, sizeof got, got);
    if (st) {
        st->nodes += got[0];
        st->receivers += got[1];
        st->clamped += got[2];
    }
    return gi_gl_check("cssm_hrc: gpu texel pass", err);
}

/* §4.1.1: one gather step for every atlas texel (cssm_gather_opts'
 * atlas_gather): the nodes of the previous bounce uploaded, one invocation
 * per texel (cssm_bounce.comp), the radiance read back into out. pass:
 * the gather's jitter stream (hrc.c gather_atlas). */
static gi_result bounce_gather(void *ctx, const float *node_L, const cssm_ctree *ct, uint32_t pass,
                               float *out, cssm_gather_stats *st, gi_error *err)
{
    cssm_hrc *c = ctx;
    const cssm_gather_opts *o = &c->bounce_opts;
    gi_result r = maps_setup(c);
    if (r == GI_OK)
        r = upload_nodes(c, node_L, ct);
    if (r != GI_OK)
        return gi_error_set(err, r, "%s", gi_kit_last_error(&c->kit));
    c->gpu_dirty = 1; /* the final gather's node buffer is overwritten by the bounces' */
    const GLuint p =
        program_for(c->gpu_bounce_prog, "cssm_bounce.comp", o->pcf != 0, o->atlas_jitter != 0,
                    o->rep_centroid != 0, 0, err); /* built by cssm_gpu_bounces */
    return texel_pass(c, p, o, o->atlas_frame, o->atlas_seed ^ (CSSM_ATLAS_SALT + pass), NULL, out,
                      st, err);
}

gi_result cssm_gpu_texel_gather(cssm_hrc *c, const gi_view *view, uint32_t frame, int random,
                                cssm_gather_stats *st)
{
    const gi_host *host = c->kit.host;
    host->stage_begin(host, "texel_gather");
    const cssm_gather_opts o = cssm_hrc_gather_opts(c, view->exposure, NULL);
    gi_error err;
    gi_result r = maps_setup(c);
    if (r == GI_OK)
        r = upload_nodes(c, c->node_B, c->nodes ? &c->ct[2] : NULL); /* light set 2: reflected */
    c->gpu_dirty = 1;
    const GLuint p = r == GI_OK ? program_for(c->gpu_bounce_prog, "cssm_bounce.comp", o.pcf != 0,
                                              random != 0, o.rep_centroid != 0, 1, &err)
                                : 0;
    if (r == GI_OK && !p)
        r = gi_kit_fail_with(&c->kit, GI_ERR_GL, &err);
    if (r == GI_OK && (r = texel_pass(c, p, &o, frame, view->seed ^ 0x7e1u, &view->eye, c->texel_T,
                                      st, &err)) != GI_OK)
        r = gi_kit_fail_with(&c->kit, r, &err);
    host->stage_end(host, "texel_gather");
    return r;
}

gi_result cssm_gpu_bounces(cssm_hrc *c, cssm_gather_opts *o)
{
    gi_error err;
    if (!program_for(c->gpu_bounce_prog, "cssm_bounce.comp", o->pcf != 0, o->atlas_jitter != 0,
                     o->rep_centroid != 0, 0, &err))
        return gi_kit_fail_with(&c->kit, GI_ERR_GL, &err);
    c->bounce_opts = *o;
    o->atlas_gather = bounce_gather;
    o->atlas_ctx = c;
    return GI_OK;
}
