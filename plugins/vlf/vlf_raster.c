/* Propagation of the vlf light field by the rasteriser (paper §3.2, §3.3,
 * §5; plugins/vlf/README.md "Propagation by the rasteriser"): per fixed
 * direction the faces, in the depth order of the sort stage, are drawn
 * orthographically along it into the radiance interface, a render target
 * of the subfield's (N S)^2 rays; each fragment reads the interface as the
 * faces drawn before it left it (GL_EXT_shader_framebuffer_fetch, whose
 * reads are ordered like blending, in primitive order per pixel), so the
 * rasteriser resolves visibility as the paper's does. Receivers add their
 * flux into accumulators (64-bit fixed point, deterministic); a compute pass of
 * vlf_gpu.c then settles them into the maps, and the scattering and the
 * end of an iteration are vlf_gpu.c's passes. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi/glsl_shared.h"
#include "gi/gpu.h"
#include "gi/shader.h"
#include "vlf_gpu.h"

/* Buffers of vlf_gpu this file fills (their binding after
 * GI_SSBO_PLUGIN_FIRST, as in shaders/vlf_raster.vert and .frag). */
enum { B_TRI_P = 16, B_ORDER = 17, B_EXTRA = 18, B_CHARTS = 19 };
/* The barrier variant's texture units for the interfaces and the counters
 * (GI_TEX_PLUGIN_FIRST + 1 and + 2 in shaders/vlf_raster.frag). */
enum { VLF_TEX_RI = GI_TEX_PLUGIN_FIRST + 1 };

static int has_extension(const char *name)
{
    GLint n = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &n);
    for (GLint k = 0; k < n; k++)
        if (strcmp((const char *)glGetStringi(GL_EXTENSIONS, (GLuint)k), name) == 0)
            return 1;
    return 0;
}

/* The three programs with the variant's define. 1, or 0 with e set. */
static int build_programs(vlf_raster *r, gi_error *e)
{
    const char *v = r->barrier ? "#define VLF_BARRIER 1\n" : "";
    char d[3][96];
    snprintf(d[0], sizeof d[0], "%s", v);
    snprintf(d[1], sizeof d[1], "%s#define VLF_ESCAPE 1\n", v);
    snprintf(d[2], sizeof d[2], "%s#define VLF_INIT 1\n", v);
    GLuint *p[3] = {&r->draw, &r->escape, &r->init};
    for (int k = 0; k < 3; k++)
        if (!(*p[k] = gi_program_build("vlf_raster.vert", NULL, "vlf_raster.frag", d[k], e)))
            return 0;
    return 1;
}

gi_result vlf_raster_init(vlf_raster *r, int sync, gi_error *err)
{
    memset(r, 0, sizeof *r);
    /* the interface's read-modify-write in draw order: by the fetch
     * extension where the GL has it (or it is asked for), else in layers
     * between texture barriers (GL 4.5 core, vlf_layers.c) */
    int fetch = has_extension("GL_EXT_shader_framebuffer_fetch");
    if (sync == VLF_SYNC_FETCH && !fetch)
        return gi_error_set(err, GI_ERR_UNSUPPORTED,
                            "vlf: raster_sync = fetch needs GL_EXT_shader_framebuffer_fetch, which "
                            "this GL (%s) lacks",
                            (const char *)glGetString(GL_RENDERER));
    r->barrier = sync == VLF_SYNC_BARRIER || !fetch;
    gi_error e;
    if (!build_programs(r, &e)) {
        vlf_raster_free(r);
        return gi_error_set(err, GI_ERR_GL, "vlf: raster propagation: %s", e.text);
    }
    return GI_OK;
}

void vlf_raster_free(vlf_raster *r)
{
    if (r->draw)
        glDeleteProgram(r->draw);
    if (r->escape)
        glDeleteProgram(r->escape);
    if (r->init)
        glDeleteProgram(r->init);
    if (r->dirs)
        glDeleteBuffers(1, &r->dirs);
    if (r->signed_dirs)
        glDeleteBuffers(1, &r->signed_dirs);
    if (r->fbo)
        glDeleteFramebuffers(1, &r->fbo);
    if (r->tex[0])
        glDeleteTextures(2, r->tex);
    if (r->vao)
        glDeleteVertexArrays(1, &r->vao);
    free(r->order_first), free(r->order_count), free(r->extra_first);
    free(r->layer_first), free(r->layer_start);
    memset(r, 0, sizeof *r);
}

