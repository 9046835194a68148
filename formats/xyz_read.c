/* Point text files: XYZ, PTS and numeric exports (docs/inputs.md, "XYZ and PTS").
 *
 * One point per line, numbers separated by blanks, commas or semicolons. The first line
 * with three or more numbers fixes the number of columns N, and every point line must have
 * N; what the columns mean follows from N:
 *   3  x y z                 7  x y z intensity r g b  (Leica PTS)
 *   4  x y z intensity       9  x y z, then two triples: one colour, one normal
 *   6  x y z, then a triple  10 x y z intensity, then two triples
 * A triple is a normal when every row of it has length 1 (within 5 %), a colour when every
 * component is an integer in 0..255 or a number in [0, 1] that is not such a normal; when
 * the data cannot tell (or two triples look alike) the file is refused as unsupported, never
 * guessed. Intensity is not read. A line holding one integer is a PTS point count (PTS
 * files begin with one, and repeat one per scan): skipped. Lines before the first point
 * that are not numbers are a header, skipped (at most 100, with a warning); blank lines and
 * lines starting with '#' or "//" are skipped anywhere.
 *
 * A first pass counts the candidate lines, which bounds the allocation by the file's
 * lines; the second stores every column, and the meaning is decided at the end.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats/scan_internal.h"

#define MAX_COLUMNS 10
#define MAX_HEADER_LINES 100
#define SEPARATORS ",;"
#define TICK_ROWS 0xffff

enum { TRIPLE_UNKNOWN, TRIPLE_NORMAL, TRIPLE_COLOR };

typedef struct xyz_reader {
    const scan_src *s;
    sl_mesh *m;
    int columns;              /* N, from the first point line */
    uint64_t lines;           /* lines with content (first pass): the most points there are */
    uint64_t header_lines, count_lines;
    float *values;            /* columns per point */
} xyz_reader;

static int skipped_line(const text_cursor *c)
{
    const char *p = text_skip(c->line, c->eol);
    return p == c->eol || *p == '#' || (c->eol - p >= 2 && p[0] == '/' && p[1] == '/');
}

/* Numbers on the line into x (up to MAX_COLUMNS + 1 counted); -1 when a token is not one. */
static int line_numbers(const text_cursor *c, float *x)
{
    const char *p = c->line;
    float ignored;
    int n = 0, rc;
    while ((rc = text_float(c, &p, SEPARATORS, n < MAX_COLUMNS ? &x[n] : &ignored)) == 1)
        if (++n > MAX_COLUMNS)
            break;
    return rc < 0 ? -1 : n;
}

/* The first pass: content lines, and the column count of the first point line. */
static int count_lines(xyz_reader *r)
{
    text_cursor c;
    text_begin(&c, r->s);
    float x[MAX_COLUMNS];
    int rc;
    while (text_next_line(&c)) {
        if (skipped_line(&c))
            continue;
        r->lines++;
        if (!r->columns) {
            int n = line_numbers(&c, x);
            r->columns = n >= 3 ? n : 0;
        }
        if ((c.number & TICK_ROWS) == 0 && (rc = scan_tick(r->s, c.p)))
            return rc;
    }
    if (!r->columns)
        return scan_error(r->s, SL_E_BADINPUT, 0, "no line with three numbers (x y z)");
    if (r->columns == 5 || r->columns == 8 || r->columns > MAX_COLUMNS)
        return scan_error(r->s, SL_E_UNSUPPORTED, 0, "%d columns: not a layout scanlod knows "
                          "(3, 4, 6, 7, 9 or 10; docs/inputs.md)", r->columns);
    return scan_check_limit(r->s, "lines", r->lines, r->s->lim->max_vertices);
}

static int read_line(xyz_reader *r, const text_cursor *c)
{
    float x[MAX_COLUMNS];
    int n = line_numbers(c, x);
    if (n == r->columns) {
        memcpy(r->values + (uint64_t)r->columns * r->m->vertex_count++, x,
               (size_t)n * sizeof(float));
        return 0;
    }
    if (n == 1 && x[0] >= 0 && x[0] == floorf(x[0])) {
        r->count_lines++; /* a PTS count */
        return 0;
    }
    if (n < 0 && r->m->vertex_count == 0 && r->count_lines == 0 &&
        r->header_lines < MAX_HEADER_LINES) {
        r->header_lines++;
        return 0;
    }
    if (n < 0)
        return scan_error(r->s, SL_E_BADINPUT, c->number, "not a number");
    return scan_error(r->s, SL_E_BADINPUT, c->number, "%d numbers where the file's points "
                      "have %d", n, r->columns);
}

