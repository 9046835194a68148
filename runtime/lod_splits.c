/* The split table (see lod_splits.h). */
#include "runtime/lod_splits.h"

#include <pthread.h>
#include <stdatomic.h>

static int face_direction(int f)
{
    int a = f / 2, d = f % 2 ? 1 : -1;
    return sl_direction(a == 0 ? d : 0, a == 1 ? d : 0, a == 2 ? d : 0);
}

/* The 3 same-level neighbours sharing edge e. */
static void edge_directions(int e, int dirs[3])
{
    int a = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e), b = (a + 1) % 3, c = (a + 2) % 3;
    int off_b[3] = {0, 0, 0}, off_c[3] = {0, 0, 0};
    off_b[b] = (c0 >> b & 1) ? 1 : -1;
    off_c[c] = (c0 >> c & 1) ? 1 : -1;
    dirs[0] = sl_direction(off_b[0], off_b[1], off_b[2]);
    dirs[1] = sl_direction(off_c[0], off_c[1], off_c[2]);
    dirs[2] = sl_direction(off_b[0] + off_c[0], off_b[1] + off_c[1], off_b[2] + off_c[2]);
}



static sl_lod_split_table splits;
static pthread_once_t splits_once = PTHREAD_ONCE_INIT;
static atomic_int splits_ready; /* set once the table is built: later calls skip libc */

static void build_split_table(void)
{
    for (int f = 0; f < 6; f++) {
        int edges[4], d = face_direction(f);
        sl_mc_face_edges(f, edges);
        splits.faces[d] |= (uint8_t)(1u << f);
        for (int i = 0; i < 4; i++)
            splits.edges[d] |= (uint16_t)(1u << edges[i]);
    }
    for (int e = 0; e < 12; e++) {
        int dirs[3];
        edge_directions(e, dirs);
        for (int i = 0; i < 3; i++)
            splits.edges[dirs[i]] |= (uint16_t)(1u << e);
    }
    for (int e = 0; e < 12; e++) {
        splits.edge_c0[e] = (uint8_t)sl_mc_edge_c0(e);
        splits.edge_c1[e] = (uint8_t)sl_mc_edge_c1(e);
    }
    for (int f = 0; f < 6; f++) {
        int edges[4];
        sl_mc_face_edges(f, edges);
        for (int i = 0; i < 4; i++)
            splits.face_edges[f][i] = (uint8_t)edges[i];
    }
    int slot = 0;
    for (int d = 0; d < 27; d++) {
        splits.slot_of_dir[d] = -1;
        if (!splits.edges[d])
            continue;
        splits.split_dirs |= 1u << d;
        splits.slot_of_dir[d] = slot;
        splits.slot_faces[slot] = splits.faces[d];
        splits.slot_edges[slot] = splits.edges[d];
        slot++;
    }
    atomic_store_explicit(&splits_ready, 1, memory_order_release);
}

/* Every cut asks for the table first; after the first, a flag says it is built, so a cut
 * from cold caches does not also fetch pthread_once's code from another library. */
const sl_lod_split_table *sl_lod_split_table_get(void)
{
    if (!atomic_load_explicit(&splits_ready, memory_order_acquire))
        pthread_once(&splits_once, build_split_table);
    return &splits;
}