static void put(GLuint b, const void *data, size_t bytes)
{
    static const uint32_t zero[4] = {0, 0, 0, 0};
    glNamedBufferData(b, (GLsizeiptr)(bytes ? bytes : sizeof zero), bytes ? data : zero,
                      GL_DYNAMIC_DRAW);
}

/* The scene's triangles (three corners a triangle, VLF coordinates, the
 * face index in the fourth word) and the faces' charts (axes, density, W,
 * H, first element, twin). 1, or 0 out of memory. */
static int upload_geometry(GLuint *buf, const vlf_field *f)
{
    uint32_t *tri = malloc(((size_t)f->sort_count * 12 + 4) * sizeof *tri);
    float *charts = calloc((size_t)f->face_count * 12 + 4, sizeof *charts);
    if (!tri || !charts) {
        free(tri), free(charts);
        return 0;
    }
    for (uint32_t t = 0; t < f->sort_count; t++)
        for (uint32_t c = 0; c < 3; c++) {
            uint32_t *w = tri + 12 * (size_t)t + 4 * c;
            memcpy(w, &f->sort_p[3 * (size_t)t + c], 3 * sizeof(float));
            w[3] = f->sort_face[t];
        }
    for (uint32_t i = 0; i < f->face_count; i++) {
        const vlf_face *fc = &f->faces[i];
        float *C = charts + 12 * (size_t)i;
        memcpy(C, &fc->t, 3 * sizeof(float));
        C[3] = f->prm.density;
        memcpy(C + 4, &fc->b, 3 * sizeof(float));
        uint32_t w[4] = {fc->W, fc->H, fc->first_elem, fc->twin >= 0 ? (uint32_t)fc->twin : 0u};
        memcpy(C + 8, w, sizeof w);
    }
    put(buf[B_TRI_P], tri, (size_t)f->sort_count * 12 * sizeof *tri);
    put(buf[B_CHARTS], charts, (size_t)f->face_count * 12 * sizeof *charts);
    free(tri), free(charts);
    return 1;
}

/* Every subfield's order and piece triangles, one after another. 1, or 0
 * out of memory. */
static int upload_orders(vlf_raster *r, GLuint *buf, const vlf_field *f)
{
    uint32_t l = f->prm.l;
    size_t no = 0, ne = 0;
    r->order_first = calloc(l, sizeof(uint32_t));
    r->order_count = calloc(l, sizeof(uint32_t));
    r->extra_first = calloc(l, sizeof(uint32_t));
    if (!r->order_first || !r->order_count || !r->extra_first)
        return 0;
    for (uint32_t i = 0; i < l; i++) {
        r->order_first[i] = (uint32_t)no;
        r->order_count[i] = f->psf[i].rorder_count;
        r->extra_first[i] = (uint32_t)ne;
        no += f->psf[i].rorder_count;
        ne += f->psf[i].rextra_count;
    }
    glNamedBufferData(buf[B_ORDER], (GLsizeiptr)((no + 1) * sizeof(uint32_t)), NULL,
                      GL_DYNAMIC_DRAW);
    glNamedBufferData(buf[B_EXTRA], (GLsizeiptr)((ne * 12 + 4) * sizeof(uint32_t)), NULL,
                      GL_DYNAMIC_DRAW);
    if (r->barrier) {
        /* the entries in layers (vlf_layers.c), drawn without reversal */
        uint32_t *ord = malloc((no + 1) * sizeof *ord);
        gi_error e;
        if (!ord || vlf_raster_layers(r, f, ord, &e) != GI_OK) {
            free(ord);
            return 0;
        }
        glNamedBufferSubData(buf[B_ORDER], 0, (GLsizeiptr)(no * sizeof *ord), ord);
        free(ord);
    }
    for (uint32_t i = 0; i < l; i++) {
        const vlf_psf *p = &f->psf[i];
        if (p->rorder_count && !r->barrier)
            glNamedBufferSubData(buf[B_ORDER], (GLintptr)(r->order_first[i] * sizeof(uint32_t)),
                                 (GLsizeiptr)(p->rorder_count * sizeof(uint32_t)), p->rorder);
        if (p->rextra_count)
            glNamedBufferSubData(
                buf[B_EXTRA], (GLintptr)((size_t)r->extra_first[i] * 12 * sizeof(uint32_t)),
                (GLsizeiptr)((size_t)p->rextra_count * 12 * sizeof(uint32_t)), p->rextra);
    }
    return 1;
}

