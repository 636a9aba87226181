/* gibench info: what a scene file holds, after validation. */
#include "cli.h"

#include "gi/scene.h"

#include <stdio.h>
#include <string.h>

static json_object *vec3_json(const float *v)
{
    json_object *a = json_object_new_array();
    for (int i = 0; i < 3; i++)
        json_object_array_add(a, json_object_new_double(v[i]));
    return a;
}

static const char *light_type(gi_light_type t)
{
    return t == GI_LIGHT_POINT ? "point" : t == GI_LIGHT_SPOT ? "spot" : "directional";
}

static json_object *scene_json(const gi_scene *s)
{
    json_object *o = json_object_new_object();
    json_object_object_add(o, "path", json_object_new_string(s->path));
    json_object_object_add(o, "triangles", json_object_new_int64(s->triangle_count));
    json_object_object_add(o, "vertices", json_object_new_int64(s->vertex_count));
    json_object_object_add(o, "emissive_triangles", json_object_new_int64(s->emitter_count));
    json_object_object_add(o, "animation_length", json_object_new_double(s->animation_length));
    json_object *b = json_object_new_array();
    for (int i = 0; i < 6; i++)
        json_object_array_add(b, json_object_new_double(s->bounds[i]));
    json_object_object_add(o, "bounds", b);
    json_object *objs = json_object_new_array();
    for (uint32_t i = 0; i < s->object_count; i++) {
        json_object *x = json_object_new_object();
        json_object_object_add(
            x, "name", json_object_new_string(s->objects[i].name ? s->objects[i].name : ""));
        json_object_object_add(x, "triangles", json_object_new_int64(s->objects[i].triangle_count));
        json_object_object_add(x, "animated", json_object_new_boolean(s->objects[i].animated));
        json_object_object_add(x, "morph_targets",
                               json_object_new_int64(s->objects[i].morph_count));
        json_object_object_add(x, "morph_animated",
                               json_object_new_boolean(s->objects[i].morph_track.count > 0));
        json_object_array_add(objs, x);
    }
    json_object_object_add(o, "objects", objs);
    json_object *mats = json_object_new_array();
    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *m = &s->materials[i];
        json_object *x = json_object_new_object();
        json_object_object_add(x, "name", json_object_new_string(m->name ? m->name : ""));
        json_object_object_add(x, "albedo", vec3_json(m->albedo));
        json_object_object_add(x, "textured", json_object_new_boolean(m->albedo_texture >= 0));
        json_object_object_add(x, "ks", vec3_json(m->ks));
        json_object_object_add(x, "exponent", json_object_new_double(m->exponent));
        json_object_object_add(x, "mirror", json_object_new_boolean(m->mirror));
        json_object_object_add(x, "emission", vec3_json(m->emission));
        json_object_array_add(mats, x);
    }
    json_object_object_add(o, "materials", mats);
    json_object *lights = json_object_new_array();
    for (uint32_t i = 0; i < s->light_count; i++) {
        json_object *x = json_object_new_object();
        json_object_object_add(x, "name",
                               json_object_new_string(s->lights[i].name ? s->lights[i].name : ""));
        json_object_object_add(x, "type", json_object_new_string(light_type(s->lights[i].type)));
        json_object_object_add(x, "intensity", vec3_json(s->lights[i].intensity));
        json_object_array_add(lights, x);
    }
    json_object_object_add(o, "lights", lights);
    json_object *cams = json_object_new_array();
    for (uint32_t i = 0; i < s->camera_count; i++) {
        json_object *x = json_object_new_object();
        json_object_object_add(
            x, "name", json_object_new_string(s->cameras[i].name ? s->cameras[i].name : ""));
        json_object_object_add(x, "yfov_deg",
                               json_object_new_double(s->cameras[i].yfov * 180.0 / GI_PI));
        json_object_array_add(cams, x);
    }
    json_object_object_add(o, "cameras", cams);
    if (s->has_environment) {
        json_object *e = json_object_new_object();
        json_object_object_add(e, "uri", json_object_new_string(s->environment.uri));
        json_object_object_add(e, "intensity", json_object_new_double(s->environment.intensity));
        json_object_object_add(e, "rotation_deg",
                               json_object_new_double(s->environment.rotation_deg));
        json_object_object_add(o, "environment", e);
    }
    return o;
}

