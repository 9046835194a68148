/* Wavefront OBJ reader (docs/inputs.md, "OBJ"): `v x y z [w | r g b]`, `vt`, `vn`, faces
 * `f v[/vt][/vn] ...` with positive or negative (relative) indices, polygons
 * fan-triangulated, `usemtl` groups and `mtllib` (obj_mtl.c). Lines, points, groups,
 * smoothing groups and free-form geometry are not geometry a scan needs: skipped (free-form
 * with a warning).
 *
 * Two passes over the mapped file: the first counts each kind of line (and the triangles
 * of each face), so every array is allocated once at its exact size, after the counts were
 * checked against the limits; bounded by the file's lines, so a 100-byte file cannot ask
 * for gigabytes. The second parses. An index is checked against the count of its kind
 * (positive indices may name a vertex defined further down, as the format allows).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/obj_internal.h"

#define TICK_LINES 0xffff

static int is_word(const char *p, const char *q, const char *w)
{
    return text_token_is(p, q, w);
}

/* Numbers on a `v` line after the keyword (for the info: are there colours). */
static int count_numbers(const text_cursor *c, const char *p)
{
    int n = 0;
    float x;
    while (n < 8 && text_float(c, &p, NULL, &x) == 1)
        n++;
    return n;
}

static uint64_t count_tokens(const char *p, const char *eol)
{
    uint64_t n = 0;
    for (p = text_skip(p, eol); p < eol; p = text_skip(text_token_end(p, eol), eol))
        n++;
    return n;
}

int obj_count(const scan_src *s, obj_counts *n)
{
    memset(n, 0, sizeof *n);
    text_cursor c;
    text_begin(&c, s);
    int rc;
    while (text_next_line(&c)) {
        const char *p = text_skip(c.line, c.eol), *q = text_token_end(p, c.eol);
        if (is_word(p, q, "v")) {
            if (n->v++ == 0)
                n->v_columns = count_numbers(&c, q);
        } else if (is_word(p, q, "vt")) {
            n->vt++;
        } else if (is_word(p, q, "vn")) {
            n->vn++;
        } else if (is_word(p, q, "f")) {
            uint64_t corners = count_tokens(q, c.eol);
            n->faces++;
            n->triangles += corners >= 3 ? corners - 2 : 0;
        } else if (is_word(p, q, "usemtl")) {
            n->materials_lines++;
        } else if (is_word(p, q, "curv") || is_word(p, q, "surf") || is_word(p, q, "curv2")) {
            n->freeform = 1;
        }
        if ((c.number & TICK_LINES) == 0 && (rc = scan_tick(s, c.p)))
            return rc;
    }
    return 0;
}

static int read_vertex(obj_reader *r, const text_cursor *c, const char *p)
{
    float xyz[3], extra[4];
    int rc = 0, k, ne = 0;
    for (k = 0; k < 3 && (rc = text_float(c, &p, NULL, &xyz[k])) == 1; k++)
        ;
    if (k < 3)
        return scan_error(r->s, SL_E_BADINPUT, c->number, "a vertex needs x y z (%s)",
                          rc < 0 ? "not a number" : "too few numbers");
    while (ne < 4 && (rc = text_float(c, &p, NULL, &extra[ne])) == 1)
        ne++;
    if (rc < 0)
        return scan_error(r->s, SL_E_BADINPUT, c->number, "a vertex coordinate is not a number");
    memcpy(r->m->positions + 3 * r->nv, xyz, sizeof xyz);
    if (ne >= 3) { /* `v x y z r g b`: the colour extension (w alone is one number) */
        int alloc_rc = 0;
        if (!r->rgb && !(r->rgb = scan_alloc(r->s, r->n.v, 3 * sizeof(float), &alloc_rc)))
            return alloc_rc;
        memcpy(r->rgb + 3 * r->nv, extra, 3 * sizeof(float));
        r->colored++;
    } else if (r->rgb) {
        memset(r->rgb + 3 * r->nv, 0, 3 * sizeof(float));
    }
    r->nv++;
    return 0;
}

/* `vt u [v [w]]` and `vn x y z`: `min` numbers at least, `keep` stored. */
static int read_attribute(obj_reader *r, const text_cursor *c, const char *p, float *dst,
                          int min, int keep, const char *what)
{
    float x[3] = {0, 0, 0};
    int k, rc = 0;
    for (k = 0; k < 3 && (rc = text_float(c, &p, NULL, &x[k])) == 1; k++)
        ;
    if (rc < 0 || k < min)
        return scan_error(r->s, SL_E_BADINPUT, c->number, "%s needs %d numbers", what, min);
    memcpy(dst, x, (size_t)keep * sizeof(float));
    return 0;
}

/* One signed index of a corner token at *p (up to '/' or the token's end): 1, 0 when
 * empty, -1 when not an integer. */
static int corner_index(const char **p, const char *q, int64_t *out)
{
    const char *s = *p;
    int neg = s < q && *s == '-';
    s += neg;
    int64_t v = 0;
    int digits = 0;
    for (; s < q && *s >= '0' && *s <= '9'; s++, digits++)
        if (digits < 18)
            v = v * 10 + (*s - '0');
    if (digits > 18 || (s < q && *s != '/'))
        return -1;
    *p = s;
    if (!digits)
        return neg ? -1 : 0;
    *out = neg ? -v : v;
    return 1;
}

