/* A level made of some of a point set's points (level.h): what the segment and cluster
 * methods' levels and the scan itself are, since they keep the input's own vertices. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "levels/level.h"

int sl_level_from_points(sl_level *lv, uint64_t point_count, const float *positions,
                         const uint8_t *colors, const float *texcoords, uint64_t triangle_count,
                         const uint32_t *triangles, sl_error *err)
{
    uint32_t *map = malloc((point_count ? point_count : 1) * sizeof *map);
    if (!map)
        return sl_error_nomem(err, NULL, "level %s", lv->name);
    memset(map, 0xff, (point_count ? point_count : 1) * sizeof *map);
    for (uint64_t k = 0; k < 3 * triangle_count; k++)
        map[triangles[k]] = 0;
    uint64_t used = 0;
    for (uint64_t p = 0; p < point_count; p++)
        if (map[p] != UINT32_MAX)
            map[p] = (uint32_t)used++;
    size_t nv = used ? (size_t)used : 1, nt = triangle_count ? (size_t)triangle_count : 1;
    lv->positions = malloc(3 * nv * sizeof *lv->positions);
    lv->colors = colors ? malloc(4 * nv) : NULL;
    lv->texcoords = texcoords ? malloc(2 * nv * sizeof *lv->texcoords) : NULL;
    lv->source = malloc(nv * sizeof *lv->source);
    lv->triangles = malloc(3 * nt * sizeof *lv->triangles);
    if (!lv->positions || !lv->source || !lv->triangles || (colors && !lv->colors) ||
        (texcoords && !lv->texcoords)) {
        free(map);
        sl_level_release_mesh(lv);
        return sl_error_nomem(err, NULL, "level %s", lv->name);
    }
    for (uint64_t p = 0; p < point_count; p++) {
        uint32_t v = map[p];
        if (v == UINT32_MAX)
            continue;
        memcpy(lv->positions + 3 * (uint64_t)v, positions + 3 * p, 3 * sizeof *positions);
        if (colors)
            memcpy(lv->colors + 4 * (uint64_t)v, colors + 4 * p, 4);
        if (texcoords)
            memcpy(lv->texcoords + 2 * (uint64_t)v, texcoords + 2 * p, 2 * sizeof *texcoords);
        lv->source[v] = (uint32_t)p;
    }
    for (uint64_t k = 0; k < 3 * triangle_count; k++)
        lv->triangles[k] = map[triangles[k]];
    lv->vertex_count = used;
    lv->triangle_count = triangle_count;
    free(map);
    return 0;
}
