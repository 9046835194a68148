/* The GLB writer's document model (glb_internal.h): its buffer views and accessors, which
 * the streams (glb_streams.c), the morph target (glb_morph.c) and the writer add to. */
#include <string.h>

#include "formats/glb_internal.h"

/* Takes ownership of `data`. */
int glb_add_view(glb_doc *d, unsigned char *data, uint64_t size, uint32_t stride,
                 uint64_t count, int target, const char *mode)
{
    glb_view *v = &d->views[d->view_count];
    memset(v, 0, sizeof *v);
    v->data = data, v->size = size, v->stride = stride, v->count = count;
    v->target = target;
    v->mode = d->opt->compression == SL_GLB_MESHOPT ? mode : NULL;
    return d->view_count++;
}

glb_accessor *glb_add_accessor(glb_doc *d, const char *semantic, int view, int component,
                               const char *type, int normalized, uint64_t count)
{
    glb_accessor *a = &d->accessors[d->accessor_count++];
    memset(a, 0, sizeof *a);
    a->semantic = semantic, a->view = view, a->component = component, a->type = type;
    a->normalized = normalized, a->count = count, a->draco_id = -1;
    return a;
}