/* 1-based or negative `raw` to a 0-based index below `total`; -1 when it names nothing. */
static int64_t resolve(int64_t raw, uint64_t so_far, uint64_t total)
{
    int64_t i = raw > 0 ? raw - 1 : (int64_t)so_far + raw;
    return raw != 0 && i >= 0 && (uint64_t)i < total ? i : -1;
}

/* One corner "v", "v/vt", "v//vn" or "v/vt/vn" into out[0..2]. */
static int read_corner(obj_reader *r, const text_cursor *c, const char *p, const char *q,
                       uint32_t out[3])
{
    static const char *const kinds[3] = {"vertex", "texture coordinate", "normal"};
    static const char *const plural[3] = {"vertices", "texture coordinates", "normals"};
    const uint64_t so_far[3] = {r->nv, r->nvt, r->nvn}, total[3] = {r->n.v, r->n.vt, r->n.vn};
    const char *token = p;
    out[0] = out[1] = out[2] = OBJ_NONE;
    for (int k = 0; k < 3; k++) {
        int64_t raw = 0;
        int got = corner_index(&p, q, &raw);
        if (got < 0 || (k == 0 && got == 0))
            break;
        if (got) {
            int64_t i = resolve(raw, so_far[k], total[k]);
            if (i < 0)
                return scan_error(r->s, SL_E_BADINPUT, c->number,
                                  "%s index %lld is out of range (%llu %s)", kinds[k],
                                  (long long)raw, (unsigned long long)total[k], plural[k]);
            out[k] = (uint32_t)i;
        }
        if (p == q)
            return 0;
        p++; /* the '/' corner_index stopped at */
    }
    return scan_error(r->s, SL_E_BADINPUT, c->number, "bad face corner '%.*s'",
                      (int)(q - token < 40 ? q - token : 40), token);
}

static void push_triangle(obj_reader *r, const uint32_t *a, const uint32_t *b, const uint32_t *c)
{
    sl_mesh *m = r->m;
    uint64_t t = m->triangle_count++;
    const uint32_t *corner[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        m->triangles[3 * t + k] = corner[k][0];
        if (r->corner_vt)
            r->corner_vt[3 * t + k] = corner[k][1];
        if (r->corner_vn)
            r->corner_vn[3 * t + k] = corner[k][2];
    }
    if (r->tri_material)
        r->tri_material[t] = (uint16_t)r->current;
}

static int read_face(obj_reader *r, const text_cursor *c, const char *p)
{
    uint64_t n = 0;
    int rc;
    for (p = text_skip(p, c->eol); p < c->eol; p = text_skip(p, c->eol), n++) {
        const char *q = text_token_end(p, c->eol);
        if (n >= r->s->lim->max_face_corners)
            return scan_error(r->s, SL_E_LIMIT, c->number, "face has more than %u corners",
                              r->s->lim->max_face_corners);
        if ((rc = scan_reserve(r->s, (void **)&r->poly, &r->poly_cap, 3 * (n + 1),
                               sizeof *r->poly)) ||
            (rc = read_corner(r, c, p, q, r->poly + 3 * n)))
            return rc;
        p = q;
    }
    if (n < 3) {
        r->m->stats.faces_too_short++;
        return 0;
    }
    if (r->m->triangle_count + (n - 2) > r->n.triangles)
        return scan_error(r->s, SL_E_INTERNAL, c->number, "more triangles than counted");
    r->m->stats.polygons_triangulated += n > 3;
    for (uint64_t k = 1; k + 1 < n; k++) /* fan around corner 0 */
        push_triangle(r, r->poly, r->poly + 3 * k, r->poly + 3 * (k + 1));
    return 0;
}

int obj_material_find(const obj_reader *r, const char *p, const char *eol)
{
    const char *b, *e;
    text_rest(p, eol, &b, &e);
    size_t len = (size_t)(e - b < 127 ? e - b : 127);
    for (uint32_t i = 0; i < r->material_count; i++)
        if (strlen(r->materials[i].name) == len && !memcmp(r->materials[i].name, b, len))
            return (int)i;
    return -1;
}

/* `usemtl NAME`: the current material, by first use. */
static void use_material(obj_reader *r, const char *p, const char *eol)
{
    int found = obj_material_find(r, p, eol);
    if (found >= 0) {
        r->current = (uint32_t)found;
        return;
    }
    if (r->material_count == OBJ_MAX_MATERIALS) {
        if (r->current != OBJ_MAX_MATERIALS - 1)
            sl_mesh_warn(r->m, "more than %d materials: later ones read as the last",
                         OBJ_MAX_MATERIALS);
        r->current = OBJ_MAX_MATERIALS - 1;
        return;
    }
    const char *b, *e;
    text_rest(p, eol, &b, &e);
    obj_material *mt = &r->materials[r->material_count];
    snprintf(mt->name, sizeof mt->name, "%.*s", (int)(e - b < 127 ? e - b : 127), b);
    r->current = r->material_count++;
}

