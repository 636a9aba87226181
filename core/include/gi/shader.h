/* Shader programs built from GLSL sources embedded at build time.
 *
 * Every .glsl/.vert/.frag/.geom/.comp file under core/shaders/ and under
 * plugins/<name>/shaders/ is compiled into the binary (core: the gicore
 * library; plugins: their own table, registered with gi_shader_register).
 * A source may `#include "name.glsl"`: the name is looked up in the core's
 * sources, then in the including file's own table, then in every registered
 * table (a name two plugins' tables share is then an error: name it by its
 * path). A table that reuses a core shader's name is refused when it is
 * registered, never silently shadowed. Lines are tagged with #line so
 * that a compile error reads "core/shaders/brdf.glsl:42: message".
 * The `#version 450 core` line is added by the builder; sources must not
 * contain one.
 */
#ifndef GI_SHADER_H
#define GI_SHADER_H

#include <epoxy/gl.h>

#include "gi/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_shader_source {
    const char *name; /* "brdf.glsl" - what #include names */
    const char *path; /* "core/shaders/brdf.glsl" - what error messages name */
    const char *text;
} gi_shader_source;

/* Adds a table of sources (static storage, NULL-name terminated) to the
 * lookup. Plugins register theirs in create() (gi_kit_init does).
 * Registering the same table twice is harmless. GI_ERR_INVALID_ARGUMENT
 * with the reason in err (may be NULL) when one of its names is a core
 * shader's. */
gi_result gi_shader_register(const gi_shader_source *table, gi_error *err);
/* Finds a source by name (or path) as #include does from the top level;
 * NULL when unknown or ambiguous. */
const gi_shader_source *gi_shader_find(const char *name);

/* Expands #include directives of `name`, prefixes #version and `defines`
 * (e.g. "#define S 16\n", may be NULL). Result is malloc'd; NULL + err on
 * a missing include or include cycle. */
char *gi_shader_expand(const char *name, const char *defines, gi_error *err);

/* Builds a program from named stages (any of them NULL). Returns 0 and
 * writes "path:line: message" (the first error) into err on failure. */
GLuint gi_program_build(const char *vert, const char *geom, const char *frag, const char *defines,
                        gi_error *err);
GLuint gi_program_build_compute(const char *comp, const char *defines, gi_error *err);
/* The same from literal source text (tests, one-off passes); `label` names
 * it in errors. Includes work as above. */
GLuint gi_program_build_compute_text(const char *label, const char *text, const char *defines,
                                     gi_error *err);
/* A vertex + fragment program from literal text (without #version). */
GLuint gi_program_build_text(const char *label, const char *vert_text, const char *frag_text,
                             const char *defines, gi_error *err);

#ifdef __cplusplus
}
#endif
#endif
