/* A driver for the libFuzzer targets without libFuzzer, so that `make test`
 * fuzzes for a few seconds with gcc (and, in the asan preset, under ASan +
 * UBSan): every seed file first, then deterministic mutations of the seeds
 * (bit flips, byte changes, deletions, duplications, splices of another
 * seed, dictionary tokens) until the time is up. The coverage-guided search
 * stays libFuzzer's (GIBENCH_FUZZ, scripts/fuzz-scene.sh); this finds the
 * shallow crashes and keeps every seed passing.
 *   fuzz_driver SECONDS DICT|- SEED_FILE_OR_DIR...
 * Prints the inputs tried; a crash is the sanitiser's report and a non-zero
 * exit. The mutations are deterministic (a fixed xorshift seed), so the same
 * command with the same seeds replays a crash. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv) __attribute__((weak));

typedef struct blob {
    uint8_t *data;
    size_t size;
} blob;

static blob *seeds;
static size_t seed_count;
static char **tokens;
static size_t token_count;

static void add_seed(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return;
    blob b = {0};
    uint8_t buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0 && b.size < (1u << 20)) {
        uint8_t *grown = realloc(b.data, b.size + n);
        if (!grown)
            break;
        b.data = grown;
        memcpy(b.data + b.size, buf, n);
        b.size += n;
    }
    fclose(f);
    blob *grown = realloc(seeds, (seed_count + 1) * sizeof *seeds);
    if (!grown) {
        free(b.data);
        return;
    }
    seeds = grown;
    seeds[seed_count++] = b;
}

static void add_path(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return;
    if (!S_ISDIR(st.st_mode)) {
        add_seed(path);
        return;
    }
    DIR *d = opendir(path);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char p[4096];
        snprintf(p, sizeof p, "%s/%s", path, e->d_name);
        if (stat(p, &st) == 0 && S_ISREG(st.st_mode))
            add_seed(p);
    }
    if (d)
        closedir(d);
}

/* Dictionary lines of libFuzzer's form: name="token" (simple escapes: \" \\). */
static void read_dict(const char *path)
{
    FILE *f = fopen(path, "r");
    char line[1024];
    while (f && fgets(line, sizeof line, f)) {
        char *q = strchr(line, '"'), *end = strrchr(line, '"');
        if (line[0] == '#' || !q || end <= q)
            continue;
        *end = '\0';
        char *t = malloc(strlen(q + 1) + 1), *w = t;
        if (!t)
            break;
        for (char *r = q + 1; *r; r++)
            *w++ = (*r == '\\' && r[1]) ? *++r : *r;
        *w = '\0';
        char **grown = realloc(tokens, (token_count + 1) * sizeof *tokens);
        if (!grown) {
            free(t);
            break;
        }
        tokens = grown;
        tokens[token_count++] = t;
    }
    if (f)
        fclose(f);
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t next(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* One mutation of `in` into a new buffer (caller frees). */
static blob mutate(blob in)
{
    size_t extra = 64;
    blob o = {malloc(in.size * 2 + extra + 1), in.size};
    if (!o.data)
        return (blob){0};
    if (in.size)
        memcpy(o.data, in.data, in.size);
    int rounds = 1 + (int)(next() % 4);
    for (int r = 0; r < rounds; r++) {
        size_t at = o.size ? next() % o.size : 0;
        switch (next() % 6) {
        case 0: /* bit flip */
            if (o.size)
                o.data[at] ^= (uint8_t)(1u << (next() % 8));
            break;
        case 1: /* a byte from a set that matters to parsers */
            if (o.size) {
                static const char interesting[] = "{}[]\":,0123456789-.eE \n\\tfn";
                o.data[at] = (uint8_t)interesting[next() % (sizeof interesting - 1)];
            }
            break;
        case 2: { /* delete a run */
            size_t len = o.size - at > 0 ? 1 + next() % (o.size - at < 32 ? o.size - at : 32) : 0;
            memmove(o.data + at, o.data + at + len, o.size - at - len);
            o.size -= len;
            break;
        }
        case 3: { /* duplicate a run (bounded by the buffer) */
            size_t len = o.size - at < 16 ? o.size - at : 16;
            if (o.size + len <= in.size * 2 + extra) {
                memmove(o.data + at + len, o.data + at, o.size - at);
                o.size += len;
            }
            break;
        }
        case 4: { /* a dictionary token */
            if (!token_count)
                break;
            const char *t = tokens[next() % token_count];
            size_t len = strlen(t);
            if (o.size + len <= in.size * 2 + extra) {
                memmove(o.data + at + len, o.data + at, o.size - at);
                if (len)
                    memcpy(o.data + at, t, len);
                o.size += len;
            }
            break;
        }
        default: { /* the tail of another seed */
            blob other = seeds[next() % seed_count];
            size_t from = other.size ? next() % other.size : 0;
            size_t len = other.size - from;
            if (at + len > in.size * 2 + extra)
                len = in.size * 2 + extra - at;
            if (len)
                memcpy(o.data + at, other.data + from, len);
            o.size = at + len;
            break;
        }
        }
    }
    return o;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void run_one(const blob *b)
{
    LLVMFuzzerTestOneInput(b->data, b->size);
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: fuzz_driver SECONDS DICT|- SEED_FILE_OR_DIR...\n");
        return 2;
    }
    double seconds = atof(argv[1]);
    if (strcmp(argv[2], "-") != 0)
        read_dict(argv[2]);
    for (int i = 3; i < argc; i++)
        add_path(argv[i]);
    if (seed_count == 0) {
        fprintf(stderr, "fuzz_driver: no seed files found\n");
        return 2;
    }
    if (LLVMFuzzerInitialize)
        LLVMFuzzerInitialize(&argc, &argv);
    for (size_t i = 0; i < seed_count; i++)
        run_one(&seeds[i]);
    unsigned long long tried = 0;
    double t0 = now();
    while (now() - t0 < seconds) {
        blob m = mutate(seeds[next() % seed_count]);
        if (!m.data)
            break;
        run_one(&m);
        free(m.data);
        tried++;
    }
    printf("fuzz_driver: %zu seeds, %llu mutated inputs in %.1f s, no crash\n", seed_count, tried,
           now() - t0);
    for (size_t i = 0; i < seed_count; i++)
        free(seeds[i].data);
    free(seeds);
    for (size_t i = 0; i < token_count; i++)
        free(tokens[i]);
    free(tokens);
    return 0;
}
