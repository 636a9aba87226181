/* Minimal test assertions for the unit tests: each CHECK prints the failing
 * expression with file:line and counts; gi_test_finish prints
 * "N passed, N failed" and returns the exit status. A test program made of
 * several files has one pair of counters: they are weak definitions, which
 * the linker merges into one, so a CHECK in any file counts. */
#ifndef GI_TEST_CHECK_H
#define GI_TEST_CHECK_H

#include <math.h>
#include <stdio.h>

__attribute__((weak)) int gi_test_passed, gi_test_failed;

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (cond) {                                                                                \
            gi_test_passed++;                                                                      \
        } else {                                                                                   \
            gi_test_failed++;                                                                      \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);               \
        }                                                                                          \
    } while (0)

#define CHECK_MSG(cond, ...)                                                                       \
    do {                                                                                           \
        if (cond) {                                                                                \
            gi_test_passed++;                                                                      \
        } else {                                                                                   \
            gi_test_failed++;                                                                      \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond);               \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

/* |a - b| <= tol, printing both values on failure. */
#define CHECK_NEAR(a, b, tol)                                                                      \
    CHECK_MSG(fabs((double)(a) - (double)(b)) <= (double)(tol), "%.9g vs %.9g (tol %.3g)",         \
              (double)(a), (double)(b), (double)(tol))

static inline int gi_test_finish(void)
{
    printf("%d passed, %d failed\n", gi_test_passed, gi_test_failed);
    return gi_test_failed == 0 ? 0 : 1;
}

#endif
