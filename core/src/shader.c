/* Shader building from embedded sources with #include and file:line errors.
 *
 * Sources are registered tables (the core's own is built in). Expansion
 * splices included files in place, each at most once per program (so
 * includes need no guards), and tags every piece with `#line L S` where S
 * numbers the file; compile logs of Mesa ("0:12(7): error") and NVIDIA
 * ("0(12) : error") are mapped back to "path:line: message". */
#include "gi/shader.h"
#include "gi/log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_core_shaders[];

#define MAX_TABLES 32
#define MAX_FILES 64

/* The table registry is process-wide: GL itself is, and the tables are
 * static data. Registration happens on the GL thread only. */
static const gi_shader_source *g_tables[MAX_TABLES];
static int g_table_count;

/* Names are looked up in three places, in order: the core's shaders; the
 * table of the file that includes (so a plugin's own helpers win over
 * another plugin's of the same name); then every registered table, where
 * a name two tables define is ambiguous and an error, never a silent
 * choice. A name may also be a source's full path ("plugins/x/shaders/y.comp"),
 * which is unique. A table may not reuse a core shader's name: the core's
 * would be found first and the plugin's silently ignored. */

static const gi_shader_source *find_in(const gi_shader_source *table, const char *name)
{
    for (const gi_shader_source *s = table; s && s->name; s++)
        if (strcmp(s->name, name) == 0 || strcmp(s->path, name) == 0)
            return s;
    return NULL;
}

/* The registered table that holds `src`, or NULL (the core's, or none). */
static const gi_shader_source *table_of(const gi_shader_source *src)
{
    for (int t = 0; t < g_table_count; t++)
        for (const gi_shader_source *s = g_tables[t]; s->name; s++)
            if (s == src)
                return g_tables[t];
    return NULL;
}

gi_result gi_shader_register(const gi_shader_source *table, gi_error *err)
{
    for (int i = 0; i < g_table_count; i++)
        if (g_tables[i] == table)
            return GI_OK;
    for (const gi_shader_source *s = table; s->name; s++) {
        const gi_shader_source *core = find_in(gi_core_shaders, s->name);
        if (core)
            return gi_error_set(
                err, GI_ERR_INVALID_ARGUMENT,
                "%s: named like the core's %s, which #include and the builders find first; "
                "rename it",
                s->path, core->path);
    }
    if (g_table_count >= MAX_TABLES)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "more than %d shader tables registered",
                            MAX_TABLES);
    g_tables[g_table_count++] = table;
    return GI_OK;
}

/* Looks `name` up as described above, `from` being the including file's
 * table (NULL at the top level). */
static const gi_shader_source *lookup(const char *name, const gi_shader_source *from, gi_error *err)
{
    const gi_shader_source *s = find_in(gi_core_shaders, name);
    if (s)
        return s;
    if (from && (s = find_in(from, name)) != NULL)
        return s;
    const gi_shader_source *found = NULL;
    for (int t = 0; t < g_table_count; t++) {
        s = find_in(g_tables[t], name);
        if (!s)
            continue;
        if (found) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                         "shader name '%s' is ambiguous: %s and %s; name it by its path", name,
                         found->path, s->path);
            return NULL;
        }
        found = s;
    }
    if (!found)
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "no shader source named '%s'", name);
    return found;
}

const gi_shader_source *gi_shader_find(const char *name)
{
    gi_error err;
    return lookup(name, NULL, &err);
}

typedef struct buf {
    char *data;
    size_t len, cap;
} buf;

static int buf_add(buf *b, const char *s, size_t n)
{
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + n + 1)
            cap *= 2;
        char *d = realloc(b->data, cap);
        if (!d)
            return 0;
        b->data = d;
        b->cap = cap;
    }
    memcpy(b->data + b->len, s, n);
    b->len += n;
    b->data[b->len] = '\0';
    return 1;
}

static int buf_printf(buf *b, const char *fmt, int a, int c)
{
    char tmp[64];
    int n = snprintf(tmp, sizeof tmp, fmt, a, c);
    return buf_add(b, tmp, (size_t)n);
}

typedef struct expansion {
    const char *paths[MAX_FILES];
    int count;
} expansion;

