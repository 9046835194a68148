/* libFuzzer target for the PLY reader (build: -DSCANLOD_FUZZ=ON with clang; see
 * tests/fuzz/CMakeLists.txt). Errors are fine; crashes, leaks, hangs, allocations beyond
 * -malloc_limit_mb and broken promises are not: a failure must be one bad-input/limit
 * error with a message, a success must be a mesh whose every index is in range.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply.h"

static void require(int cond)
{
    if (!cond)
        abort();
}

static void check_mesh(const sl_mesh *m)
{
    require(m->vertex_count == 0 || m->positions);
    require(m->triangle_count == 0 || m->triangles);
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        require(m->triangles[i] < m->vertex_count);
    uint64_t cells = (uint64_t)m->grid_cols * m->grid_rows;
    require(!m->grid_index == (cells == 0));
    for (uint64_t i = 0; m->grid_index && i < cells; i++)
        require(m->grid_index[i] >= -1 && m->grid_index[i] < (int64_t)m->vertex_count);
    require(memchr(m->texture_file, 0, sizeof m->texture_file) != NULL);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sl_mesh m;
    sl_ply_info info;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read_memory(data, size, "fuzz.ply", NULL, &m, &info, &err);
    if (rc == 0) {
        check_mesh(&m);
        sl_mesh_release(&m);
    } else {
        require(rc == err.code && (rc == SL_E_BADINPUT || rc == SL_E_LIMIT));
        require(err.message[0] && strcmp(err.file, "fuzz.ply") == 0);
        require(m.positions == NULL && m.triangles == NULL && m.vertex_count == 0);
    }
    require(memchr(info.elements, 0, sizeof info.elements) != NULL);
    return 0;
}
