/* The implicit_vis method's link creation on several threads (Sec. 4.2.2;
 * README "Multi-threaded link creation"): the same links, to the bit, as
 * link_self / link_pair make on one thread (links.c).
 * 1. The recursion of link_self / link_pair is unrolled into an ordered
 *    list of tasks (calls in the order one thread would make them).
 * 2. Threads take tasks and list the pairs each task links, in order.
 * 3. Threads write the links: each owns the receiving nodes x with
 *    x mod threads = its index, and goes through all pairs in task order,
 *    writing only its own nodes' sides. Every node's bins see the same
 *    writes in the same order as on one thread, so the result (shortest
 *    links, ties, coverage sums) is the same to the bit. */
#include "iv_internal.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>

typedef struct link_task {
    uint32_t A, B;   /* B == UINT32_MAX: link_self(A) */
    uint32_t *pairs; /* 4 per pair linked, in order: A, B, A's bin toward B, B's toward A; NULL:
                        in l->pair_buf[buf] from pair `off` on */
    size_t n, cap;
    uint32_t buf;
    size_t off;
    uint64_t tries;
    uint32_t root; /* the top-level task it comes from (its index among them) */
    int kept;      /* its pairs are the kept list of a task between two still segments */
} link_task;

typedef struct link_par {
    iv_links *l;
    const iv_hier *h;
    float subdiv;
    int splat;
    link_task *tasks;
    size_t ntasks;
    atomic_size_t next;
    int threads;
    int fail;
    atomic_int stop;      /* a cancel seen by any thread (issue 32) */
    size_t *used;         /* per thread: pairs in its l->pair_buf */
    iv_kept *kept;        /* keep_pairs: the lists of the last build; NULL: none */
    uint64_t *root_tries; /* with kept: per top-level task, the tests made while unrolling it */
} link_par;

typedef struct write_arg {
    link_par *p;
    uint32_t index;
    uint64_t created;
} write_arg;

static const uint32_t *task_pairs(const link_par *p, const link_task *t)
{
    return t->pairs ? t->pairs : p->l->pair_buf[t->buf] + 4 * t->off;
}

/* Appends a pair to the buffer of the thread listing task t (its pairs
 * contiguous there: a thread lists one task at a time). */
static int buf_push(link_par *p, link_task *t, uint32_t A, uint32_t B, const uint32_t bins[2])
{
    iv_links *l = p->l;
    uint32_t w = t->buf;
    size_t n = p->used[w];
    if (n == l->pair_cap[w]) {
        size_t c = n ? 2 * n : 4096;
        uint32_t *q = realloc(l->pair_buf[w], c * 4 * sizeof *q);
        if (!q)
            return 0;
        l->pair_buf[w] = q;
        l->pair_cap[w] = c;
    }
    uint32_t *o = &l->pair_buf[w][4 * n];
    o[0] = A, o[1] = B, o[2] = bins[0], o[3] = bins[1];
    p->used[w] = n + 1;
    t->n++;
    return 1;
}

/* Whether to stop: the host is asked every 64 k steps of `count`, and a
 * cancel seen by one thread stops them all. */
static int par_stop(link_par *p, uint64_t count)
{
    if ((count & 0xFFFF) == 0 && iv_links_cancelled(p->l))
        atomic_store(&p->stop, 1);
    return atomic_load_explicit(&p->stop, memory_order_relaxed);
}

static int task_push(link_task *t, uint32_t A, uint32_t B, const uint32_t bins[2])
{
    if (t->n == t->cap) {
        size_t c = t->cap ? 2 * t->cap : 256;
        uint32_t *p = realloc(t->pairs, c * 4 * sizeof *p);
        if (!p)
            return 0;
        t->pairs = p;
        t->cap = c;
    }
    uint32_t *o = &t->pairs[4 * t->n];
    o[0] = A, o[1] = B, o[2] = bins[0], o[3] = bins[1];
    t->n++;
    return 1;
}