static void print_scene(const gi_scene *s)
{
    printf("%s\n", s->path);
    printf("  %u triangles, %u vertices, %u objects, %u materials, %u textures\n",
           s->triangle_count, s->vertex_count, s->object_count, s->material_count,
           s->texture_count);
    printf("  bounds [%g %g %g] - [%g %g %g]\n", s->bounds[0], s->bounds[1], s->bounds[2],
           s->bounds[3], s->bounds[4], s->bounds[5]);
    printf("  lights: %u emissive triangles, %u punctual%s%s\n", s->emitter_count, s->light_count,
           s->has_environment ? ", environment " : "",
           s->has_environment ? s->environment.uri : "");
    if (s->animation_length > 0)
        printf("  animation: %g s\n", s->animation_length);
    for (uint32_t i = 0; i < s->object_count; i++) {
        printf("  object %u %-20s %7u triangles%s", i, s->objects[i].name ? s->objects[i].name : "",
               s->objects[i].triangle_count, s->objects[i].animated ? " (animated)" : "");
        if (s->objects[i].morph_count)
            printf(", %u morph targets%s", s->objects[i].morph_count,
                   s->objects[i].morph_track.count ? " (weights animated)" : "");
        printf("\n");
    }
    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *m = &s->materials[i];
        printf("  material %u %-18s albedo (%.3g %.3g %.3g)%s", i, m->name ? m->name : "",
               m->albedo[0], m->albedo[1], m->albedo[2],
               m->albedo_texture >= 0 ? " x texture" : "");
        if (m->mirror)
            printf(" mirror ks (%.3g %.3g %.3g)", m->ks[0], m->ks[1], m->ks[2]);
        else if (m->ks[0] + m->ks[1] + m->ks[2] > 0)
            printf(" phong ks (%.3g %.3g %.3g) n %g", m->ks[0], m->ks[1], m->ks[2], m->exponent);
        if (m->emission[0] + m->emission[1] + m->emission[2] > 0)
            printf(" emits (%.4g %.4g %.4g)", m->emission[0], m->emission[1], m->emission[2]);
        printf("\n");
    }
    for (uint32_t i = 0; i < s->light_count; i++)
        printf("  light %u %s %s intensity (%.4g %.4g %.4g)\n", i,
               s->lights[i].name ? s->lights[i].name : "", light_type(s->lights[i].type),
               s->lights[i].intensity[0], s->lights[i].intensity[1], s->lights[i].intensity[2]);
    for (uint32_t i = 0; i < s->camera_count; i++)
        printf("  camera %u %s yfov %.1f deg\n", i, s->cameras[i].name ? s->cameras[i].name : "",
               s->cameras[i].yfov * 180.0 / GI_PI);
}

int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    int json = 0;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (argv[i][0] == '-')
            return cli_fail(EXIT_USAGE, "info: unknown option '%s'", argv[i]);
        else if (path)
            return cli_fail(EXIT_USAGE, "info: one scene at a time ('%s' and '%s')", path, argv[i]);
        else
            path = argv[i];
    }
    if (!path)
        return cli_fail(EXIT_USAGE, "info: no scene given (gibench info SCENE [--json])");
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    if (json) {
        json_object *o = scene_json(s);
        puts(json_object_to_json_string_ext(o, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                                   JSON_C_TO_STRING_NOSLASHESCAPE));
        json_object_put(o);
    } else {
        print_scene(s);
    }
    gi_scene_free(s);
    return EXIT_OK;
}