/* Parses `#include "name"` at the start of a line (leading blanks allowed). */
static int parse_include(const char *line, size_t len, char *name, size_t size)
{
    size_t i = 0;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        i++;
    if (len - i < 8 || strncmp(line + i, "#include", 8) != 0)
        return 0;
    i += 8;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        i++;
    if (i >= len || line[i] != '"')
        return -1;
    size_t start = ++i;
    while (i < len && line[i] != '"')
        i++;
    if (i >= len || i - start + 1 > size)
        return -1;
    memcpy(name, line + start, i - start);
    name[i - start] = '\0';
    return 1;
}

static int expand_into(buf *out, expansion *ex, const gi_shader_source *src, gi_error *err)
{
    if (ex->count >= MAX_FILES) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: too many included files", src->path);
        return 0;
    }
    int index = ex->count;
    ex->paths[ex->count++] = src->path;
    buf_printf(out, "#line %d %d\n", 1, index);
    const char *p = src->text;
    int line = 1;
    while (*p) {
        const char *eol = strchr(p, '\n');
        size_t len = eol ? (size_t)(eol - p) : strlen(p);
        char name[128];
        int inc = parse_include(p, len, name, sizeof name);
        if (inc < 0) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s:%d: malformed #include", src->path,
                         line);
            return 0;
        }
        if (inc > 0) {
            gi_error why;
            const gi_shader_source *child = lookup(name, table_of(src), &why);
            if (!child) {
                gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s:%d: #include \"%s\": %s", src->path,
                             line, name, why.text);
                return 0;
            }
            int seen = 0;
            for (int i = 0; i < ex->count; i++)
                seen |= ex->paths[i] == child->path;
            if (!seen) {
                if (!expand_into(out, ex, child, err))
                    return 0;
                buf_printf(out, "#line %d %d\n", line + 1, index);
            } else {
                buf_add(out, "\n", 1);
            }
        } else if (!buf_add(out, p, len) || !buf_add(out, "\n", 1)) {
            gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory expanding %s", src->path);
            return 0;
        }
        line++;
        p = eol ? eol + 1 : p + len;
    }
    return 1;
}

static char *expand(const gi_shader_source *src, const char *stage_define, const char *defines,
                    expansion *ex, gi_error *err)
{
    buf out = {0};
    buf_add(&out, "#version 450 core\n", 18);
    if (stage_define)
        buf_add(&out, stage_define, strlen(stage_define));
    if (defines)
        buf_add(&out, defines, strlen(defines));
    if (!expand_into(&out, ex, src, err)) {
        free(out.data);
        return NULL;
    }
    return out.data;
}

char *gi_shader_expand(const char *name, const char *defines, gi_error *err)
{
    const gi_shader_source *src = lookup(name, NULL, err);
    if (!src)
        return NULL;
    expansion ex = {0};
    return expand(src, NULL, defines, &ex, err);
}

/* Rewrites the first error line of a compile log as "path:line: message". */
static void report_log(const char *log, const expansion *ex, const char *fallback, gi_error *err)
{
    const char *line = log;
    const char *first = NULL;
    while (line && *line) {
        if (strstr(line, "error") &&
            (!strchr(line, '\n') || strstr(line, "error") < strchr(line, '\n'))) {
            first = line;
            break;
        }
        line = strchr(line, '\n');
        line = line ? line + 1 : NULL;
    }
    if (!first)
        first = log;
    int file = -1, ln = -1, used = 0;
    /* Mesa: "0:12(7): error: msg"; NVIDIA: "0(12) : error C0000: msg". */
    if (sscanf(first, "%d:%d(%*d): %n", &file, &ln, &used) >= 2 && used > 0) {
    } else if (sscanf(first, "%d(%d) : %n", &file, &ln, &used) >= 2 && used > 0) {
    } else {
        file = -1;
    }
    const char *eol = strchr(first, '\n');
    int msg_len = eol ? (int)(eol - first) : (int)strlen(first);
    if (file >= 0 && file < ex->count) {
        const char *msg = first + used;
        int mlen = msg_len - used;
        gi_error_set(err, GI_ERR_GL, "%s:%d: %.*s", ex->paths[file], ln, mlen, msg);
    } else {
        gi_error_set(err, GI_ERR_GL, "%s: %.*s", fallback, msg_len, first);
    }
}

