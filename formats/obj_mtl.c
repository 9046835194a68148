/* The OBJ reader's second half: its MTL files, the one texture the mesh carries, and the
 * per-corner attributes onto the mesh (docs/inputs.md, "OBJ").
 *
 * Texture: `map_Kd` of the first material the faces use that has one (photogrammetry
 * software writes one material per texture page; a mesh here carries one image, so faces
 * of other textured materials get no texture coordinates, with a warning). The name is
 * taken relative to the MTL's folder and must stay inside the OBJ's folder: an absolute
 * or `..` name (Windows exports write "C:\...\tex.jpg") is looked for by its last
 * component beside the MTL instead, with a warning. A missing MTL or image is a warning,
 * never a failure: the geometry is still worth converting.
 *
 * Normals: OBJ gives them per corner; a vertex gets the unit mean of its corners' normals
 * (a vertex split by hard edges gets their mean direction). Colours (`v x y z r g b`) are
 * floats in [0, 1], or 0..255 when a component exceeds 1; kept when every vertex has one.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/io.h"
#include "formats/obj_internal.h"

/* The folder part of `name` with its slash ("" when none). */
static int folder_length(const char *name)
{
    const char *slash = strrchr(name, '/');
    return slash ? (int)(slash - name + 1) : 0;
}

/* Skips the options of a `map_Kd` line (MTL spec: -blendu on, -o u v w, ...). */
static const char *skip_map_options(const char *p, const char *eol)
{
    static const struct { const char *name; int args; } options[] = {
        {"-blendu", 1}, {"-blendv", 1}, {"-boost", 1}, {"-mm", 2}, {"-o", 3}, {"-s", 3},
        {"-t", 3}, {"-texres", 1}, {"-clamp", 1}, {"-bm", 1}, {"-imfchan", 1}, {"-type", 1},
        {"-cc", 1}};
    for (p = text_skip(p, eol); p < eol && *p == '-'; p = text_skip(p, eol)) {
        const char *q = text_token_end(p, eol);
        int args = -1;
        for (size_t i = 0; i < sizeof options / sizeof options[0]; i++)
            if (text_token_is(p, q, options[i].name))
                args = options[i].args;
        if (args < 0)
            return p; /* a name that starts with '-' */
        p = q;
        for (int a = 0; a < args; a++) { /* -o/-s/-t take 1 to 3 numbers */
            const char *t = text_skip(p, eol), *u = text_token_end(t, eol);
            char *stop;
            char num[40];
            snprintf(num, sizeof num, "%.*s", (int)(u - t < 39 ? u - t : 39), t);
            strtod(num, &stop);
            if (t == u || (a > 0 && args == 3 && *stop))
                break;
            p = u;
        }
    }
    return p;
}

/* The texture named by a `map_Kd` line, relative to the OBJ's folder, into `out`. */
static void map_name(obj_reader *r, const char *mtl, const char *p, const char *eol, char *out,
                     size_t size)
{
    const char *b, *e;
    text_rest(skip_map_options(p, eol), eol, &b, &e);
    char name[256];
    snprintf(name, sizeof name, "%.*s", (int)(e - b < 255 ? e - b : 255), b);
    for (char *c = name; *c; c++)
        if (*c == '\\')
            *c = '/';
    char probe[8];
    int drive = isalpha((unsigned char)name[0]) && name[1] == ':'; /* "C:/..." */
    if (name[0] && (drive || sl_scan_sibling_path(".", name, probe, sizeof probe) == -1)) {
        const char *base = strrchr(name, '/') ? strrchr(name, '/') + 1 : name;
        sl_mesh_warn(r->m, "%s: map_Kd '%s' is outside the folder; looking for '%s' beside it",
                     mtl, name, base);
        memmove(name, base, strlen(base) + 1);
    }
    int n = snprintf(out, size, "%.*s%s", folder_length(mtl), mtl, name);
    if (n < 0 || (size_t)n >= size) {
        sl_mesh_warn(r->m, "%s: map_Kd '%s': path too long", mtl, name);
        out[0] = 0;
    }
}

static obj_material *find_material(obj_reader *r, const char *p, const char *eol)
{
    int i = obj_material_find(r, p, eol);
    return i < 0 ? NULL : &r->materials[i]; /* NULL: a material no face uses */
}

static void parse_mtl(obj_reader *r, const char *mtl, const void *data, size_t size)
{
    scan_src src = *r->s;
    src.data = data;
    src.size = size;
    text_cursor c;
    text_begin(&c, &src);
    obj_material *current = NULL;
    while (text_next_line(&c)) {
        const char *p = text_skip(c.line, c.eol), *q = text_token_end(p, c.eol);
        if (text_token_is(p, q, "newmtl") && (current = find_material(r, q, c.eol)))
            current->defined = 1;
        else if (current && text_token_is(p, q, "map_Kd") && !current->map_kd[0])
            map_name(r, mtl, q, c.eol, current->map_kd, sizeof current->map_kd);
    }
}

/* Reads one `mtllib` file; 0 when it was found (counted in r->mtl_read). */
static int read_mtl(obj_reader *r, const char *mtl)
{
    void *map = NULL;
    size_t size = 0;
    sl_error e;
    sl_error_init(&e);
    if (!r->s->dir || scan_sibling_map(r->s, mtl, &map, &size, &e))
        return -1;
    parse_mtl(r, mtl, map, size);
    sl_io_unmap(map, size);
    r->mtl_read++;
    return 0;
}