/* The interfaces and the counters: an atlas of TX x TY tiles of (N S)^2
 * rays, a batch of directions, two RGBA32F render targets (at most 2048^2
 * texels each: at N S = 128, 256 directions a batch). */
static gi_result make_target(vlf_raster *r, uint32_t NS, uint32_t l, gi_error *err)
{
    uint32_t TX = 2048 / NS < 1 ? 1 : 2048 / NS;
    uint32_t TY = TX, batch = TX * TY < l ? TX * TY : l;
    if (TX > batch)
        TX = batch;
    TY = (batch + TX - 1) / TX;
    r->batch = batch;
    if (r->fbo && r->NS == NS && r->TX == TX && r->TY == TY)
        return GI_OK;
    if (r->fbo) {
        glDeleteFramebuffers(1, &r->fbo);
        glDeleteTextures(2, r->tex);
    }
    r->NS = NS, r->TX = TX, r->TY = TY, r->batch = batch;
    glCreateTextures(GL_TEXTURE_2D, 2, r->tex);
    glCreateFramebuffers(1, &r->fbo);
    for (int k = 0; k < 2; k++) {
        glTextureStorage2D(r->tex[k], 1, GL_RGBA32F, (GLsizei)(TX * NS), (GLsizei)(TY * NS));
        glTextureParameteri(r->tex[k], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(r->tex[k], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glNamedFramebufferTexture(r->fbo, GL_COLOR_ATTACHMENT0 + (GLenum)k, r->tex[k], 0);
    }
    static const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(r->fbo, 2, bufs);
    if (glCheckNamedFramebufferStatus(r->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return gi_error_set(err, GI_ERR_GL, "vlf: raster propagation: incomplete render target");
    if (!r->vao)
        glCreateVertexArrays(1, &r->vao);
    return GI_OK;
}

/* Per fixed direction: first entry of its order, entries, first piece
 * triangle (uvec4). 1, or 0 out of memory. */
static int upload_dirs(vlf_raster *r, const vlf_field *f)
{
    uint32_t l = f->prm.l;
    uint32_t *d = calloc((size_t)l * 4, sizeof *d);
    if (!d)
        return 0;
    for (uint32_t i = 0; i < l; i++)
        d[4 * i] = r->order_first[i], d[4 * i + 1] = r->order_count[i],
              d[4 * i + 2] = r->extra_first[i];
    if (!r->dirs)
        glCreateBuffers(1, &r->dirs);
    if (!r->signed_dirs)
        glCreateBuffers(1, &r->signed_dirs);
    put(r->dirs, d, (size_t)l * 4 * sizeof *d);
    free(d);
    glNamedBufferData(r->signed_dirs, (GLsizeiptr)((size_t)2 * l * 8 * sizeof(float)), NULL,
                      GL_DYNAMIC_DRAW);
    return 1;
}

gi_result vlf_raster_setup(vlf_raster *r, GLuint *buf, const vlf_field *f, gi_error *err)
{
    if (!f->prm.raster || f->prm.order == VLF_ORDER_RAYS)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "vlf: propagate = raster draws the faces' order (order = faces)");
    free(r->order_first), free(r->order_count), free(r->extra_first);
    r->order_first = r->order_count = r->extra_first = NULL;
    if (!upload_geometry(buf, f) || !upload_orders(r, buf, f) || !upload_dirs(r, f))
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "vlf: out of memory setting up the raster propagation");
    return make_target(r, f->prm.N * f->prm.S, f->prm.l, err);
}

static void set_u(GLuint p, const char *name, uint32_t v)
{
    glProgramUniform1ui(p, glGetUniformLocation(p, name), v);
}

static void set_f(GLuint p, const char *name, float v)
{
    glProgramUniform1f(p, glGetUniformLocation(p, name), v);
}

void vlf_raster_constants(vlf_raster *r, const vlf_field *f, float cell_area)
{
    GLuint progs[3] = {r->draw, r->escape, r->init};
    for (int k = 0; k < 3; k++) {
        GLuint P = progs[k];
        set_u(P, "u_l", f->prm.l);
        set_u(P, "u_S", f->prm.S);
        set_u(P, "u_NS", r->NS);
        set_u(P, "u_TX", r->TX);
        set_u(P, "u_TY", r->TY);
        set_u(P, "u_ne", f->elem_count * 3);
        set_f(P, "u_cell_area", cell_area);
        set_f(P, "u_min_area", 1.0f / (64.0f * f->prm.density * f->prm.density));
        set_f(P, "u_inv_s2", 1.0f / (float)(f->prm.S * f->prm.S));
    }
    /* per signed direction: travel direction, solid angle; the sky is
     * written per iteration */
    uint32_t l = f->prm.l;
    float *sd = calloc((size_t)2 * l * 8, sizeof *sd);
    if (sd) {
        for (uint32_t k = 0; k < 2 * l; k++) {
            memcpy(sd + 8 * k, &f->dirs.signed_dirs[k], 3 * sizeof(float));
            sd[8 * k + 3] = f->dirs.solid_angle[k];
        }
        glNamedBufferSubData(r->signed_dirs, 0, (GLsizeiptr)((size_t)2 * l * 8 * sizeof *sd), sd);
        free(sd);
    }
}

void vlf_raster_clear_counters(vlf_raster *r)
{
    static const float zero[4] = {0, 0, 0, 0};
    glClearNamedFramebufferfv(r->fbo, GL_COLOR, 1, zero);
    if (r->barrier)
        glTextureBarrier();
}

/* The sky each signed direction's interface starts with this iteration
 * (vlf_sweep_sky), into the second half of each record. */
static void upload_sky(vlf_raster *r, const vlf_field *f, int first_iteration)
{
    uint32_t l = f->prm.l;
    for (uint32_t k = 0; k < 2 * l; k++) {
        float sky[4] = {0, 0, 0, 0};
        if (first_iteration)
            vlf_sweep_sky(f, k % l, k < l ? 1 : -1, 1, sky);
        glNamedBufferSubData(r->signed_dirs, (GLintptr)((8 * (size_t)k + 4) * sizeof(float)),
                             (GLsizeiptr)(4 * sizeof(float)), sky);
    }
}

/* The faces of directions first .. first + n, sign s. Fetch: one
 * sub-draw a direction, its order as vertex ids (the vertex shader
 * reverses it for s = 1). Barrier: one multi-draw a layer, each
 * direction's layers in turn (in reverse for s = 1), a texture barrier
 * after each, so that each pixel is read and written once between
 * barriers (GL 4.5 §9.3.1). */
static void draw_faces(vlf_raster *r, uint32_t first, uint32_t n, int s, GLint *starts,
                       GLsizei *counts)
{
    if (!r->barrier) {
        for (uint32_t j = 0; j < n; j++) {
            starts[j] = (GLint)(3 * r->order_first[first + j]);
            counts[j] = (GLsizei)(3 * r->order_count[first + j]);
        }
        glMultiDrawArrays(GL_TRIANGLES, starts, counts, (GLsizei)n);
        return;
    }
    uint32_t most = 0;
    for (uint32_t j = 0; j < n; j++) {
        uint32_t d = first + j, L = r->layer_first[d + 1] - r->layer_first[d] - 1;
        most = L > most ? L : most;
    }
    for (uint32_t t = 0; t < most; t++) {
        GLsizei m = 0;
        for (uint32_t j = 0; j < n; j++) {
            uint32_t d = first + j, L = r->layer_first[d + 1] - r->layer_first[d] - 1;
            if (t >= L)
                continue;
            const uint32_t *ls = r->layer_start + r->layer_first[d] + (s ? L - 1 - t : t);
            starts[m] = (GLint)(3 * (r->order_first[d] + ls[0]));
            counts[m++] = (GLsizei)(3 * (ls[1] - ls[0]));
        }
        glMultiDrawArrays(GL_TRIANGLES, starts, counts, m);
        glTextureBarrier();
    }
}

/* One sweep (sign s) of directions first .. first + n: the skies, the
 * faces, the escape. */
static void draw_batch(vlf_raster *r, uint32_t first, uint32_t n, int s, GLint *starts,
                       GLsizei *counts)
{
    GLuint progs[3] = {r->init, r->draw, r->escape};
    for (int k = 0; k < 3; k++) {
        set_u(progs[k], "u_first_dir", first);
        set_u(progs[k], "u_sign", (uint32_t)s);
    }
    GLsizei w = (GLsizei)(r->TX * r->NS), h = (GLsizei)(r->TY * r->NS);
    glViewport(0, 0, w, h);
    /* each pass writes only the target it changes (an output left
     * unwritten is not kept by every driver) */
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glUseProgram(r->init);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    if (r->barrier)
        glTextureBarrier();
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glUseProgram(r->draw);
    draw_faces(r, first, n, s, starts, counts);
    glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glUseProgram(r->escape);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    if (r->barrier)
        glTextureBarrier();
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
}

gi_result vlf_raster_iteration(vlf_raster *r, const vlf_field *f, int first_iteration,
                               int (*cancelled)(void *), void *user, gi_error *err)
{
    uint32_t l = f->prm.l;
    GLint *starts = malloc(r->batch * sizeof *starts);
    GLsizei *counts = malloc(r->batch * sizeof *counts);
    if (!starts || !counts) {
        free(starts), free(counts);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "vlf: out of memory drawing the sweeps");
    }
    upload_sky(r, f, first_iteration);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_PLUGIN_FIRST + 20, r->dirs);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_PLUGIN_FIRST + 21, r->signed_dirs);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo);
    if (r->barrier) /* the interfaces read as textures (shaders/vlf_raster.frag) */
        glBindTextures(VLF_TEX_RI, 2, r->tex);
    glDisable(GL_DEPTH_TEST), glDisable(GL_CULL_FACE), glDisable(GL_BLEND);
    for (int k = 0; k < 4; k++)
        glEnable(GL_CLIP_DISTANCE0 + (GLenum)k);
    glBindVertexArray(r->vao);
    gi_result rc = GI_OK;
    for (uint32_t first = 0; first < l && rc == GI_OK; first += r->batch) {
        if (cancelled && cancelled(user)) {
            rc = gi_error_set(err, GI_ERR_CANCELLED, "vlf: propagation cancelled");
            break;
        }
        uint32_t n = l - first < r->batch ? l - first : r->batch;
        for (int s = 0; s < 2; s++)
            draw_batch(r, first, n, s, starts, counts);
    }
    for (int k = 0; k < 4; k++)
        glDisable(GL_CLIP_DISTANCE0 + (GLenum)k);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (r->barrier)
        glBindTextures(VLF_TEX_RI, 2, NULL);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    free(starts), free(counts);
    return rc;
}
gi_result vlf_raster_counters(vlf_raster *r, vlf_field *f, gi_error *err)
{
    size_t n = (size_t)r->TX * r->NS * r->TY * r->NS * 4;
    float *c = malloc(n * sizeof *c);
    if (!c)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "vlf: out of memory reading the GPU's counters");
    glGetTextureImage(r->tex[1], 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof *c), c);
    double sum[4] = {0, 0, 0, 0};
    for (size_t k = 0; k < n; k++)
        sum[k % 4] += c[k];
    free(c);
    f->st.flux_shot = sum[0], f->st.flux_received = sum[1], f->st.flux_back = sum[2],
    f->st.flux_escaped = sum[3];
    return GI_OK;
}
