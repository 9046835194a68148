/* PLY header: lines up to `end_header` into a table of elements and properties.
 *
 * The header is tokenised in place (no copies of lines, so a 10 MB line costs one memchr
 * and is refused by the header size limit). Each property gets its role here, once, so
 * the body readers never compare names. After `end_header` every declared count is
 * checked against the bytes left in the file (checked arithmetic), so a 100-byte file
 * cannot make the body reader allocate for 2^32 vertices.
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats/ply_internal.h"

#define MAX_TOKENS 8

typedef struct token {
    const char *s;
    size_t n;
} token;

typedef struct header_parser {
    const char *name;
    sl_error *err;
    ply_header *h;
    const sl_ply_limits *lim;
    int line;                /* 1-based header line number */
    const char *line_end;    /* end of the current line (without \r\n) */
    token tok[MAX_TOKENS];
    int ntok;                /* tokens found, capped at MAX_TOKENS */
    int more;                /* the line has more than MAX_TOKENS tokens */
    int have_format;
} header_parser;

static const struct {
    const char *name;
    int type;
} type_names[] = {
    {"char", PLY_INT8},     {"int8", PLY_INT8},       {"uchar", PLY_UINT8},
    {"uint8", PLY_UINT8},   {"short", PLY_INT16},     {"int16", PLY_INT16},
    {"ushort", PLY_UINT16}, {"uint16", PLY_UINT16},   {"int", PLY_INT32},
    {"int32", PLY_INT32},   {"uint", PLY_UINT32},     {"uint32", PLY_UINT32},
    {"float", PLY_FLOAT32}, {"float32", PLY_FLOAT32}, {"double", PLY_FLOAT64},
    {"float64", PLY_FLOAT64},
};

int sl_ply_type_size(int type)
{
    static const int size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return type > PLY_NONE && type <= PLY_FLOAT64 ? size[type] : 0;
}

const char *sl_ply_type_name(int type)
{
    static const char *name[] = {"?", "char", "uchar", "short", "ushort",
                                 "int", "uint", "float", "double"};
    return type > PLY_NONE && type <= PLY_FLOAT64 ? name[type] : "?";
}