static int collect_pair(link_par *p, link_task *t, uint32_t A, uint32_t B)
{
    const iv_hier *h = p->h;
    if (par_stop(p, ++t->tries))
        return 0;
    gi_vec3 d;
    float r2;
    uint32_t bins[2];
    switch (iv_pair_decide(p->l, h, p->subdiv, A, B, &d, &r2, bins)) {
    case IV_PAIR_SPLIT_B:
        for (uint32_t k = 0; k < h->child_count[B]; k++)
            if (!collect_pair(p, t, A, h->first_child[B] + k))
                return 0;
        return 1;
    case IV_PAIR_SPLIT_A:
        for (uint32_t k = 0; k < h->child_count[A]; k++)
            if (!collect_pair(p, t, h->first_child[A] + k, B))
                return 0;
        return 1;
    case IV_PAIR_LINK:
        return buf_push(p, t, A, B, bins);
    default:
        return 1;
    }
}

static int collect_self(link_par *p, link_task *t, uint32_t A)
{
    const iv_hier *h = p->h;
    uint32_t f = h->first_child[A], n = h->child_count[A];
    for (uint32_t i = 0; i < n; i++)
        if (!collect_self(p, t, f + i))
            return 0;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n; j++)
            if (!collect_pair(p, t, f + i, f + j))
                return 0;
    return 1;
}

/* Replaces every task by the calls it makes (in order) until there are
 * at least `want` or none can be unrolled; a link found while unrolling
 * stays a one-pair task. tries counts the calls unrolled. */
static link_task *unroll_tasks(link_par *p, link_task *tasks, size_t *count, size_t want,
                               uint64_t *tries)
{
    const iv_hier *h = p->h;
    for (int pass = 0; pass < 12 && *count < want; pass++) {
        size_t n = *count, cap = 0, m = 0;
        for (size_t i = 0; i < n; i++) {
            uint32_t A = tasks[i].A, B = tasks[i].B;
            uint32_t ca = h->child_count[A];
            cap += B == UINT32_MAX ? ca + (size_t)ca * ca / 2 : 4;
        }
        link_task *out = calloc(cap + 1, sizeof *out);
        if (!out)
            return tasks;
        int grew = 0;
        for (size_t i = 0; i < n; i++) {
            uint32_t A = tasks[i].A, B = tasks[i].B;
            if (tasks[i].n > 0 || tasks[i].kept) { /* a link found while unrolling, or a kept
                                                      list: as it is */
                out[m++] = tasks[i];
                continue;
            }
            if (B == UINT32_MAX) {
                uint32_t f = h->first_child[A], c = h->child_count[A];
                for (uint32_t k = 0; k < c; k++)
                    out[m++] = (link_task){.A = f + k, .B = UINT32_MAX, .root = tasks[i].root};
                for (uint32_t x = 0; x < c; x++)
                    for (uint32_t y = x + 1; y < c; y++)
                        out[m++] = (link_task){.A = f + x, .B = f + y, .root = tasks[i].root};
                grew = 1;
                continue;
            }
            (*tries)++;
            if (p->root_tries)
                p->root_tries[tasks[i].root]++;
            gi_vec3 d;
            float r2;
            uint32_t bins[2];
            int what = iv_pair_decide(p->l, h, p->subdiv, A, B, &d, &r2, bins);
            if (what == IV_PAIR_SPLIT_B) {
                for (uint32_t k = 0; k < h->child_count[B]; k++)
                    out[m++] =
                        (link_task){.A = A, .B = h->first_child[B] + k, .root = tasks[i].root};
                grew = 1;
            } else if (what == IV_PAIR_SPLIT_A) {
                for (uint32_t k = 0; k < h->child_count[A]; k++)
                    out[m++] =
                        (link_task){.A = h->first_child[A] + k, .B = B, .root = tasks[i].root};
                grew = 1;
            } else if (what == IV_PAIR_LINK) {
                out[m] = (link_task){.A = A, .B = B, .root = tasks[i].root};
                if (!task_push(&out[m], A, B, bins)) {
                    free(out);
                    return tasks;
                }
                m++;
            }
        }
        free(tasks);
        tasks = out;
        *count = m;
        if (!grew)
            break;
    }
    return tasks;
}

