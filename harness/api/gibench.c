/* libgibench (gi/gibench.h): the process's GL context, plugins and scenes,
 * and one render through the CLI's render loop (render_loop.h). */
#include "gi/gibench.h"

#include "cli.h"
#include "debug_buffer.h"
#include "gibench_internal.h"
#include "gi/cache.h"
#include "gi/image.h"
#include "gi/log.h"
#include "render_loop.h"
#include "view_file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct gibench_scene {
    gi_scene *scene;
    gi_gpu_scene *gs;
    /* counts the moves of nodes (gibench_method_move): an instance made
     * before a move was prepared for another scene */
    uint64_t generation;
    /* the instance of the last gibench_render, kept for the next render
     * with the same options (render_key); NULL when none */
    gibench_method *kept;
    char *kept_key;
};

/* What one process keeps: the GL context and the plugin registry, made on
 * first use and kept until exit (the plugins' code must outlive every
 * instance, and a context per call would cost what the API saves). */
static gi_gpu *g_gpu;
static gi_plugins *g_reg;

static gi_result ensure_gpu(gi_error *err)
{
    if (g_gpu)
        return GI_OK;
    /* the same check the CLI makes before any command (GIBENCH_TIMER) */
    gi_result res = gi_timer_env_check(err);
    if (res != GI_OK)
        return res;
    g_gpu = gi_gpu_create(NULL, err);
    return g_gpu ? GI_OK : GI_ERR_GL;
}

static gi_result ensure_plugins(gi_error *err)
{
    if (!g_reg)
        g_reg = cli_load_plugins(1);
    return g_reg ? GI_OK : gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
}

gi_result gibench_json_out(json_object *j, char **out, gi_error *err)
{
    const char *text =
        json_object_to_json_string_ext(j, JSON_C_TO_STRING_PLAIN | JSON_C_TO_STRING_NOSLASHESCAPE);
    size_t n = text ? strlen(text) + 1 : 0;
    *out = n ? malloc(n) : NULL;
    if (*out)
        memcpy(*out, text, n);
    json_object_put(j);
    return *out ? GI_OK : gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
}

gibench_render_opts gibench_render_defaults(void)
{
    gibench_render_opts o;
    memset(&o, 0, sizeof o);
    o.width = o.height = 256;
    o.frames = 1;
    o.seed = 1;
    return o;
}

gi_result gibench_methods_json(char **out, gi_error *err)
{
    *out = NULL;
    gi_result res = ensure_plugins(err);
    if (res != GI_OK)
        return res;
    json_object *arr = json_object_new_array();
    for (uint32_t i = 0; i < g_reg->count; i++)
        json_object_array_add(arr, cli_method_json(&g_reg->items[i]));
    return gibench_json_out(arr, out, err);
}

gi_result gibench_scene_open(const char *path, gibench_scene **out, gi_error *err)
{
    *out = NULL;
    gi_result res = ensure_gpu(err);
    if (res != GI_OK)
        return res;
    gibench_scene *s = calloc(1, sizeof *s);
    if (!s)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    /* a scene that does not load is bad input, as for gibench render */
    s->scene = gi_scene_load(path, err);
    res = GI_ERR_INVALID_ARGUMENT;
    if (s->scene) {
        s->gs = gi_gpu_scene_upload(g_gpu, s->scene, err);
        res = s->gs ? GI_OK : GI_ERR_GL;
    }
    if (res != GI_OK) {
        gibench_scene_close(s);
        return res;
    }
    *out = s;
    return GI_OK;
}

const gi_scene *gibench_scene_of(const gibench_scene *s)
{
    return s->scene;
}

static void drop_kept(gibench_scene *s);

void gibench_scene_close(gibench_scene *s)
{
    if (!s)
        return;
    drop_kept(s);
    gi_gpu_scene_free(s->gs);
    gi_scene_free(s->scene);
    free(s);
}

gi_result gibench_scene_info_json(const gibench_scene *s, char **out, gi_error *err)
{
    const gi_scene *sc = s->scene;
    json_object *j = json_object_new_object();
    json_object_object_add(j, "path", json_object_new_string(sc->path ? sc->path : ""));
    json_object *cams = json_object_new_array();
    for (uint32_t i = 0; i < sc->camera_count; i++)
        json_object_array_add(
            cams, json_object_new_string(sc->cameras[i].name ? sc->cameras[i].name : ""));
    json_object_object_add(j, "cameras", cams);
    json_object_object_add(j, "duration", json_object_new_double(sc->animation_length));
    json_object_object_add(j, "objects", json_object_new_int64(sc->object_count));
    json_object_object_add(j, "lights", json_object_new_int64(sc->light_count));
    json_object_object_add(j, "triangles", json_object_new_int64(sc->triangle_count));
    return gibench_json_out(j, out, err);
}

