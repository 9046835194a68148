/* Loading the collection manifest: the file read whole (bounded), its format picked by
 * its suffix, the text cut into rows by manifest_csv.c or manifest_json.c, the rows
 * finished by manifest.c (manifest.h). */
#include "pipeline/manifest.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/atomicfile.h"

int sl_manifest_load(sl_manifest *m, const char *path, sl_error *err)
{
    memset(m, 0, sizeof *m);
    snprintf(m->path, sizeof m->path, "%s", path);
    char *text = NULL;
    size_t size = 0;
    int rc = sl_read_file(path, SL_MANIFEST_MAX_BYTES, &text, &size, err);
    if (rc == 0) {
        size_t n = strlen(path);
        int json = n >= 5 && !strcasecmp(path + n - 5, ".json");
        /* A byte order mark (spreadsheets write one) is not part of the first cell. */
        size_t bom = size >= 3 && !memcmp(text, "\xef\xbb\xbf", 3) ? 3 : 0;
        rc = json ? sl_manifest_parse_json(m, text + bom, size - bom, err)
                  : sl_manifest_parse_csv(m, text + bom, size - bom, err);
    }
    free(text);
    if (rc == 0)
        rc = sl_manifest_finish_rows(m, err);
    if (rc)
        sl_manifest_release(m);
    return rc;
}
