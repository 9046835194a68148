/* Replays the fuzz corpora in every normal build, so the CI ASan+UBSan build re-checks
 * every input the fuzzers ever kept or crashed on, without clang or libFuzzer. Each input
 * sits in a buffer of exactly its size (ASan sees any read past it).
 * - tests/fuzz/corpus/ply through sl_ply_read_memory: a valid mesh or one bad-input/limit
 *   error;
 * - tests/fuzz/corpus/slod (.slod bodies) through sl_lod_model_parse and generation: the
 *   promises of tests/fuzz/slod_promises.h;
 * - tests/fuzz/corpus/{obj,stl,off,xyz,gltf} through sl_scan_read_memory with that format:
 *   the promises of tests/fuzz/scan_promises.h.
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply.h"
#include "tests/check.h"
#include "tests/fuzz/scan_promises.h"
#include "tests/fuzz/slod_promises.h"

static unsigned char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc(n > 0 ? (size_t)n : 1);
    *size = n > 0 && buf ? fread(buf, 1, (size_t)n, f) : 0;
    fclose(f);
    return buf;
}

static int mesh_valid(const sl_mesh *m)
{
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return 0;
    uint64_t cells = (uint64_t)m->grid_cols * m->grid_rows;
    for (uint64_t i = 0; m->grid_index && i < cells; i++)
        if (m->grid_index[i] < -1 || m->grid_index[i] >= (int64_t)m->vertex_count)
            return 0;
    return (m->vertex_count == 0 || m->positions) && (m->triangle_count == 0 || m->triangles);
}

/* counts[0]: inputs that loaded, counts[1]: refused, counts[2]: seeds among the loaded. */
typedef void replay_fn(const unsigned char *data, size_t size, const char *name, int counts[3]);

static void replay_ply(const unsigned char *data, size_t size, const char *name, int counts[3])
{
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read_memory(data, size, name, NULL, &m, NULL, &err);
    if (rc == 0) {
        CHECK_MSG(mesh_valid(&m), "%s: invalid mesh", name);
        counts[0]++;
    } else {
        CHECK_MSG((rc == SL_E_BADINPUT || rc == SL_E_LIMIT) && rc == err.code && err.message[0],
                  "%s: rc %d '%s'", name, rc, err.message);
        counts[1]++;
    }
    sl_mesh_release(&m);
}

/* The scan readers' corpora: the reader is the folder's name (the corpus' sub-folder). */
static const char *scan_format;

static void replay_scan(const unsigned char *data, size_t size, const char *name, int counts[3])
{
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_scan_read_memory(data, size, name, scan_format, NULL, NULL, &m, NULL, &err);
    const char *why = scan_outcome_broken(rc, &err, &m, name);
    CHECK_MSG(why == NULL, "%s/%s: %s (rc %d '%s')", scan_format, name, why, rc, err.message);
    counts[rc == 0 ? 0 : 1]++;
    sl_mesh_release(&m);
}

static void replay_slod(const unsigned char *data, size_t size, const char *name, int counts[3])
{
    const char *why = slod_body_broken(data, size);
    CHECK_MSG(why == NULL, "%s: %s", name, why);
    sl_lod_model m;
    sl_error err;
    sl_error_init(&err);
    int loaded = sl_lod_model_parse(data, size, name, &m, &err) == 0;
    if (loaded)
        sl_lod_model_release(&m);
    counts[loaded ? 0 : 1]++;
    /* The seeds are models as built: they must load, or the replay tests refusals only. */
    if (!strncmp(name, "tiny-", 5)) {
        CHECK_MSG(loaded, "seed %s refused: %s", name, err.message);
        counts[2]++;
    }
    /* The packed mutants (make_slod_mutants.py) each lie about their frames. */
    if (!strncmp(name, "packed-", 7))
        CHECK_MSG(!loaded && err.code == SL_E_CORRUPT, "%s loaded or not refused as corrupt: %s",
                  name, err.message);
}

/* Replays every file of tests/fuzz/corpus/SUB, each in a buffer of exactly its size. */
static void replay_corpus(const char *sub, replay_fn *replay, int counts[3])
{
    char rel[64], dir[1024], path[1400];
    snprintf(rel, sizeof rel, "tests/fuzz/corpus/%s", sub);
    check_source_path(rel, dir, sizeof dir);
    DIR *d = opendir(dir);
    CHECK_MSG(d != NULL, "no corpus at %s", dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        size_t size = 0;
        unsigned char *data = slurp(path, &size);
        CHECK_MSG(data != NULL, "cannot read %s", path);
        if (data)
            replay(data, size, e->d_name, counts);
        free(data);
    }
    if (d)
        closedir(d);
    printf("%s corpus: %d loaded, %d refused\n", sub, counts[0], counts[1]);
}

int main(void)
{
    int ply[3] = {0, 0, 0}, slod[3] = {0, 0, 0};
    replay_corpus("ply", replay_ply, ply);
    CHECK(ply[0] > 20 && ply[1] > 20);
    replay_corpus("slod", replay_slod, slod);
    CHECK_MSG(slod[2] == 6 && slod[1] >= 5, "slod corpus: %d seeds, %d refused", slod[2], slod[1]);
    static const char *const scans[] = {"obj", "stl", "off", "xyz", "gltf"};
    for (size_t i = 0; i < sizeof scans / sizeof scans[0]; i++) {
        int n[3] = {0, 0, 0};
        scan_format = scans[i];
        replay_corpus(scans[i], replay_scan, n);
        CHECK_MSG(n[0] >= 2 && n[1] >= 5, "%s corpus: %d loaded, %d refused", scans[i], n[0], n[1]);
    }
    return check_report();
}