static void add_mtllib(obj_reader *r, const char *p, const char *eol)
{
    const char *b, *e;
    text_rest(p, eol, &b, &e);
    if (b == e || r->mtllib_count == OBJ_MAX_MTLLIBS)
        return;
    snprintf(r->mtllib[r->mtllib_count++], sizeof r->mtllib[0], "%.*s",
             (int)(e - b < 255 ? e - b : 255), b);
}

static int read_line(obj_reader *r, const text_cursor *c)
{
    const char *p = text_skip(c->line, c->eol), *q = text_token_end(p, c->eol);
    if (is_word(p, q, "v"))
        return read_vertex(r, c, q);
    if (is_word(p, q, "vt"))
        return read_attribute(r, c, q, r->vt + 2 * r->nvt++, 1, 2, "a texture coordinate");
    if (is_word(p, q, "vn"))
        return read_attribute(r, c, q, r->vn + 3 * r->nvn++, 3, 3, "a normal");
    if (is_word(p, q, "f"))
        return read_face(r, c, q);
    if (is_word(p, q, "usemtl"))
        use_material(r, q, c->eol);
    else if (is_word(p, q, "mtllib"))
        add_mtllib(r, q, c->eol);
    return 0;
}

static int alloc_arrays(obj_reader *r)
{
    const scan_src *s = r->s;
    sl_mesh *m = r->m;
    int rc = 0;
    m->vertex_count = r->n.v;
    m->positions = scan_alloc(s, r->n.v, 3 * sizeof(float), &rc);
    m->triangles = scan_alloc(s, r->n.triangles, 3 * sizeof(uint32_t), &rc);
    if (r->n.vt) {
        r->vt = scan_alloc(s, r->n.vt, 2 * sizeof(float), &rc);
        r->corner_vt = scan_alloc(s, r->n.triangles, 3 * sizeof(uint32_t), &rc);
    }
    if (r->n.vn) {
        r->vn = scan_alloc(s, r->n.vn, 3 * sizeof(float), &rc);
        r->corner_vn = scan_alloc(s, r->n.triangles, 3 * sizeof(uint32_t), &rc);
    }
    if (r->n.materials_lines)
        r->tri_material = scan_alloc(s, r->n.triangles, sizeof(uint16_t), &rc);
    r->materials = rc ? NULL : calloc(OBJ_MAX_MATERIALS, sizeof *r->materials);
    if (!rc && !r->materials)
        rc = sl_error_nomem(s->err, s->name, "out of memory for the materials");
    return rc;
}

static void release(obj_reader *r)
{
    free(r->vt), free(r->vn), free(r->rgb), free(r->corner_vt), free(r->corner_vn);
    free(r->tri_material), free(r->materials), free(r->poly);
}

static int check_counts(const scan_src *s, const obj_counts *n)
{
    int rc = scan_check_limit(s, "vertices", n->v, s->lim->max_vertices);
    if (!rc)
        rc = scan_check_limit(s, "triangles", n->triangles, s->lim->max_faces);
    if (!rc && (n->vt >= OBJ_NONE || n->vn >= OBJ_NONE))
        rc = scan_error(s, SL_E_LIMIT, 0, "%llu texture coordinates, %llu normals (limit %u)",
                        (unsigned long long)n->vt, (unsigned long long)n->vn, OBJ_NONE - 1);
    return rc;
}

static void fill_info(const obj_counts *n, sl_scan_info *info)
{
    snprintf(info->format, sizeof info->format, "obj");
    snprintf(info->detail, sizeof info->detail,
             "Wavefront OBJ: %llu v, %llu vt, %llu vn, %llu faces, %llu usemtl",
             (unsigned long long)n->v, (unsigned long long)n->vt, (unsigned long long)n->vn,
             (unsigned long long)n->faces, (unsigned long long)n->materials_lines);
    info->declared_vertices = n->v;
    info->declared_faces = n->triangles;
    info->has_normals = n->vn > 0;
    info->has_colors = n->v_columns >= 6;
    info->has_texcoords = n->vt > 0;
}

int sl_obj_info_source(const scan_src *s, sl_scan_info *info)
{
    obj_counts n;
    int rc = obj_count(s, &n);
    if (!rc)
        fill_info(&n, info);
    return rc ? rc : check_counts(s, &n);
}

int sl_obj_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info)
{
    obj_reader r = {.s = s, .m = out, .current = OBJ_MAX_MATERIALS};
    int rc = obj_count(s, &r.n);
    if (!rc && info)
        fill_info(&r.n, info);
    if (rc || (rc = check_counts(s, &r.n)) || (rc = alloc_arrays(&r)))
        goto done;
    if (r.n.freeform)
        sl_mesh_warn(out, "free-form curves and surfaces are not read");
    text_cursor c;
    text_begin(&c, s);
    while (!rc && text_next_line(&c)) {
        rc = read_line(&r, &c);
        if (!rc && (c.number & TICK_LINES) == 0)
            rc = scan_tick(s, c.p);
    }
    if (!rc)
        rc = obj_finish(&r);
done:
    release(&r);
    return rc;
}
