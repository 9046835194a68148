/* A scan's texture image, from its file or its embedded bytes (scan_texture.h). */
#include "formats/scan_texture.h"

#include <stdio.h>
#include <string.h>

#include "formats/scan_read.h"

int sl_scan_has_texture(const sl_mesh *m)
{
    return m->texture_file[0] || m->texture_data;
}

const char *sl_scan_texture_name(const sl_mesh *m, char *buf, size_t size)
{
    if (m->texture_file[0])
        snprintf(buf, size, "%s", m->texture_file);
    else if (m->texture_data)
        snprintf(buf, size, "embedded %s (%llu bytes)", m->texture_mime[0] ? m->texture_mime
                 : "image", (unsigned long long)m->texture_size);
    else
        snprintf(buf, size, "none");
    return buf;
}

int sl_scan_texture_read(const sl_mesh *m, const char *dir, uint64_t max_pixels, sl_image *img,
                         char *why, size_t why_size)
{
    char name[300], path[4096], msg[1400];
    sl_scan_texture_name(m, name, sizeof name);
    memset(img, 0, sizeof *img);
    if (!sl_scan_has_texture(m)) {
        snprintf(why, why_size, "the input has no texture");
        return 0;
    }
    sl_error err;
    sl_error_init(&err);
    int rc;
    if (m->texture_data) {
        rc = sl_image_read_memory(m->texture_data, (size_t)m->texture_size, m->texture_mime,
                                  name, max_pixels, img, &err);
    } else {
        int where = sl_scan_sibling_path(dir, m->texture_file, path, sizeof path);
        if (where) {
            snprintf(why, why_size, "texture %s: %s", name,
                     where == -1 ? "not a name inside the input's directory" : "path too long");
            return 0;
        }
        rc = sl_image_read(path, max_pixels, img, &err);
    }
    if (rc) {
        snprintf(why, why_size, "texture %s: %s", name, sl_error_format(&err, msg, sizeof msg));
        return 0;
    }
    if (img->width <= 0 || img->height <= 0 || img->channels <= 0) {
        sl_image_release(img);
        snprintf(why, why_size, "texture %s: empty image", name);
        return 0;
    }
    return 1;
}