/* The method, its parameters and the camera, checked as gibench render
 * checks them, with the CLI's messages. */
static gi_result resolve(const gibench_scene *s, const gibench_render_opts *o, const gi_method **m,
                         gi_params **params, int *camera, gi_error *err)
{
    char size[32];
    uint32_t w, h;
    snprintf(size, sizeof size, "%ux%u", o->width, o->height);
    if (!cli_parse_size(size, &w, &h))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --size '%s' is not WxH with " GI_IMAGE_SIZE_RULE, size);
    if (o->frames < 1 || o->frames > 1000000)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --frames '%u' is not an integer in 1..1000000", o->frames);
    if (o->warmup >= o->frames && o->frames > 1)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --warmup %u leaves no timed frame of %u", o->warmup,
                            o->frames);
    if (!(o->time >= 0) || o->time > 3.4e38f)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --time '%g' is not a non-negative number", (double)o->time);
    if (!o->method)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --method is required (see gibench methods)");
    gi_result res = ensure_plugins(err);
    if (res != GI_OK)
        return res;
    *m = gi_plugins_find(g_reg, o->method);
    if (!*m) {
        char known[512] = "";
        for (uint32_t i = 0; i < g_reg->count; i++) {
            size_t used = strlen(known);
            snprintf(known + used, sizeof known - used, "%s%s", i ? ", " : "",
                     g_reg->items[i].method->id);
        }
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "render: no method '%s' (installed: %s)",
                            o->method, known[0] ? known : "none");
    }
    *params = gi_params_parse((*m)->id, (*m)->params, o->params, o->param_count, err);
    if (!*params)
        return GI_ERR_INVALID_ARGUMENT;
    *camera = s->scene->camera_count ? 0 : -1;
    if (o->camera) {
        *camera = gi_scene_find_camera(s->scene, o->camera);
        if (*camera < 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "render: %s has no camera '%s' (%u cameras; use a name or #k)",
                                s->scene->path, o->camera, s->scene->camera_count);
    }
    return GI_OK;
}

/* The run's timings, the part of gibench render --timings that concerns
 * the method (the rest the caller knows). */
static json_object *timings_json(const render_loop *l, const gi_params *params,
                                 const cli_host *host, int reused)
{
    json_object *j = json_object_new_object();
    char *pstr = gi_params_to_string(params);
    json_object_object_add(j, "method", json_object_new_string(l->m->id));
    json_object_object_add(j, "method_version", json_object_new_string(l->m->version));
    json_object_object_add(j, "params", json_object_new_string(pstr ? pstr : ""));
    free(pstr);
    json_object_object_add(j, "gl_renderer", json_object_new_string(gi_gpu_renderer(g_gpu)));
    json_object_object_add(
        j, "timer", json_object_new_string(gi_timer_mode_name(gi_timer_get_mode(l->render_timer))));
    json_object_object_add(j, "prepare", cli_timer_json(l->prep_timer));
    json_object_object_add(j, "render", cli_timer_json(l->render_timer));
    json_object_object_add(j, "stats", json_object_get(host->stats));
    json_object_object_add(j, "reused", json_object_new_boolean(reused));
    return j;
}

struct gibench_method {
    gibench_scene *s;
    gi_params *params;
    char *cache_dir;
    cli_host host;
    int host_ready;
    render_loop l;
    uint32_t next_frame; /* the frame_index of the next frame: 0 after an update */
    uint32_t warmup;
    gi_timer_mode mode;
    int reused; /* this render's instance was kept from an earlier gibench_render */
};

void gibench_method_close(gibench_method *m)
{
    if (!m)
        return;
    render_loop_free(&m->l);
    gi_timer_free(m->l.prep_timer);
    gi_timer_free(m->l.render_timer);
    if (m->host_ready)
        cli_host_free(&m->host);
    free(m->cache_dir);
    gi_params_free(m->params);
    free(m);
}

