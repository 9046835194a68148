/* The export stage's cuts, made one level ahead on a thread of their own (export.h,
 * docs/threads.md "The export's two lanes").
 *
 * A level's cut is serial work on the model (the walk of the frontier and the builder's
 * one scratch), while writing a level (meshopt or Draco encoding, the thumbnail, the
 * topology, the fidelity measure) reads only its mesh. So the cut of the next level runs
 * on a second thread while the stage's thread writes the current one with its OpenMP
 * loops: the cuts are made in exactly the serial order (each one's choices depend on the
 * levels cut before it, never on the writes), one at a time, so the output does not
 * depend on the threads and at most two levels' meshes and one cut's scratch are held.
 */
#include <errno.h>
#include <omp.h>
#include <pthread.h>
#include <string.h>

#include "core/hash.h"
#include "stages/export/export_internal.h"

sl_export_digest sl_export_digest_mesh(const sl_lod_mesh *m)
{
    sl_export_digest d;
    memset(&d, 0, sizeof d); /* no padding bytes left undefined: digests are compared whole */
    d.vertices = m->vertex_count;
    d.triangles = m->triangle_count;
    size_t v = (size_t)m->vertex_count, t = (size_t)m->triangle_count;
    d.positions = sl_hash_bytes(m->positions, v * 3 * sizeof *m->positions);
    d.normals = m->normals ? sl_hash_bytes(m->normals, v * 3 * sizeof *m->normals) : d.normals;
    d.colors = m->colors ? sl_hash_bytes(m->colors, v * 4) : d.colors;
    d.indices = sl_hash_bytes(m->indices, t * 3 * sizeof *m->indices);
    return d;
}

/* Without morph targets, in preference order, each distinct cut generated once (the cut
 * is the costliest part of exporting a large level): a level with the k of one already
 * seen shares its mesh; else its mesh is cut, and shares the files of an earlier one with
 * the same digest (equal meshes from different k), or is this level's own. The same
 * rows[i].file as the morph plan gives. Returns 1 with *mesh the level's own mesh to
 * write, 0 when it shares another's or has no triangles (nothing held), -1 out of memory
 * (err). Reads rows[].k, .file and cracks[] of the levels before `at` and writes level
 * order[at]'s: the fields a concurrent write of an earlier level does not touch. */
static int cut_once(sl_export_cutter *cutter, const int *order, int at, sl_export_result *rows,
                    uint64_t *cracks, sl_export_digest *digests, sl_lod_mesh *mesh,
                    sl_error *err)
{
    int i = order[at];
    for (int b = 0; b < at; b++)
        if (rows[order[b]].k == rows[i].k) {
            rows[i].file = rows[order[b]].file, cracks[i] = cracks[order[b]];
            return 0;
        }
    if (sl_export_cut_row(cutter, &cutter->c->levels[i], &rows[i], mesh, &cracks[i], err))
        return -1;
    rows[i].triangles = mesh->triangle_count;
    rows[i].vertices = mesh->vertex_count;
    rows[i].file = mesh->triangle_count ? i : -1;
    if (mesh->triangle_count) {
        digests[i] = sl_export_digest_mesh(mesh);
        for (int b = 0; b < at && rows[i].file == i; b++) {
            int j = order[b];
            if (rows[j].file == j && !memcmp(&digests[j], &digests[i], sizeof *digests))
                rows[i].file = j;
        }
    }
    if (rows[i].file == i)
        return 1;
    sl_lod_mesh_release(mesh);
    return 0;
}

/* The job's cut (and with morph targets its coarser level's), in whichever thread. */
static void cut_job_run(sl_export_cut_job *j)
{
    sl_export_cutter *x = j->cutter;
    int i = j->order[j->at];
    memset(&j->mesh, 0, sizeof j->mesh);
    memset(&j->coarser, 0, sizeof j->coarser);
    if (!j->morph) {
        j->own = cut_once(x, j->order, j->at, j->rows, j->cracks, j->digests, &j->mesh, &j->err);
    } else if (j->rows[i].file != i) {
        j->own = 0; /* the morph plan cut every level once already: files are known */
    } else {
        j->own = sl_export_cut_level(x, j->rows[i].k, &j->mesh, NULL, NULL, &j->err) ? -1 : 1;
    }
    int to = j->own == 1 ? j->rows[i].morph_to : -1;
    if (to >= 0 && sl_export_cut_level(x, j->rows[to].k, &j->coarser, NULL, NULL, &j->err)) {
        sl_lod_mesh_release(&j->mesh);
        j->own = -1;
    }
}

static void *cut_job_thread(void *arg)
{
    /* A new thread starts from the process's default OpenMP thread count, not the one the
     * engine set for the item ([run] threads): any parallel loop a cut reaches keeps to it. */
    omp_set_num_threads(((sl_export_cut_job *)arg)->threads);
    cut_job_run(arg);
    return NULL;
}

void sl_export_cut_job_start(sl_export_cut_job *j, int at)
{
    j->at = at;
    j->own = 0;
    sl_error_init(&j->err);
    /* Alone on one thread there is nothing to overlap: the cut is made when it is asked
     * for. Otherwise, if no thread can be had, it is made now, before the write. */
    j->threaded = j->threads > 1 && pthread_create(&j->thread, NULL, cut_job_thread, j) == 0;
    j->pending = j->threads <= 1;
    if (!j->threaded && !j->pending)
        cut_job_run(j);
}

int sl_export_cut_job_finish(sl_export_cut_job *j, sl_error *err)
{
    if (j->threaded)
        pthread_join(j->thread, NULL);
    if (j->pending)
        cut_job_run(j);
    j->threaded = j->pending = 0;
    if (j->own < 0) {
        sl_error_merge(err, &j->err);
        return err->code ? err->code : SL_E_NOMEM;
    }
    return 0;
}

void sl_export_cut_job_release(sl_export_cut_job *j)
{
    sl_lod_mesh_release(&j->mesh);
    sl_lod_mesh_release(&j->coarser);
}

void sl_export_cut_job_cancel(sl_export_cut_job *j)
{
    if (j->threaded)
        pthread_join(j->thread, NULL);
    j->threaded = j->pending = 0; /* a cut not begun is not made */
    sl_export_cut_job_release(j);
}