static void *collect_worker(void *arg)
{
    write_arg *w = arg;
    link_par *p = w->p;
    for (;;) {
        size_t i = atomic_fetch_add(&p->next, 1);
        if (i >= p->ntasks)
            break;
        if (par_stop(p, 0)) /* the host asked before each task, and every 64 k pairs in it */
            break;
        link_task *t = &p->tasks[i];
        if (t->n > 0 || t->kept)
            continue; /* a link found while unrolling, or a kept list */
        t->buf = w->index;
        t->off = p->used[w->index];
        int ok = t->B == UINT32_MAX ? collect_self(p, t, t->A) : collect_pair(p, t, t->A, t->B);
        if (!ok)
            p->fail = 1;
    }
    return NULL;
}

static void *write_worker(void *arg)
{
    write_arg *w = arg;
    link_par *p = w->p;
    const iv_hier *h = p->h;
    uint32_t T = (uint32_t)p->threads, me = w->index;
    /* a private copy of the counters: `created` is summed afterwards */
    iv_links mine = *p->l;
    mine.created = 0;
    iv_links_clear_nodes(p->l, me, T); /* its nodes' bins emptied */
    uint64_t steps = 0;
    for (size_t i = 0; i < p->ntasks; i++) {
        const link_task *t = &p->tasks[i];
        const uint32_t *pairs = task_pairs(p, t);
        for (size_t k = 0; k < t->n; k++) {
            if (par_stop(p, ++steps))
                return NULL;
            if (k + 16 < t->n) { /* the cells 16 pairs ahead, fetched while these are written */
                const uint32_t *f = &pairs[4 * (k + 16)];
                if (f[0] % T == me)
                    __builtin_prefetch(&p->l->cell[(size_t)f[0] * p->l->bins + f[2]], 1);
                if (f[1] % T == me)
                    __builtin_prefetch(&p->l->cell[(size_t)f[1] * p->l->bins + f[3]], 1);
            }
            const uint32_t *q = &pairs[4 * k];
            uint32_t A = q[0], B = q[1];
            int a = A % T == me, b = B % T == me;
            if (!a && !b)
                continue;
            gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
            float r = sqrtf(gi_v3_dot(d, d));
            if (a)
                iv_put_side(&mine, h, A, B, d, r, q[2], p->splat);
            if (b)
                iv_put_side(&mine, h, B, A, gi_v3_scale(d, -1.0f), r, q[3], p->splat);
        }
    }
    w->created = mine.created;
    return NULL;
}

/* At least `threads` pair buffers in l (kept from frame to frame). */
static int pair_bufs(iv_links *l, uint32_t threads)
{
    if (l->pair_bufs >= threads)
        return 1;
    uint32_t **b = realloc(l->pair_buf, threads * sizeof *b);
    if (!b)
        return 0;
    l->pair_buf = b;
    size_t *c = realloc(l->pair_cap, threads * sizeof *c);
    if (!c)
        return 0;
    l->pair_cap = c;
    for (uint32_t i = l->pair_bufs; i < threads; i++)
        b[i] = NULL, c[i] = 0;
    l->pair_bufs = threads;
    return 1;
}

/* The top-level tasks as the recursion makes them: each segment with
 * itself, then every two segments. With keep_pairs a task between two
 * still segments takes its kept list (its pair tests counted as made). */
static link_task *top_tasks(link_par *p, size_t *count, uint64_t *tries)
{
    const iv_hier *h = p->h;
    size_t n = h->root_count + (size_t)h->root_count * (h->root_count - 1) / 2;
    link_task *tasks = calloc(n + 1, sizeof *tasks);
    if (!tasks)
        return NULL;
    size_t m = 0;
    for (uint32_t i = 0; i < h->root_count; i++)
        tasks[m++] = (link_task){.A = i, .B = UINT32_MAX};
    for (uint32_t i = 0; i < h->root_count; i++)
        for (uint32_t j = i + 1; j < h->root_count; j++)
            tasks[m++] = (link_task){.A = i, .B = j};
    for (size_t t = 0; t < m; t++) {
        tasks[t].root = (uint32_t)t;
        if (!p->kept || !iv_kept_usable(p->kept, tasks[t].A, tasks[t].B))
            continue;
        const iv_pair_list *k = &p->kept->list[t];
        tasks[t].kept = 1;
        tasks[t].pairs = k->pairs;
        tasks[t].n = k->n;
        *tries += k->tries;
        p->l->kept_tries += k->tries;
    }
    *count = m;
    return tasks;
}

/* After a completed build: every task that was tested anew gives its
 * top-level task's list for the next build (a kept list stays as it is);
 * the task's tests are counted with it. */