/* The instance's loop, host and timers, as gibench render sets them up. */
static void method_setup(gibench_method *m, const gi_method *gm, const gibench_render_opts *o,
                         int camera)
{
    gi_error cerr;
    gibench_scene *s = m->s;
    /* as gibench render: without a usable cache folder, precompute afresh */
    m->cache_dir = o->no_cache ? NULL : gi_cache_dir(&cerr);
    gi_gpu_scene_set_time(s->gs, o->time);
    m->mode = gi_timer_mode_for(gi_gpu_is_software(g_gpu));
    cli_host_init(&m->host, gm->id, m->cache_dir, s->gs, gi_gpu_renderer(g_gpu),
                  gi_gpu_is_software(g_gpu));
    m->host_ready = 1;
    m->warmup = o->warmup;
    render_loop *l = &m->l;
    l->m = gm;
    l->scene = s->scene;
    l->gs = s->gs;
    l->host = &m->host;
    l->prep_timer = gi_timer_create(m->mode, 0);
    l->width = o->width;
    l->height = o->height;
    l->seed = o->seed;
    l->time = o->time;
    l->exposure = o->exposure;
    l->camera = camera;
    render_loop_target(l);
}

gi_result gibench_method_open(gibench_scene *s, const gibench_render_opts *o, gibench_method **out,
                              gi_error *err)
{
    *out = NULL;
    const gi_method *gm = NULL;
    gi_params *params = NULL;
    int camera = 0;
    gi_result res = resolve(s, o, &gm, &params, &camera, err);
    if (res != GI_OK) {
        gi_params_free(params);
        return res;
    }
    char why[256];
    if (!cli_caps_cover(gm, s->scene, 0, why, sizeof why))
        gi_log(GI_LOG_WARN,
               "render: %s in %s: the image leaves that out (a study marks this cell n/a)", why,
               s->scene->path);
    gibench_method *m = calloc(1, sizeof *m);
    if (!m) {
        gi_params_free(params);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    }
    m->s = s;
    m->params = params;
    method_setup(m, gm, o, camera);
    res = render_loop_prepare(&m->l, params, err);
    if (res != GI_OK) {
        gibench_method_close(m);
        return res;
    }
    *out = m;
    return GI_OK;
}

gi_result gibench_method_update(gibench_method *m, float time, const char *camera, gi_error *err)
{
    uint32_t flags = 0;
    if (camera) {
        int c = gi_scene_find_camera(m->s->scene, camera);
        if (c < 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "render: %s has no camera '%s' (%u cameras; use a name or #k)",
                                m->s->scene->path, camera, m->s->scene->camera_count);
        flags = c != m->l.camera ? GI_CHANGED_CAMERA : 0u;
        m->l.camera = c;
    }
    if (!(time >= 0) || time > 3.4e38f)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --time '%g' is not a non-negative number", (double)time);
    m->l.time = time;
    m->next_frame = 0;
    return render_loop_update(&m->l, time, flags, err);
}

/* The node a move names (a name or a decimal index); -1 when none. */
static int find_node(const gi_scene *s, const char *node)
{
    char *end;
    unsigned long k = strtoul(node, &end, 10);
    if (*node >= '0' && *node <= '9' && !*end)
        return k < s->node_count ? (int)k : -1;
    for (uint32_t i = 0; i < s->node_count; i++)
        if (s->nodes[i].name && !strcmp(s->nodes[i].name, node))
            return (int)i;
    return -1;
}

/* The moves as a saved view's nodes (each placement complete), checked as
 * gibench render --view checks them. */
static gi_result moves_view(const gi_scene *s, const gibench_node_move *mv, uint32_t count,
                            view_file *v, gi_error *err)
{
    if (count > VIEW_FILE_MAX_NODES)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "render: at most %d nodes move at once",
                            VIEW_FILE_MAX_NODES);
    for (uint32_t i = 0; i < count; i++) {
        int k = mv[i].node ? find_node(s, mv[i].node) : -1;
        if (k < 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "render: %s has no node '%s' (%u nodes; use a name or an index)",
                                s->path, mv[i].node ? mv[i].node : "", s->node_count);
        view_node *n = &v->nodes[v->node_count++];
        const gi_node *d = &s->nodes[k];
        n->node = (uint32_t)k;
        snprintf(n->name, sizeof n->name, "%s", d->name ? d->name : "");
        memcpy(n->translation, mv[i].has_translation ? mv[i].translation : d->translation,
               sizeof n->translation);
        memcpy(n->rotation, mv[i].has_rotation ? mv[i].rotation : d->rotation, sizeof n->rotation);
        memcpy(n->scale, mv[i].has_scale ? mv[i].scale : d->scale, sizeof n->scale);
        const float *q = n->rotation;
        float len = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(fabsf(len - 1.0f) <= 1e-3f))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "render: node '%s': rotation is not a unit quaternion", n->name);
    }
    char why[600];
    if (!view_file_check_nodes(v, s, why, sizeof why))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "render: %s", why);
    return GI_OK;
}

/* The instance made again with the scene as it stands (objects newly
 * marked moving), its prepare timed afresh. */
