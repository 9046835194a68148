/* The item's frame (export_internal.h; docs/metadata.md, "Frames"): its up axis and units,
 * each from the first that says it of the collection manifest's row, the config ([export]
 * up, units), the file itself (PLY `comment units`/`comment up`, glTF's metres and +Y),
 * else estimated from the geometry (geometry/frame_estimate.h). Never silent: where each
 * came from is in the report, the item's page and, for an estimate, a warning in the log. */
#include <stdio.h>
#include <string.h>

#include "core/log.h"
#include "stages/export/export_internal.h"

/* The estimate, once, when either part needs it (no input: none). */
static int estimate(const sl_mesh *input, sl_export_frame *f)
{
    if (f->estimated)
        return 1;
    sl_error err;
    sl_error_init(&err);
    if (!input || sl_frame_estimate_compute(input, &f->estimate, &err) != 0)
        return 0;
    f->estimated = 1;
    return 1;
}

static void resolve_units(const sl_export_config *c, const sl_item_metadata *meta,
                          const sl_mesh *input, sl_export_frame *f)
{
    const char *units = NULL;
    if (meta && meta->units[0])
        units = meta->units, f->units_from = "manifest";
    else if (c->units_to_metres > 0)
        units = c->units, f->units_from = "config";
    else if (input && input->units[0])
        units = input->units, f->units_from = "file";
    else if (estimate(input, f)) {
        units = f->estimate.units, f->units_from = "estimated";
        snprintf(f->units_why, sizeof f->units_why,
                 "the bounding-box diagonal is %.4g units, which reads as %s for an object "
                 "2 cm to 20 m across (%s %g)", f->estimate.diagonal,
                 !strcmp(units, "mm") ? "millimetres" : "metres",
                 !strcmp(units, "mm") ? "at least" : "under", SL_FRAME_MM_DIAGONAL);
    } else {
        units = "m", f->units_from = "estimated";
        snprintf(f->units_why, sizeof f->units_why, "the input could not be read: taken as "
                 "metres, as given");
    }
    snprintf(f->units, sizeof f->units, "%.3s", units);
    f->to_metres = sl_export_unit_metres(f->units);
}

static void resolve_up(const sl_export_config *c, const sl_item_metadata *meta,
                       const sl_mesh *input, sl_export_frame *f)
{
    if (meta && meta->up[0])
        f->up = meta->up[0], f->up_from = "manifest";
    else if (c->up)
        f->up = c->up, f->up_from = "config";
    else if (input && input->up_axis)
        f->up = input->up_axis, f->up_from = "file";
    else if (estimate(input, f)) {
        const sl_frame_estimate *e = &f->estimate;
        f->up = e->up, f->up_from = "estimated";
        int n = snprintf(f->up_why, sizeof f->up_why,
                         "standing on its lowest %g %% along %c, the scan covers %.0f %% of "
                         "its cross-section, along %c %.0f %%", 100 * SL_FRAME_SLAB, e->up,
                         100 * e->support[e->up == 'z' ? 4 : 2], e->up == 'z' ? 'y' : 'z',
                         100 * e->support[e->up == 'z' ? 2 : 4]);
        int chosen = e->up == 'z' ? 4 : 2;
        if (e->best != chosen && n > 0 && (size_t)n < sizeof f->up_why)
            snprintf(f->up_why + n, sizeof f->up_why - (size_t)n,
                     "; it would stand best on %s (%.0f %%), which the export cannot turn it "
                     "to: the scan may lie on its side or upside down",
                     sl_frame_direction_name(e->best), 100 * e->support[e->best]);
    } else {
        f->up = 'y', f->up_from = "estimated";
        snprintf(f->up_why, sizeof f->up_why, "the input could not be read: taken as +y, "
                 "glTF's up");
    }
}

void sl_export_resolve_frame(const sl_export_config *c, const sl_item_metadata *meta,
                             const sl_mesh *input, sl_export_frame *f)
{
    memset(f, 0, sizeof *f);
    resolve_units(c, meta, input, f);
    resolve_up(c, meta, input, f);
}

void sl_export_report_frame(const sl_export_frame *f, const sl_stage_io *io)
{
    sl_json *r = io->report;
    sl_json_object_begin(r, "frame");
    sl_json_string(r, "units", f->units);
    sl_json_string(r, "units_from", f->units_from);
    sl_json_double(r, "to_metres", f->to_metres);
    sl_json_string(r, "up", f->up == 'z' ? "z" : "y");
    sl_json_string(r, "up_from", f->up_from);
    if (f->units_why[0])
        sl_json_string(r, "units_estimate", f->units_why);
    if (f->up_why[0])
        sl_json_string(r, "up_estimate", f->up_why);
    if (f->estimated) {
        static const char *const keys[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
        sl_json_double(r, "diagonal", f->estimate.diagonal);
        sl_json_object_begin(r, "support");
        for (int d = 0; d < 6; d++)
            sl_json_double(r, keys[d], f->estimate.support[d]);
        sl_json_object_end(r);
    }
    sl_json_object_end(r);
    /* An estimate is a guess a curator should confirm: said where runs are watched. */
    if (f->units_why[0])
        SL_LOG(SL_LOG_WARN, "export", io->item, "units estimated: %s (%s); give them in the "
               "collection manifest or [export] units", f->units, f->units_why);
    if (f->up_why[0])
        SL_LOG(SL_LOG_WARN, "export", io->item, "up axis estimated: %c (%s); give it in the "
               "collection manifest or [export] up", f->up, f->up_why);
}
