/* Replays the PLY fuzz corpus (tests/fuzz/corpus/ply) through sl_ply_read_memory in every
 * normal build, so the CI ASan+UBSan build re-checks every input the fuzzer ever kept or
 * crashed on, without clang or libFuzzer. Each input sits in a buffer of exactly its size
 * (ASan sees any read past it) and must give a valid mesh or one bad-input/limit error.
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/ply.h"
#include "tests/check.h"

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

static void replay(const char *path, const char *name, int *read_ok, int *rejected)
{
    size_t size = 0;
    unsigned char *data = slurp(path, &size);
    CHECK_MSG(data != NULL, "cannot read %s", path);
    if (!data)
        return;
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read_memory(data, size, name, NULL, &m, NULL, &err);
    if (rc == 0) {
        CHECK_MSG(mesh_valid(&m), "%s: invalid mesh", name);
        (*read_ok)++;
    } else {
        CHECK_MSG((rc == SL_E_BADINPUT || rc == SL_E_LIMIT) && rc == err.code && err.message[0],
                  "%s: rc %d '%s'", name, rc, err.message);
        (*rejected)++;
    }
    sl_mesh_release(&m);
    free(data);
}

int main(void)
{
    char dir[1024], path[1400];
    check_source_path("tests/fuzz/corpus/ply", dir, sizeof dir);
    DIR *d = opendir(dir);
    CHECK_MSG(d != NULL, "no corpus at %s", dir);
    int read_ok = 0, rejected = 0;
    for (struct dirent *e; d && (e = readdir(d));) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        replay(path, e->d_name, &read_ok, &rejected);
    }
    if (d)
        closedir(d);
    printf("corpus: %d read, %d rejected\n", read_ok, rejected);
    CHECK(read_ok > 20 && rejected > 20);
    return check_report();
}