static gi_result method_remake(gibench_method *m, gi_error *err)
{
    render_loop *l = &m->l;
    l->m->destroy(l->inst);
    l->inst = NULL;
    gi_timer_free(l->prep_timer);
    l->prep_timer = gi_timer_create(m->mode, 0);
    gi_gpu_scene_set_time(l->gs, l->time);
    return render_loop_prepare(l, m->params, err);
}

gi_result gibench_method_move(gibench_method *m, const gibench_node_move *moves, uint32_t count,
                              gi_error *err)
{
    gi_scene *s = m->s->scene;
    view_file *v = calloc(1, sizeof *v);
    unsigned char *moved = calloc(s->node_count ? s->node_count : 1, 1);
    gi_result res = v && moved ? moves_view(s, moves, count, v, err)
                               : gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    int remake = 0;
    for (uint32_t i = 0; res == GI_OK && i < v->node_count; i++) {
        remake |= view_scene_mark_moving(s, v->nodes[i].node);
        moved[v->nodes[i].node] = 1;
    }
    if (res == GI_OK && count) {
        /* the scene's placements (and perhaps its moving marks) change: an
         * instance kept by gibench_render was prepared for the old scene */
        m->s->generation++;
        if (m->s->kept != m)
            drop_kept(m->s);
    }
    if (res == GI_OK && remake)
        res = method_remake(m, err);
    if (res == GI_OK) {
        gi_changes ch = {0, m->l.time, 0};
        view_scene_changes(s, moved, &ch.flags, &ch.moved_objects);
        view_file_apply_nodes(v, s);
        gi_gpu_scene_set_time(m->l.gs, m->l.time);
        res = m->l.m->update(m->l.inst, m->l.gs, &ch);
        if (res != GI_OK)
            res = render_loop_method_error(&m->l, "update", res, err);
        m->next_frame = 0;
    }
    free(moved);
    free(v);
    return res;
}

gi_result gibench_method_render(gibench_method *m, uint32_t frames, float *rgb, char **timings,
                                gi_error *err)
{
    if (timings)
        *timings = NULL;
    if (frames < 1 || frames > 1000000)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "render: --frames '%u' is not an integer in 1..1000000", frames);
    render_loop *l = &m->l;
    /* every call's frames timed afresh; the scene at this instance's time
     * (another instance on the same scene may have moved it) */
    gi_timer_free(l->render_timer);
    l->render_timer = gi_timer_create(m->mode, m->warmup < frames ? m->warmup : 0);
    gi_gpu_scene_set_time(l->gs, l->time);
    gi_result res = GI_OK;
    for (uint32_t f = 0; res == GI_OK && f < frames; f++)
        res = render_loop_frame(l, m->next_frame++, err);
    if (res != GI_OK)
        return res;
    gi_image *img = render_loop_image(l);
    if (!img)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory reading the image back");
    for (size_t i = 0; i < (size_t)l->width * l->height; i++)
        memcpy(rgb + 3 * i, img->rgba + 4 * i, 3 * sizeof(float));
    gi_image_free(img);
    return timings ? gibench_json_out(timings_json(l, m->params, &m->host, m->reused), timings, err)
                   : GI_OK;
}

/* What an instance made by gibench_render depends on besides the frames it
 * renders: the method, its parameters as parsed, the target's size, the
 * scene's time and placements, the camera, and whether the disk cache is
 * used. The seed, the exposure, the frame count and the warm-up only reach
 * the views of the frames (render_loop_frame), so a kept instance serves a
 * render that differs in them. */
static gi_result render_key(const gibench_scene *s, const gibench_render_opts *o, char **key,
                            gi_error *err)
{
    const gi_method *gm = NULL;
    gi_params *params = NULL;
    int camera = 0;
    *key = NULL;
    gi_result res = resolve(s, o, &gm, &params, &camera, err);
    if (res == GI_OK) {
        char *pstr = gi_params_to_string(params);
        size_t n = strlen(gm->id) + (pstr ? strlen(pstr) : 0) + 128;
        *key = malloc(n);
        if (*key)
            snprintf(*key, n, "%s|%s|%ux%u|%a|%d|%d|%llu", gm->id, pstr ? pstr : "", o->width,
                     o->height, (double)o->time, camera, o->no_cache ? 1 : 0,
                     (unsigned long long)s->generation);
        else
            res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        free(pstr);
    }
    gi_params_free(params);
    return res;
}

/* Instances whose image depends on how many frames they rendered before,
 * not only on frame_index, so that a kept one would not make a new one's
 * image: implicit_vis with direct=traced seeds its shadow rays with a frame
 * counter that runs on from prepare() (plugins/implicit_vis/traced.c,
 * tr->frame) and does not start again at frame_index 0. tests/python
 * checks every other method's reuse bit for bit. */