/* What a triple of columns holds, over every point. */
static int classify(const float *values, int stride, uint64_t n)
{
    int unit = 1, any_unit = 0, bytes = 1, fractions = 1;
    for (uint64_t i = 0; i < n; i++) {
        const float *v = values + i * stride;
        double len = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
        any_unit |= fabs(len - 1.0) <= 0.05;
        unit &= fabs(len - 1.0) <= 0.05 || len == 0; /* a scanner's "no normal" */
        for (int k = 0; k < 3; k++) {
            bytes &= v[k] >= 0 && v[k] <= 255 && v[k] == floorf(v[k]);
            fractions &= v[k] >= 0 && v[k] <= 1;
        }
    }
    return unit && any_unit ? TRIPLE_NORMAL : bytes || fractions ? TRIPLE_COLOR : TRIPLE_UNKNOWN;
}

static int take_triple(xyz_reader *r, int first, int kind)
{
    sl_mesh *m = r->m;
    uint64_t n = m->vertex_count;
    int rc = 0;
    if (kind == TRIPLE_NORMAL && !m->normals &&
        (m->normals = scan_alloc(r->s, n, 3 * sizeof(float), &rc)))
        for (uint64_t i = 0; i < n; i++)
            memcpy(m->normals + 3 * i, r->values + i * r->columns + first, 3 * sizeof(float));
    else if (kind == TRIPLE_COLOR && !m->colors && (m->colors = scan_alloc(r->s, n, 4, &rc)))
        scan_float_colors(r->values + first, r->columns, 3, n, m->colors);
    else if (!rc)
        rc = scan_error(r->s, SL_E_UNSUPPORTED, 0, "columns %d to %d hold %s: the data cannot "
                        "tell colours from normals", first + 1, first + 3,
                        kind == TRIPLE_UNKNOWN ? "neither unit normals nor colours"
                                               : "the same kind as the other triple");
    return rc;
}

/* Positions and the triples, by the column count (table above). */
static int assign_columns(xyz_reader *r)
{
    sl_mesh *m = r->m;
    uint64_t n = m->vertex_count;
    int rc = 0, first = r->columns == 4 || r->columns == 7 || r->columns == 10 ? 4 : 3;
    if (!(m->positions = scan_alloc(r->s, n, 3 * sizeof(float), &rc)))
        return rc;
    for (uint64_t i = 0; i < n; i++)
        memcpy(m->positions + 3 * i, r->values + i * r->columns, 3 * sizeof(float));
    if (r->columns == 7) {
        if (!(m->colors = scan_alloc(r->s, n, 4, &rc)))
            return rc;
        scan_float_colors(r->values + 4, 7, 3, n, m->colors);
        return 0;
    }
    for (int t = first; !rc && t + 3 <= r->columns; t += 3)
        rc = take_triple(r, t, classify(r->values + t, r->columns, n));
    return rc;
}

static void fill_info(const xyz_reader *r, uint64_t points, sl_scan_info *info)
{
    const char *ext = strrchr(r->s->name, '.');
    snprintf(info->format, sizeof info->format, "%s",
             ext && !strcasecmp(ext, ".pts") ? "pts" : "xyz");
    snprintf(info->detail, sizeof info->detail, "point text, %d columns, %llu %s", r->columns,
             (unsigned long long)points, r->m ? "points" : "lines (at most that many points)");
    info->declared_vertices = points;
    info->has_colors = r->columns >= 7;
    info->has_normals = r->columns >= 9;
}

int sl_xyz_info_source(const scan_src *s, sl_scan_info *info)
{
    xyz_reader r = {.s = s};
    int rc = count_lines(&r);
    if (!rc)
        fill_info(&r, r.lines, info);
    return rc;
}

int sl_xyz_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info)
{
    xyz_reader r = {.s = s, .m = out};
    int rc = count_lines(&r);
    if (!rc)
        r.values = scan_alloc(s, r.lines, (size_t)r.columns * sizeof(float), &rc);
    text_cursor c;
    text_begin(&c, s);
    while (!rc && text_next_line(&c)) {
        if (!skipped_line(&c))
            rc = read_line(&r, &c);
        if (!rc && (c.number & TICK_ROWS) == 0)
            rc = scan_tick(s, c.p);
    }
    if (!rc)
        rc = assign_columns(&r);
    if (!rc && r.header_lines)
        sl_mesh_warn(out, "%llu header lines skipped", (unsigned long long)r.header_lines);
    if (!rc && info) {
        fill_info(&r, out->vertex_count, info);
        info->has_colors = out->colors != NULL;
        info->has_normals = out->normals != NULL;
    }
    free(r.values);
    return rc;
}

int sl_xyz_sniff(const unsigned char *data, size_t size)
{
    scan_src s = {.name = "", .data = data, .size = size < 4096 ? size : 4096};
    text_cursor c;
    text_begin(&c, &s);
    float x[MAX_COLUMNS];
    int lines = 0;
    while (lines < 8 && text_next_line(&c)) {
        if (c.p == c.end && size > s.size)
            break; /* a line cut by the window */
        if (skipped_line(&c))
            continue;
        int n = line_numbers(&c, x);
        if (n < 3 && !(n == 1 && lines == 0))
            return 0;
        lines++;
    }
    return lines > 0;
}