static int tok_is(const token *t, const char *s)
{
    size_t n = strlen(s);
    return t->n == n && memcmp(t->s, s, n) == 0;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static int herr(header_parser *hp, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int herr(header_parser *hp, int code, const char *fmt, ...)
{
    char msg[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sl_error_set(hp->err, code, 0, hp->name, "header line %d: %s", hp->line, msg);
}

/* Copies a token for a message, shortened and with control bytes replaced. */
static const char *tok_show(const token *t, char *buf, size_t size)
{
    size_t n = t->n < size - 4 ? t->n : size - 4;
    for (size_t i = 0; i < n; i++)
        buf[i] = (unsigned char)t->s[i] < 32 || (unsigned char)t->s[i] > 126 ? '?' : t->s[i];
    strcpy(buf + n, t->n > n ? "..." : "");
    return buf;
}

static void split_line(header_parser *hp, const char *s, const char *end)
{
    hp->ntok = 0;
    hp->more = 0;
    hp->line_end = end;
    while (s < end) {
        while (s < end && is_space(*s))
            s++;
        if (s == end)
            break;
        const char *start = s;
        while (s < end && !is_space(*s))
            s++;
        if (hp->ntok == MAX_TOKENS) {
            hp->more = 1;
            break;
        }
        hp->tok[hp->ntok++] = (token){start, (size_t)(s - start)};
    }
}

/* Strict unsigned decimal: digits only, no sign, no overflow. */
static int parse_count(header_parser *hp, const token *t, uint64_t *out)
{
    char show[48];
    uint64_t v = 0;
    if (t->n > 0 && t->s[0] == '-')
        return herr(hp, SL_E_BADINPUT, "negative count '%s'", tok_show(t, show, sizeof show));
    for (size_t i = 0; i < t->n; i++) {
        unsigned d = (unsigned char)t->s[i] - '0';
        if (d > 9)
            return herr(hp, SL_E_BADINPUT, "count '%s' is not a number",
                        tok_show(t, show, sizeof show));
        if (__builtin_mul_overflow(v, 10, &v) || __builtin_add_overflow(v, d, &v))
            return herr(hp, SL_E_BADINPUT, "count '%s' does not fit 64 bits",
                        tok_show(t, show, sizeof show));
    }
    if (t->n == 0)
        return herr(hp, SL_E_BADINPUT, "missing count");
    *out = v;
    return 0;
}

static int parse_type(header_parser *hp, const token *t, int *type)
{
    char show[48];
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++) {
        if (tok_is(t, type_names[i].name)) {
            *type = type_names[i].type;
            return 0;
        }
    }
    return herr(hp, SL_E_BADINPUT, "unknown property type '%s'", tok_show(t, show, sizeof show));
}

static int kind_of(const token *name)
{
    if (tok_is(name, "vertex"))
        return KIND_VERTEX;
    if (tok_is(name, "face"))
        return KIND_FACE;
    if (tok_is(name, "camera"))
        return KIND_CAMERA;
    if (tok_is(name, "range_grid"))
        return KIND_GRID;
    return KIND_OTHER;
}

static int handle_format(header_parser *hp)
{
    char show[48];
    if (hp->have_format)
        return herr(hp, SL_E_BADINPUT, "second format line");
    if (hp->ntok != 3 || hp->more)
        return herr(hp, SL_E_BADINPUT, "format line needs 'format TYPE 1.0'");
    if (tok_is(&hp->tok[1], "ascii"))
        hp->h->format = SL_PLY_ASCII;
    else if (tok_is(&hp->tok[1], "binary_little_endian"))
        hp->h->format = SL_PLY_BINARY_LE;
    else if (tok_is(&hp->tok[1], "binary_big_endian"))
        hp->h->format = SL_PLY_BINARY_BE;
    else
        return herr(hp, SL_E_BADINPUT, "unknown format '%s'", tok_show(&hp->tok[1], show, sizeof show));
    if (!tok_is(&hp->tok[2], "1.0") && !tok_is(&hp->tok[2], "1"))
        return herr(hp, SL_E_BADINPUT, "unsupported PLY version '%s'",
                    tok_show(&hp->tok[2], show, sizeof show));
    hp->have_format = 1;
    return 0;
}

static int handle_element(header_parser *hp)
{
    ply_header *h = hp->h;
    char show[48];
    if (hp->ntok != 3 || hp->more)
        return herr(hp, SL_E_BADINPUT, "element line needs 'element NAME COUNT'");
    if (h->nelements == PLY_MAX_ELEMENTS)
        return herr(hp, SL_E_LIMIT, "more than %d elements", PLY_MAX_ELEMENTS);
    ply_element *e = &h->elements[h->nelements];
    memset(e, 0, sizeof *e);
    int rc = parse_count(hp, &hp->tok[2], &e->count);
    if (rc)
        return rc;
    e->kind = kind_of(&hp->tok[1]);
    e->header_line = hp->line;
    e->first_prop = h->nprops;
    e->fixed_row = 1;
    tok_show(&hp->tok[1], e->name, sizeof e->name);
    int *slot = e->kind == KIND_VERTEX ? &h->vertex_element
                : e->kind == KIND_FACE ? &h->face_element : NULL;
    if (slot && *slot >= 0)
        return herr(hp, SL_E_BADINPUT, "second element '%s'", tok_show(&hp->tok[1], show, sizeof show));
    if (slot)
        *slot = h->nelements;
    int *first = e->kind == KIND_CAMERA ? &h->camera_element
                 : e->kind == KIND_GRID ? &h->grid_element : NULL;
    if (first && *first >= 0)
        e->kind = KIND_OTHER; /* a second camera/range_grid is skipped */
    else if (first)
        *first = h->nelements;
    h->nelements++;
    return 0;
}

static const struct {
    int kind;
    const char *name;
    int role;
} role_names[] = {
    {KIND_VERTEX, "x", ROLE_X},          {KIND_VERTEX, "y", ROLE_Y},
    {KIND_VERTEX, "z", ROLE_Z},          {KIND_VERTEX, "nx", ROLE_NX},
    {KIND_VERTEX, "ny", ROLE_NY},        {KIND_VERTEX, "nz", ROLE_NZ},
    {KIND_VERTEX, "red", ROLE_RED},      {KIND_VERTEX, "green", ROLE_GREEN},
    {KIND_VERTEX, "blue", ROLE_BLUE},    {KIND_VERTEX, "alpha", ROLE_ALPHA},
    {KIND_VERTEX, "diffuse_red", ROLE_RED}, {KIND_VERTEX, "diffuse_green", ROLE_GREEN},
    {KIND_VERTEX, "diffuse_blue", ROLE_BLUE},
    {KIND_VERTEX, "u", ROLE_U},          {KIND_VERTEX, "v", ROLE_V},
    {KIND_VERTEX, "s", ROLE_U},          {KIND_VERTEX, "t", ROLE_V},
    {KIND_VERTEX, "texture_u", ROLE_U},  {KIND_VERTEX, "texture_v", ROLE_V},
    {KIND_VERTEX, "texture_s", ROLE_U},  {KIND_VERTEX, "texture_t", ROLE_V},
    {KIND_FACE, "vertex_indices", ROLE_INDICES}, {KIND_FACE, "vertex_index", ROLE_INDICES},
    {KIND_FACE, "texcoord", ROLE_TEXCOORD},
    {KIND_CAMERA, "view_px", ROLE_VIEW_X}, {KIND_CAMERA, "view_py", ROLE_VIEW_Y},
    {KIND_CAMERA, "view_pz", ROLE_VIEW_Z},
    {KIND_GRID, "vertex_indices", ROLE_GRID_INDICES},
};

static int role_of(int kind, const token *name)
{
    for (size_t i = 0; i < sizeof role_names / sizeof role_names[0]; i++)
        if (role_names[i].kind == kind && tok_is(name, role_names[i].name))
            return role_names[i].role;
    return ROLE_SKIP;
}

/* Which roles must be lists (face indices, texcoords, grid) and which scalars. */
static int role_is_list(int role)
{
    return role == ROLE_INDICES || role == ROLE_TEXCOORD || role == ROLE_GRID_INDICES;
}

static int check_role(header_parser *hp, ply_element *e, ply_property *p, const token *name)
{
    char show[48];
    if (p->role == ROLE_SKIP)
        return 0;
    if (role_is_list(p->role) != (p->count_type != PLY_NONE)) {
        if (e->kind == KIND_GRID) { /* an odd range_grid is only skipped, never fatal */
            p->role = ROLE_SKIP;
            return 0;
        }
        return herr(hp, SL_E_BADINPUT, "property '%s' of element %s must %sbe a list",
                    tok_show(name, show, sizeof show), e->name, role_is_list(p->role) ? "" : "not ");
    }
    if ((p->role == ROLE_INDICES || p->role == ROLE_GRID_INDICES) &&
        (p->type == PLY_FLOAT32 || p->type == PLY_FLOAT64))
        return herr(hp, SL_E_BADINPUT, "list '%s' has non-integer index type %s",
                    tok_show(name, show, sizeof show), sl_ply_type_name(p->type));
    for (int i = e->first_prop; i < hp->h->nprops - 1; i++)
        if (hp->h->props[i].role == p->role)
            return herr(hp, SL_E_BADINPUT, "element %s has property '%s' (or a synonym) twice",
                        e->name, tok_show(name, show, sizeof show));
    hp->h->role_seen[p->role] = 1;
    return 0;
}

static int add_row_bytes(header_parser *hp, ply_element *e, ply_property *p)
{
    uint64_t size = (uint64_t)sl_ply_type_size(p->count_type ? p->count_type : p->type);
    p->offset = (uint32_t)e->row_bytes; /* rows have at most 512 * 8 bytes of scalars */
    e->row_bytes += size;
    if (p->count_type)
        e->fixed_row = 0;
    e->min_row_bytes = hp->h->format == SL_PLY_ASCII ? 2 * (uint64_t)e->nprops : e->row_bytes;
    return 0;
}

static int handle_property(header_parser *hp)
{
    ply_header *h = hp->h;
    if (h->nelements == 0)
        return herr(hp, SL_E_BADINPUT, "property before any element");
    if (h->nprops == PLY_MAX_PROPERTIES)
        return herr(hp, SL_E_LIMIT, "more than %d properties", PLY_MAX_PROPERTIES);
    ply_element *e = &h->elements[h->nelements - 1];
    ply_property *p = &h->props[h->nprops];
    memset(p, 0, sizeof *p);
    int is_list = hp->ntok >= 2 && tok_is(&hp->tok[1], "list");
    if (hp->more || hp->ntok != (is_list ? 5 : 3))
        return herr(hp, SL_E_BADINPUT, is_list ? "needs 'property list COUNT_TYPE TYPE NAME'"
                                               : "needs 'property TYPE NAME'");
    int type = 0, rc; /* set by parse_type on success (GCC -O3 cannot tell) */
    if (is_list) {
        int count_type = 0;
        if ((rc = parse_type(hp, &hp->tok[2], &count_type)))
            return rc;
        if (count_type == PLY_FLOAT32 || count_type == PLY_FLOAT64)
            return herr(hp, SL_E_BADINPUT, "list count type %s is not an integer type",
                        sl_ply_type_name(count_type));
        p->count_type = (uint8_t)count_type;
    }
    if ((rc = parse_type(hp, &hp->tok[is_list ? 3 : 1], &type)))
        return rc;
    const token *name = &hp->tok[is_list ? 4 : 2];
    p->type = (uint8_t)type;
    p->role = (uint8_t)role_of(e->kind, name);
    tok_show(name, p->name, sizeof p->name);
    h->nprops++;
    e->nprops++;
    if ((rc = check_role(hp, e, p, name)))
        return rc;
    return add_row_bytes(hp, e, p);
}

/* A number from a comment/obj_info token; comments are free text, so a bad number just
 * means the comment is not the convention we look for. */
static int token_double(const token *t, double *out)
{
    char buf[64];
    if (t->n == 0 || t->n >= sizeof buf)
        return 0;
    memcpy(buf, t->s, t->n);
    buf[t->n] = 0;
    char *end;
    *out = strtod(buf, &end);
    return *end == 0;
}

static void handle_viewpoint(header_parser *hp)
{
    double v[3];
    if (hp->ntok < 5 || !token_double(&hp->tok[2], &v[0]) || !token_double(&hp->tok[3], &v[1]) ||
        !token_double(&hp->tok[4], &v[2]))
        return;
    memcpy(hp->h->viewpoint, v, sizeof v);
    hp->h->has_viewpoint = 1;
}

/* `t` equals one of the '|'-separated words of `words`, ignoring case and one trailing
 * ':' or '=' ("Units:" reads as "units"). */
static int tok_among(const token *t, const char *words)
{
    size_t n = t->n && strchr(":=", t->s[t->n - 1]) ? t->n - 1 : t->n;
    for (const char *w = words; *w;) {
        size_t len = strcspn(w, "|");
        if (len == n && n && strncasecmp(w, t->s, n) == 0)
            return 1;
        w += len + (w[len] == '|');
    }
    return 0;
}

/* Unit and up-axis hints (docs/glb.md "Units and up axis"): `comment units mm` (or unit,
 * with the unit's name spelt out, singular or plural) and `comment up z` (or up_axis,
 * upaxis, up-axis; also a lone `comment Z-up`). Any other comment is free text. */
static void handle_frame_hint(header_parser *hp)
{
    static const struct { const char *canonical, *words; } units[] = {
        {"mm", "mm|millimeter|millimeters|millimetre|millimetres"},
        {"cm", "cm|centimeter|centimeters|centimetre|centimetres"},
        {"m", "m|meter|meters|metre|metres"},
        {"in", "in|inch|inches"},
        {"ft", "ft|foot|feet"}};
    const token *key = &hp->tok[1], *value = hp->ntok >= 3 ? &hp->tok[2] : NULL;
    if (hp->ntok == 2 && tok_among(key, "y-up|z-up"))
        hp->h->up_axis = (char)(key->s[0] | 0x20);
    if (hp->ntok != 3)
        return;
    if (tok_among(key, "units|unit")) {
        for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
            if (tok_among(value, units[i].words))
                snprintf(hp->h->units, sizeof hp->h->units, "%s", units[i].canonical);
    } else if (tok_among(key, "up|up_axis|upaxis|up-axis") && tok_among(value, "y|z|+y|+z")) {
        hp->h->up_axis = (char)(value->s[value->n - 1] | 0x20);
    }
}

static int handle_comment(header_parser *hp)
{
    ply_header *h = hp->h;
    if (hp->ntok < 2)
        return 0;
    if (tok_is(&hp->tok[1], "viewpoint")) {
        handle_viewpoint(hp);
        return 0;
    }
    handle_frame_hint(hp);
    if (hp->ntok < 3 || hp->tok[1].n != 11 || strncasecmp(hp->tok[1].s, "TextureFile", 11) != 0)
        return 0;
    const char *s = hp->tok[2].s, *e = hp->line_end;
    while (e > s && is_space(e[-1]))
        e--;
    if ((size_t)(e - s) >= sizeof h->texture_file)
        return herr(hp, SL_E_LIMIT, "TextureFile name longer than %zu bytes",
                    sizeof h->texture_file - 1);
    memcpy(h->texture_file, s, (size_t)(e - s));
    h->texture_file[e - s] = 0;
    return 0;
}

static void handle_obj_info(header_parser *hp)
{
    double v;
    if (hp->ntok >= 2 && tok_is(&hp->tok[1], "viewpoint")) {
        handle_viewpoint(hp);
        return;
    }
    if (hp->ntok != 3 || !token_double(&hp->tok[2], &v) || !(v >= 0 && v <= 1e9) ||
        v != (int64_t)v)
        return;
    if (tok_is(&hp->tok[1], "num_cols"))
        hp->h->grid_cols = (int64_t)v;
    else if (tok_is(&hp->tok[1], "num_rows"))
        hp->h->grid_rows = (int64_t)v;
}

/* One header line; returns 1 at end_header, 0 to go on, < 0 on error. */
static int handle_line(header_parser *hp)
{
    char show[48];
    token *k = &hp->tok[0];
    if (hp->line == 1)
        return hp->ntok == 1 && tok_is(k, "ply")
                   ? 0
                   : herr(hp, SL_E_BADINPUT, "not a PLY file (the first line is not 'ply')");
    if (hp->ntok == 0)
        return 0;
    if (tok_is(k, "comment"))
        return handle_comment(hp);
    if (tok_is(k, "obj_info")) {
        handle_obj_info(hp);
        return 0;
    }
    if (tok_is(k, "format"))
        return handle_format(hp);
    if (!hp->have_format)
        return herr(hp, SL_E_BADINPUT, "'%s' before the format line", tok_show(k, show, sizeof show));
    if (tok_is(k, "element"))
        return handle_element(hp);
    if (tok_is(k, "property"))
        return handle_property(hp);
    if (tok_is(k, "end_header"))
        return hp->ntok == 1 ? 1 : herr(hp, SL_E_BADINPUT, "text after end_header");
    return herr(hp, SL_E_BADINPUT, "unknown header keyword '%s'", tok_show(k, show, sizeof show));
}

/* Whole-header checks once end_header is seen. */
static int check_elements(header_parser *hp)
{
    ply_header *h = hp->h;
    const ply_element *v = h->vertex_element >= 0 ? &h->elements[h->vertex_element] : NULL;
    const ply_element *f = h->face_element >= 0 ? &h->elements[h->face_element] : NULL;
    if (v && (!h->role_seen[ROLE_X] || !h->role_seen[ROLE_Y] || !h->role_seen[ROLE_Z])) {
        hp->line = v->header_line;
        return herr(hp, SL_E_BADINPUT, "element vertex lacks property x, y or z");
    }
    if (f && f->count > 0 && !h->role_seen[ROLE_INDICES]) {
        hp->line = f->header_line;
        return herr(hp, SL_E_BADINPUT, "element face has no vertex_indices list");
    }
    return 0;
}

static const char *rows_word(const ply_element *e)
{
    return e->kind == KIND_VERTEX ? "vertices" : e->kind == KIND_FACE ? "faces" : "rows";
}

/* Every element's rows need at least min_row_bytes each: the sum must fit the body (an
 * ascii body may lack its final newline, hence one byte of slack). */
static int check_sizes(header_parser *hp, uint64_t body_bytes)
{
    ply_header *h = hp->h;
    uint64_t need = 0, rows_bytes, room = body_bytes + (h->format == SL_PLY_ASCII);
    for (int i = 0; i < h->nelements; i++) {
        ply_element *e = &h->elements[i];
        int overflow = __builtin_mul_overflow(e->count, e->min_row_bytes, &rows_bytes);
        if (!overflow && !__builtin_add_overflow(need, rows_bytes, &rows_bytes) &&
            rows_bytes <= room) {
            need = rows_bytes;
            continue;
        }
        hp->line = e->header_line;
        return herr(hp, SL_E_BADINPUT,
                    "element %s declares %llu %s (at least %llu byte%s each) but the file has "
                    "%llu bytes after the header%s",
                    e->name, (unsigned long long)e->count, rows_word(e),
                    (unsigned long long)e->min_row_bytes, e->min_row_bytes == 1 ? "" : "s",
                    (unsigned long long)body_bytes,
                    need ? ", some needed by earlier elements" : "");
    }
    return 0;
}

/* Configured limits, checked after the sizes so that a count the file cannot hold is
 * reported as malformed input rather than as too large. */
static int check_limits(header_parser *hp)
{
    ply_header *h = hp->h;
    uint64_t max_vertices = hp->lim->max_vertices; /* indices are uint32 */
    if (max_vertices > (uint64_t)UINT32_MAX + 1)
        max_vertices = (uint64_t)UINT32_MAX + 1;
    const ply_element *v = h->vertex_element >= 0 ? &h->elements[h->vertex_element] : NULL;
    const ply_element *f = h->face_element >= 0 ? &h->elements[h->face_element] : NULL;
    if (v && v->count > max_vertices) {
        hp->line = v->header_line;
        return herr(hp, SL_E_LIMIT, "element vertex declares %llu vertices (limit %llu)",
                    (unsigned long long)v->count, (unsigned long long)max_vertices);
    }
    if (f && f->count > hp->lim->max_faces) {
        hp->line = f->header_line;
        return herr(hp, SL_E_LIMIT, "element face declares %llu faces (limit %llu)",
                    (unsigned long long)f->count, (unsigned long long)hp->lim->max_faces);
    }
    return 0;
}

static void header_init(ply_header *h)
{
    memset(h, 0, sizeof *h);
    h->grid_cols = h->grid_rows = -1;
    h->vertex_element = h->face_element = h->camera_element = h->grid_element = -1;
}

int sl_ply_parse_header(const unsigned char *data, size_t size, const char *name,
                        const sl_ply_limits *lim, ply_header *h, sl_error *err)
{
    header_parser hp = {.name = name, .err = err, .h = h, .lim = lim};
    header_init(h);
    if (size == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, name, "empty file");
    size_t window = size < lim->max_header_bytes ? size : (size_t)lim->max_header_bytes;
    const char *s = (const char *)data, *limit = s + window;
    for (;;) {
        hp.line++;
        const char *nl = memchr(s, '\n', (size_t)(limit - s));
        if (!nl && window < size)
            return herr(&hp, SL_E_LIMIT, "no end_header within the first %llu bytes "
                        "(header size limit)", (unsigned long long)lim->max_header_bytes);
        if (!nl)
            return herr(&hp, SL_E_BADINPUT, "file ends inside the header (no end_header)");
        const char *e = nl > s && nl[-1] == '\r' ? nl - 1 : nl;
        split_line(&hp, s, e);
        int rc = handle_line(&hp);
        s = nl + 1;
        if (rc < 0)
            return rc;
        if (rc == 1)
            break;
    }
    h->header_bytes = (uint64_t)(s - (const char *)data);
    int rc = check_elements(&hp);
    if (!rc)
        rc = check_sizes(&hp, size - h->header_bytes);
    return rc ? rc : check_limits(&hp);
}