static const struct {
    const char *method, *param;
} not_kept[] = {{"implicit_vis", "direct=traced"}};

static int keepable(const char *key)
{
    for (size_t i = 0; i < sizeof not_kept / sizeof not_kept[0]; i++) {
        size_t n = strlen(not_kept[i].method), p = strlen(not_kept[i].param);
        if (strncmp(key, not_kept[i].method, n) || key[n] != '|')
            continue;
        /* the parameter as one "k=v" of the comma-separated list */
        for (const char *at = strstr(key + n + 1, not_kept[i].param); at;
             at = strstr(at + 1, not_kept[i].param))
            if ((at[-1] == '|' || at[-1] == ',') && (at[p] == ',' || at[p] == '|'))
                return 0;
    }
    return 1;
}

static void drop_kept(gibench_scene *s)
{
    gibench_method_close(s->kept);
    free(s->kept_key);
    s->kept = NULL;
    s->kept_key = NULL;
}

/* The kept instance made ready for a render as if it were new: frame 0
 * next (a method starts its accumulation and its jitter sequence again at
 * frame_index 0, gi_kit_frame_begin), the target black as
 * render_loop_target leaves it, and this render's seed, exposure and
 * warm-up. */
static void kept_restart(gibench_method *m, const gibench_render_opts *o)
{
    m->next_frame = 0;
    m->warmup = o->warmup;
    m->l.seed = o->seed;
    m->l.exposure = o->exposure;
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(m->l.target_fbo, GL_COLOR, 0, black);
}

gi_result gibench_render(gibench_scene *s, const gibench_render_opts *o, float *rgb, char **timings,
                         gi_error *err)
{
    char *key = NULL;
    gi_result res = render_key(s, o, &key, err);
    if (res != GI_OK)
        return res;
    int reuse = !o->fresh && s->kept && !strcmp(key, s->kept_key) && keepable(key);
    if (reuse) {
        free(key);
        kept_restart(s->kept, o);
    } else {
        drop_kept(s);
        res = gibench_method_open(s, o, &s->kept, err);
        if (res != GI_OK) {
            free(key);
            return res;
        }
        s->kept_key = key;
    }
    s->kept->reused = reuse;
    res = gibench_method_render(s->kept, o->frames, rgb, timings, err);
    if (res != GI_OK) /* an instance that failed is not trusted with another render */
        drop_kept(s);
    return res;
}

/* The pixels of img handed over to the caller (gibench_free) and the
 * struct released; img NULL after a failed read. */
static gi_result hand_over(gi_image *img, float **rgba, uint32_t *width, uint32_t *height)
{
    if (!img)
        return GI_ERR_IO;
    *width = img->width;
    *height = img->height;
    *rgba = img->rgba;
    img->rgba = NULL;
    gi_image_free(img);
    return GI_OK;
}

gi_result gibench_method_buffer(gibench_method *m, const char *name, float **rgba, uint32_t *width,
                                uint32_t *height, gi_error *err)
{
    *rgba = NULL;
    gi_result res = debug_buffer_check(m->l.m, name, err);
    if (res != GI_OK)
        return res;
    if (m->next_frame == 0)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "buffer: %s: %s: render a frame first (after the last update)",
                            m->l.m->id, name);
    gi_image *img = render_loop_buffer(&m->l, name, err);
    return img ? hand_over(img, rgba, width, height) : GI_ERR_IO;
}

gi_result gibench_image_read(const char *path, float **rgba, uint32_t *width, uint32_t *height,
                             gi_error *err)
{
    *rgba = NULL;
    return hand_over(gi_image_read(path, err), rgba, width, height);
}

gi_result gibench_image_read_layer(const char *path, const char *layer, float **rgba,
                                   uint32_t *width, uint32_t *height, gi_error *err)
{
    *rgba = NULL;
    return hand_over(gi_image_read_layer(path, layer, err), rgba, width, height);
}

gi_result gibench_image_write(const char *path, const float *rgb, uint32_t width, uint32_t height,
                              float exposure, gi_error *err)
{
    gi_image *img = gi_image_create(width, height);
    if (!img)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    for (size_t i = 0; i < (size_t)width * height; i++) {
        memcpy(img->rgba + 4 * i, rgb + 3 * i, 3 * sizeof(float));
        img->rgba[4 * i + 3] = 1.0f;
    }
    gi_image_write_opts wo = {exposure};
    gi_result res = gi_image_write(path, img, &wo, err);
    gi_image_free(img);
    return res;
}

void gibench_free(void *p)
{
    free(p);
}