static void keep_lists(link_par *p)
{
    iv_kept *k = p->kept;
    size_t top = p->h->root_count + (size_t)p->h->root_count * (p->h->root_count - 1) / 2;
    uint8_t *fresh = calloc(top + 1, 1);
    if (!fresh)
        return; /* k->valid stays 0: the next build tests every pair */
    for (size_t i = 0; i < p->ntasks; i++)
        if (!p->tasks[i].kept)
            fresh[p->tasks[i].root] = 1;
    for (size_t t = 0; t < top; t++)
        if (fresh[t]) {
            k->list[t].n = 0;
            k->list[t].tries = p->root_tries[t];
        }
    int ok = 1;
    for (size_t i = 0; i < p->ntasks && ok; i++) {
        const link_task *t = &p->tasks[i];
        if (t->kept)
            continue;
        k->list[t->root].tries += t->tries;
        ok = iv_kept_append(k, t->root, task_pairs(p, t), t->n);
    }
    free(fresh);
    k->valid = ok;
}

int iv_links_build_parallel(iv_links *l, const iv_hier *h, float subdiv, int splat, int threads)
{
    link_par p = {.l = l, .h = h, .subdiv = subdiv, .splat = splat, .threads = threads};
    l->kept_tries = 0;
    if (l->keep_pairs) {
        p.kept = iv_kept_begin(l, h);
        size_t top = h->root_count + (size_t)h->root_count * (h->root_count - 1) / 2;
        p.root_tries = calloc(top + 1, sizeof *p.root_tries);
        if (!p.root_tries)
            p.kept = NULL;
    }
    uint64_t tries = 0;
    size_t m = 0;
    link_task *tasks = top_tasks(&p, &m, &tries);
    if (!tasks) {
        free(p.root_tries);
        return 0;
    }
    tasks = unroll_tasks(&p, tasks, &m, (size_t)64 * (size_t)threads, &tries);
    p.tasks = tasks;
    p.ntasks = m;
    atomic_init(&p.next, 0);
    atomic_init(&p.stop, 0);
    pthread_t *tid = malloc((size_t)threads * sizeof *tid);
    uint8_t *made = calloc((size_t)threads, 1);
    write_arg *wa = calloc((size_t)threads, sizeof *wa);
    p.used = calloc((size_t)threads, sizeof *p.used);
    int ok = tid && made && wa && p.used && pair_bufs(l, (uint32_t)threads);
    if (ok) {
        /* this thread works too; a thread that cannot start is not needed */
        for (int i = 0; i < threads; i++)
            wa[i] = (write_arg){.p = &p, .index = (uint32_t)i};
        for (int i = 1; i < threads; i++)
            made[i] = pthread_create(&tid[i], NULL, collect_worker, &wa[i]) == 0;
        collect_worker(&wa[0]);
        for (int i = 1; i < threads; i++)
            if (made[i])
                pthread_join(tid[i], NULL);
        ok = !p.fail;
    }
    if (ok && !atomic_load(&p.stop)) {
        for (size_t i = 0; i < m; i++)
            tries += tasks[i].tries;
        /* each writer owns its nodes: one that cannot start runs here afterwards */
        for (int i = 0; i < threads; i++)
            wa[i] = (write_arg){.p = &p, .index = (uint32_t)i};
        for (int i = 1; i < threads; i++)
            made[i] = pthread_create(&tid[i], NULL, write_worker, &wa[i]) == 0;
        write_worker(&wa[0]);
        for (int i = 1; i < threads; i++) {
            if (made[i])
                pthread_join(tid[i], NULL);
            else
                write_worker(&wa[i]);
        }
        for (int i = 0; i < threads; i++)
            l->created += wa[i].created;
        l->tries = tries;
        if (p.kept && !atomic_load(&p.stop))
            keep_lists(&p);
    }
    for (size_t i = 0; i < m; i++)
        if (!tasks[i].kept)
            free(tasks[i].pairs);
    free(tasks), free(tid), free(made), free(wa), free(p.used), free(p.root_tries);
    if (atomic_load(&p.stop)) { /* cancelled: no build on one thread follows */
        l->stopped = 1;
        return 1;
    }
    return ok;
}
