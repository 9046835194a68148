/* Minimal test harness: CHECK records a failure and goes on; each test program ends with
 * `return check_report();`, which prints "N passed, N failed" and returns non-zero on any
 * failure. Tests get the source dir in SCANLOD_SOURCE_DIR and the shared data folder (if
 * present) in SCANLOD_SHARED_DATA (see tests/CMakeLists.txt).
 */
#ifndef SCANLOD_TESTS_CHECK_H
#define SCANLOD_TESTS_CHECK_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int check_passed_, check_failed_;

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (cond) {                                                                   \
            check_passed_++;                                                          \
        } else {                                                                      \
            check_failed_++;                                                          \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);  \
        }                                                                             \
    } while (0)

#define CHECK_MSG(cond, ...)                                                          \
    do {                                                                              \
        if (cond) {                                                                   \
            check_passed_++;                                                          \
        } else {                                                                      \
            check_failed_++;                                                          \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);  \
            fprintf(stderr, __VA_ARGS__);                                             \
            fputc('\n', stderr);                                                      \
        }                                                                             \
    } while (0)

#define CHECK_EQ_U64(a, b)                                                            \
    CHECK_MSG((unsigned long long)(a) == (unsigned long long)(b), "%llu != %llu",     \
              (unsigned long long)(a), (unsigned long long)(b))

#define CHECK_NEAR(a, b, tol)                                                         \
    CHECK_MSG(fabs((double)(a) - (double)(b)) <= (tol), "%.9g vs %.9g (tol %.3g)",   \
              (double)(a), (double)(b), (double)(tol))

static inline int check_report(void)
{
    printf("%d passed, %d failed\n", check_passed_, check_failed_);
    return check_failed_ ? 1 : 0;
}

/* Path of a file under the source tree, or under the shared data folder (NULL if that
 * folder is absent: the caller then skips only checks that need the larger scans). */
static inline const char *check_source_path(const char *rel, char *buf, size_t size)
{
    const char *root = getenv("SCANLOD_SOURCE_DIR");
    snprintf(buf, size, "%s/%s", root ? root : ".", rel);
    return buf;
}
static inline const char *check_shared_path(const char *rel, char *buf, size_t size)
{
    const char *root = getenv("SCANLOD_SHARED_DATA");
    if (!root || !root[0]) {
        /* Said on every call, so a log shows exactly which checks did not run. */
        printf("SKIP: %s: no ../shared/data (SCANLOD_SHARED_DATA is empty)\n",
               rel[0] ? rel : "the shared scans");
        return NULL;
    }
    snprintf(buf, size, "%s/%s", root, rel);
    return buf;
}

/* The sanitizer pass sets SCANLOD_LIGHT=1 (tests/CMakeLists.txt): the same code on less
 * data, as the unoptimised instrumented build runs 10-20x slower. A loop over every
 * expansion count K = 0..last then visits every check_k_step(last)-th K and the last
 * (41 K), still every path of the loop. */
static inline int check_light(void)
{
    const char *light = getenv("SCANLOD_LIGHT");
    return light && !strcmp(light, "1");
}
static inline uint32_t check_k_step(uint32_t last)
{
    return check_light() ? last / 40 + 1 : 1;
}
static inline uint32_t check_k_next(uint32_t k, uint32_t last)
{ /* the K after k: last once the step passes it, then last + 1 (done) */
    uint32_t step = check_k_step(last);
    return k == last ? last + 1 : k + step > last ? last : k + step;
}

#endif