static void read_materials(obj_reader *r)
{
    for (int i = 0; i < r->mtllib_count; i++) {
        const char *name = r->mtllib[i];
        if (read_mtl(r, name) == 0)
            continue;
        /* `mtllib a.mtl b.mtl` names several; a name with blanks names one (Windows). */
        int found = 0;
        char copy[256], *save = NULL;
        snprintf(copy, sizeof copy, "%s", name);
        for (char *t = strtok_r(copy, " \t", &save); t && strchr(name, ' ');
             t = strtok_r(NULL, " \t", &save))
            found += read_mtl(r, t) == 0;
        if (!found)
            sl_mesh_warn(r->m, "%s: %s", name, r->s->dir ? "missing" : "not read (no folder)");
    }
    for (uint32_t i = 0; i < r->material_count; i++)
        if (!r->materials[i].defined && r->mtl_read)
            sl_mesh_warn(r->m, "material '%s' is not in the MTL files", r->materials[i].name);
}

/* The first textured material in face order; warns when faces use other textures. */
static const obj_material *choose_texture(obj_reader *r)
{
    const obj_material *chosen = NULL;
    uint64_t others = 0;
    for (uint64_t t = 0; r->tri_material && t < r->m->triangle_count; t++) {
        uint16_t k = r->tri_material[t];
        const obj_material *mt = k < r->material_count ? &r->materials[k] : NULL;
        if (!mt || !mt->map_kd[0])
            continue;
        if (!chosen)
            chosen = mt;
        else if (strcmp(mt->map_kd, chosen->map_kd))
            others++;
    }
    if (others)
        sl_mesh_warn(r->m, "%llu triangles use another texture than %s: they get none",
                     (unsigned long long)others, chosen->map_kd);
    return chosen;
}

/* Per-corner texture coordinates; NaN where a corner has none or the face's material is
 * not the one whose texture the mesh carries. */
static int corner_texcoords(obj_reader *r, const obj_material *chosen)
{
    sl_mesh *m = r->m;
    int rc = 0;
    if (!(m->face_texcoords = scan_alloc(r->s, m->triangle_count, 6 * sizeof(float), &rc)))
        return rc;
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *vt = r->corner_vt + 3 * t;
        uint16_t k = r->tri_material ? r->tri_material[t] : OBJ_MAX_MATERIALS;
        int wrong = chosen && (k >= r->material_count || strcmp(r->materials[k].map_kd,
                                                                chosen->map_kd));
        int have = !wrong && vt[0] != OBJ_NONE && vt[1] != OBJ_NONE && vt[2] != OBJ_NONE;
        m->stats.texcoord_faces += have;
        for (int c = 0; c < 3; c++) {
            m->face_texcoords[6 * t + 2 * c] = have ? r->vt[2 * (uint64_t)vt[c]] : NAN;
            m->face_texcoords[6 * t + 2 * c + 1] = have ? r->vt[2 * (uint64_t)vt[c] + 1] : NAN;
        }
    }
    return 0;
}

static int vertex_normals(obj_reader *r)
{
    sl_mesh *m = r->m;
    if (!(m->normals = calloc(3 * m->vertex_count + 1, sizeof(float))))
        return sl_error_nomem(r->s->err, r->s->name, "out of memory for the normals");
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++) {
        uint32_t n = r->corner_vn[i];
        if (n == OBJ_NONE)
            continue;
        for (int k = 0; k < 3; k++)
            m->normals[3 * (uint64_t)m->triangles[i] + k] += r->vn[3 * (uint64_t)n + k];
    }
    for (uint64_t v = 0; v < m->vertex_count; v++) { /* the corners' mean direction */
        float *n = m->normals + 3 * v, len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; len > 0 && k < 3; k++)
            n[k] /= len;
    }
    return 0;
}

static int vertex_colors(obj_reader *r)
{
    sl_mesh *m = r->m;
    if (r->colored < m->vertex_count) {
        sl_mesh_warn(r->m, "colours on %llu of %llu vertices: not used",
                     (unsigned long long)r->colored, (unsigned long long)m->vertex_count);
        return 0;
    }
    if (!(m->colors = malloc(4 * m->vertex_count + 1)))
        return sl_error_nomem(r->s->err, r->s->name, "out of memory for the colours");
    scan_float_colors(r->rgb, 3, 3, m->vertex_count, m->colors);
    return 0;
}

static void set_texture(obj_reader *r, const obj_material *chosen)
{
    snprintf(r->m->texture_file, sizeof r->m->texture_file, "%s", chosen->map_kd);
    char path[4096];
    if (r->s->dir && sl_scan_sibling_path(r->s->dir, chosen->map_kd, path, sizeof path) == 0 &&
        access(path, R_OK) != 0)
        sl_mesh_warn(r->m, "%s: missing", chosen->map_kd);
}

int obj_finish(obj_reader *r)
{
    int rc = 0;
    read_materials(r);
    const obj_material *chosen = choose_texture(r);
    if (chosen)
        set_texture(r, chosen);
    if (r->corner_vt)
        rc = corner_texcoords(r, chosen);
    if (!rc && r->corner_vn)
        rc = vertex_normals(r);
    if (!rc && r->rgb)
        rc = vertex_colors(r);
    return rc;
}
