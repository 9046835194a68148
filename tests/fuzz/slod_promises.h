/* What the LOD model reader promises for any body (docs/formats.md, model.slod), checked
 * by the libFuzzer target (fuzz_slod.c) and by the corpus replay in every ctest run
 * (tests/unit/test_fuzz_corpus.c): either one SL_E_CORRUPT/SL_E_NOMEM error with a message
 * naming the file and nothing left allocated, or a model from which every lookup and every
 * generation below stays in bounds: meshes whose indices name their own vertices and whose
 * positions are finite, both through the allocating path and into buffers sized by the
 * accumulation table (which a hostile table may make too small: that must fail, not
 * overflow). A format 5 body is also read by prefixes from a file, as the C API reads
 * it: the same promises, and every cut it makes the whole model's when the whole reader
 * took the body.
 * Returns 0 if the promise held; `why` gets the broken one.
 */
#ifndef SCANLOD_TESTS_FUZZ_SLOD_PROMISES_H
#define SCANLOD_TESTS_FUZZ_SLOD_PROMISES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "runtime/lod_pack.h"
#include "runtime/lod_prefix.h"

static const char *slod_mesh_broken(const sl_lod_mesh *mesh)
{
    if ((mesh->vertex_count && (!mesh->positions || !mesh->normals)) ||
        (mesh->triangle_count && !mesh->indices))
        return "mesh arrays missing";
    for (uint64_t i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->indices[i] >= mesh->vertex_count)
            return "index out of range";
    for (uint64_t i = 0; i < 3 * mesh->vertex_count; i++)
        if (!isfinite(mesh->positions[i]) || !isfinite(mesh->normals[i]))
            return "non-finite vertex";
    return NULL;
}

/* Generates level k both ways; returns the broken promise or NULL. */
static const char *slod_level_broken(sl_lod_model *m, uint32_t k)
{
    sl_lod_mesh mesh;
    uint64_t cracks = 0;
    if (sl_lod_generate(m, k, &mesh, &cracks) != 0)
        return NULL; /* out of memory is an allowed outcome */
    const char *why = slod_mesh_broken(&mesh);
    uint64_t triangles = mesh.triangle_count;
    sl_lod_mesh_release(&mesh);
    if (why)
        return why;
    /* Into buffers of the table's size, as scanlod_extract does: exactly the allocating
     * path's mesh when the table is right, a clean failure when it is short. */
    uint64_t cap_t = m->accumulation[k], cap_v = 3 * cap_t;
    float *positions = malloc(cap_v * 12 + 1), *normals = malloc(cap_v * 12 + 1);
    uint8_t *colors = malloc(cap_v * 4 + 1);
    uint32_t *indices = malloc(cap_t * 12 + 1);
    sl_lod_mesh into = {0, 0, positions, normals, colors, indices};
    if (positions && normals && colors && indices) {
        int rc = sl_lod_generate_into(m, k, &into, cap_v, cap_t, NULL);
        if (rc == 0 && (into.triangle_count != triangles || triangles > cap_t))
            why = "buffered generation differs from the allocating one";
        else if (rc == 0)
            why = slod_mesh_broken(&into);
        else if (triangles <= cap_t)
            why = "buffered generation failed although the table's size fits";
    }
    free(positions); /* the generation sets colors NULL for a model without colours */
    free(normals);
    free(colors);
    free(indices);
    return why;
}

static int slod_same_cut(sl_lod_model *a, sl_lod_model *b, uint32_t k)
{
    sl_lod_mesh x, y;
    int ax = sl_lod_generate(a, k, &x, NULL), by = sl_lod_generate(b, k, &y, NULL);
    int same = ax || by ||
               (x.triangle_count == y.triangle_count && x.vertex_count == y.vertex_count &&
                (!x.vertex_count || !memcmp(x.positions, y.positions, 12 * (size_t)x.vertex_count)) &&
                (!x.triangle_count || !memcmp(x.indices, y.indices, 12 * (size_t)x.triangle_count)));
    if (!ax)
        sl_lod_mesh_release(&x);
    if (!by)
        sl_lod_mesh_release(&y);
    return same;
}

