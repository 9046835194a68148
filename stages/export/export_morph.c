/* Which level a published level morphs to ([export] morph, docs/morphing.md). */
#include "stages/export/export_internal.h"

int sl_export_morph_coarser(const sl_export_config *c, const sl_export_result *rows, int i)
{
    if (!c->morph || !c->write_glb || rows[i].file != i)
        return -1;
    int best = -1;
    for (int j = 0; j < c->level_count; j++)
        if (rows[j].file == j && rows[j].triangles && rows[j].triangles < rows[i].triangles &&
            (best < 0 || rows[j].triangles > rows[best].triangles))
            best = j;
    return best;
}