static GLuint compile_text(GLenum type, const char *text, const expansion *ex, const char *label,
                           gi_error *err)
{
    GLuint sh = glCreateShader(type);
    glShaderSource(sh, 1, &text, NULL);
    glCompileShader(sh);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint n = 0;
        glGetShaderiv(sh, GL_INFO_LOG_LENGTH, &n);
        char *log = calloc(1, (size_t)n + 1);
        if (log)
            glGetShaderInfoLog(sh, n, NULL, log);
        report_log(log ? log : "", ex, label, err);
        free(log);
        glDeleteShader(sh);
        return 0;
    }
    return sh;
}

/* Compiles one stage of `src` with the stage's define (GI_VERTEX_SHADER, ...). */
static GLuint compile_source(GLenum type, const gi_shader_source *src, const char *defines,
                             gi_error *err)
{
    expansion ex = {0};
    const char *stage = type == GL_VERTEX_SHADER     ? "#define GI_VERTEX_SHADER 1\n"
                        : type == GL_FRAGMENT_SHADER ? "#define GI_FRAGMENT_SHADER 1\n"
                        : type == GL_GEOMETRY_SHADER ? "#define GI_GEOMETRY_SHADER 1\n"
                                                     : "#define GI_COMPUTE_SHADER 1\n";
    char *text = expand(src, stage, defines, &ex, err);
    if (!text)
        return 0;
    GLuint sh = compile_text(type, text, &ex, src->path, err);
    free(text);
    return sh;
}

static GLuint compile_named(GLenum type, const char *name, const char *defines, gi_error *err)
{
    const gi_shader_source *src = lookup(name, NULL, err);
    return src ? compile_source(type, src, defines, err) : 0;
}

static GLuint link_program(GLuint *shaders, int n, const char *label, gi_error *err)
{
    GLuint prog = glCreateProgram();
    for (int i = 0; i < n; i++)
        glAttachShader(prog, shaders[i]);
    glLinkProgram(prog);
    for (int i = 0; i < n; i++) {
        glDetachShader(prog, shaders[i]);
        glDeleteShader(shaders[i]);
    }
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(prog, sizeof log, NULL, log);
        char *nl = strchr(log, '\n');
        if (nl && nl[1] == '\0')
            *nl = '\0';
        gi_error_set(err, GI_ERR_GL, "%s: link failed: %s", label, log);
        glDeleteProgram(prog);
        return 0;
    }
    return prog;
}

GLuint gi_program_build(const char *vert, const char *geom, const char *frag, const char *defines,
                        gi_error *err)
{
    GLuint sh[3];
    int n = 0;
    const char *names[3] = {vert, geom, frag};
    const GLenum types[3] = {GL_VERTEX_SHADER, GL_GEOMETRY_SHADER, GL_FRAGMENT_SHADER};
    for (int i = 0; i < 3; i++) {
        if (!names[i])
            continue;
        GLuint s = compile_named(types[i], names[i], defines, err);
        if (!s) {
            for (int k = 0; k < n; k++)
                glDeleteShader(sh[k]);
            return 0;
        }
        sh[n++] = s;
    }
    return link_program(sh, n, vert ? vert : frag, err);
}

GLuint gi_program_build_compute(const char *comp, const char *defines, gi_error *err)
{
    GLuint s = compile_named(GL_COMPUTE_SHADER, comp, defines, err);
    return s ? link_program(&s, 1, comp, err) : 0;
}

GLuint gi_program_build_compute_text(const char *label, const char *text, const char *defines,
                                     gi_error *err)
{
    gi_shader_source src = {label, label, text};
    GLuint s = compile_source(GL_COMPUTE_SHADER, &src, defines, err);
    return s ? link_program(&s, 1, label, err) : 0;
}

GLuint gi_program_build_text(const char *label, const char *vert_text, const char *frag_text,
                             const char *defines, gi_error *err)
{
    gi_shader_source vs = {label, label, vert_text}, fs = {label, label, frag_text};
    GLuint sh[2] = {compile_source(GL_VERTEX_SHADER, &vs, defines, err), 0};
    if (sh[0])
        sh[1] = compile_source(GL_FRAGMENT_SHADER, &fs, defines, err);
    if (!sh[1]) {
        if (sh[0])
            glDeleteShader(sh[0]);
        return 0;
    }
    return link_program(sh, 2, label, err);
}