/* A format 5 body (checked pieces) as a file read by prefixes (lod_prefix.h): refused with
 * one error naming the file, or cuts that keep the promises, and each the whole model's
 * cut when the whole reader took the body (`whole`). (The prefix reader may refuse a body
 * the whole reader takes: it also needs the writer's pieces, one section or more each.) */
static const char *slod_prefix_broken(const unsigned char *body, size_t size,
                                      sl_lod_model *whole)
{
    char path[] = "/tmp/scanlod-fuzz-prefix-XXXXXX";
    int fd = mkstemp(path);
    if (fd < 0)
        return NULL;
    unsigned char header[SL_ARTIFACT_HEADER_SIZE] = "SLODMODL";
    sl_put_u32(header + 8, SL_LOD_FORMAT_VERSION);
    sl_put_u32(header + 12, 1);
    sl_put_u64(header + 16, size); /* the envelope's checksum is not what this reader checks */
    int written = write(fd, header, sizeof header) == (ssize_t)sizeof header &&
                  write(fd, body, size) == (ssize_t)size;
    close(fd);
    const char *why = NULL;
    sl_lod_file *f = NULL;
    sl_error err;
    sl_error_init(&err);
    int rc = written ? sl_lod_file_open(path, &f, &err) : -1;
    uint32_t e = rc == 0 ? sl_lod_file_levels(f)->expansion_count : 0;
    uint32_t ks[] = {0, 1, e / 3, e / 2, e};
    for (size_t i = 0; rc == 0 && i < sizeof ks / sizeof ks[0] && !why; i++) {
        sl_lod_model *cut = NULL;
        rc = sl_lod_file_reach(f, ks[i], &cut, &err);
        if (rc == 0)
            why = whole && !slod_same_cut(whole, cut, ks[i]) ? "a prefix cut unlike the whole model's"
                                                             : slod_level_broken(cut, ks[i]);
    }
    if (written && rc && !why &&
        (rc != err.code || (rc != SL_E_CORRUPT && rc != SL_E_NOMEM) || !err.message[0] ||
         strcmp(err.file, path) != 0))
        why = "a prefix refusal that is not one corrupt/out-of-memory error naming the file";
    sl_lod_file_close(f);
    unlink(path);
    return why;
}

static int slod_ordered(const unsigned char *body, size_t size)
{
    return size >= 4 && sl_get_u32(body) == SL_PACK_MAGIC_CHECKED;
}

static const char *slod_body_broken(const unsigned char *body, size_t size)
{
    sl_lod_model m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_lod_model_parse(body, size, "fuzz.slod", &m, &err);
    if (rc) {
        if (rc != err.code || (rc != SL_E_CORRUPT && rc != SL_E_NOMEM) || !err.message[0] ||
            strcmp(err.file, "fuzz.slod") != 0)
            return "a refusal that is not one corrupt/out-of-memory error naming the file";
        /* The contract callers rely on (they may release it again); leaks are LSan's. */
        if (m.tree.nodes || m.lod_array || m.cells)
            return "a refused model left arrays behind";
        return slod_ordered(body, size) ? slod_prefix_broken(body, size, NULL) : NULL;
    }
    uint32_t e = m.expansion_count;
    uint32_t ks[] = {0, 1, e / 3, e / 2, e > 0 ? e - 1 : 0, e,
                     sl_lod_expansions_for_triangles(&m, m.accumulation[e] / 2 + 1),
                     sl_lod_expansions_for_percent(&m, 40),
                     sl_lod_expansions_for_error(&m, m.error_after[e / 2])};
    const char *why = NULL;
    for (size_t i = 0; i < sizeof ks / sizeof ks[0] && !why; i++)
        why = ks[i] > e ? "a lookup past the last expansion" : slod_level_broken(&m, ks[i]);
    /* The octree alone, as `extract --level` uses a merge stage's octree.slot. */
    for (uint32_t level = 0; level <= m.tree.depth && !why; level++) {
        sl_lod_mesh mesh;
        if (sl_octree_level_mesh(&m.tree, level, &mesh) == 0) {
            why = slod_mesh_broken(&mesh);
            sl_lod_mesh_release(&mesh);
        }
    }
    if (!why && slod_ordered(body, size))
        why = slod_prefix_broken(body, size, &m);
    sl_lod_model_release(&m);
    return why;
}

#endif
