/* Binary artifact envelope: magic, versions, size, checksum (see artifact.h). */
#include "core/artifact.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "core/atomicfile.h"
#include "core/io.h"

int sl_artifact_write(const char *path, const char magic[8], uint32_t format_version,
                      uint32_t stage_version, const sl_artifact_part *parts, int part_count,
                      sl_error *err)
{
    XXH3_state_t *state = XXH3_createState();
    if (!state)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    XXH3_64bits_reset(state);
    uint64_t body_size = 0;
    for (int i = 0; i < part_count; i++) {
        if (parts[i].size)
            XXH3_64bits_update(state, parts[i].data, parts[i].size);
        body_size += parts[i].size;
    }
    uint64_t checksum = XXH3_64bits_digest(state);
    XXH3_freeState(state);

    unsigned char header[SL_ARTIFACT_HEADER_SIZE];
    memcpy(header, magic, 8);
    sl_put_u32(header + 8, format_version);
    sl_put_u32(header + 12, stage_version);
    sl_put_u64(header + 16, body_size);
    sl_put_u64(header + 24, checksum);

    sl_atomic_file f;
    int rc = sl_atomic_open(&f, path, err);
    if (rc)
        return rc;
    rc = sl_atomic_write(&f, header, sizeof header, err);
    for (int i = 0; rc == 0 && i < part_count; i++)
        if (parts[i].size)
            rc = sl_atomic_write(&f, parts[i].data, parts[i].size, err);
    if (rc) {
        sl_atomic_abort(&f);
        return rc;
    }
    return sl_atomic_commit(&f, err);
}

static int read_all(int fd, void *buf, size_t n)
{
    unsigned char *p = buf;
    while (n > 0) {
        ssize_t r = read(fd, p, n);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return r < 0 ? -1 : 1;
        p += r;
        n -= (size_t)r;
    }
    return 0;
}

int sl_artifact_read(const char *path, const char magic[8], uint32_t format_version,
                     uint64_t max_body_size, void **body, uint64_t *body_size,
                     uint32_t *stage_version, sl_error *err)
{
    uint32_t version;
    return sl_artifact_read_versions(path, magic, format_version, format_version, max_body_size,
                                     body, body_size, stage_version, &version, err);
}

int sl_artifact_open(const char *path, const char magic[8], uint32_t oldest, uint32_t newest,
                     int *fd_out, sl_artifact_info *info, sl_error *err)
{
    *fd_out = -1;
    struct stat st;
    int fd = sl_io_open_regular(path, &st, err);
    if (fd < 0)
        return fd;
    int rc = 0;
    unsigned char header[SL_ARTIFACT_HEADER_SIZE];
    uint32_t version = 0;
    uint64_t size = 0;
    if ((uint64_t)st.st_size < SL_ARTIFACT_HEADER_SIZE || read_all(fd, header, sizeof header)) {
        rc = sl_error_set(err, SL_E_CORRUPT, 0, path, "truncated artifact header");
    } else if (memcmp(header, magic, 8) != 0) {
        rc = sl_error_set(err, SL_E_CORRUPT, 0, path, "not a %.8s file (wrong magic)", magic);
    } else if ((version = sl_get_u32(header + 8)) < oldest || version > newest) {
        if (oldest == newest)
            rc = sl_error_set(err, SL_E_CORRUPT, 0, path,
                              "format version %u, this scanlod reads version %u", version,
                              newest);
        else
            rc = sl_error_set(err, SL_E_CORRUPT, 0, path,
                              "format version %u, this scanlod reads versions %u to %u",
                              version, oldest, newest);
    } else if ((size = sl_get_u64(header + 16)) !=
               (uint64_t)st.st_size - SL_ARTIFACT_HEADER_SIZE) {
        rc = sl_error_set(err, SL_E_CORRUPT, 0, path,
                          "header declares %llu body bytes, file holds %llu",
                          (unsigned long long)size,
                          (unsigned long long)st.st_size - SL_ARTIFACT_HEADER_SIZE);
    }
    if (rc) {
        close(fd);
        return rc;
    }
    *fd_out = fd;
    *info = (sl_artifact_info){version, sl_get_u32(header + 12), size, sl_get_u64(header + 24)};
    return 0;
}

int sl_artifact_pread(int fd, const char *path, void *dest, uint64_t size, uint64_t at,
                      sl_error *err)
{
    unsigned char *p = dest;
    off_t offset = (off_t)(SL_ARTIFACT_HEADER_SIZE + at);
    while (size > 0) {
        ssize_t r = pread(fd, p, size, offset);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return sl_error_set(err, SL_E_IO, errno, path, "cannot read: %s", strerror(errno));
        if (r == 0)
            return sl_error_set(err, SL_E_CORRUPT, 0, path, "file shrank while reading");
        p += r;
        size -= (uint64_t)r;
        offset += r;
    }
    return 0;
}

int sl_artifact_read_versions(const char *path, const char magic[8], uint32_t oldest,
                              uint32_t newest, uint64_t max_body_size, void **body,
                              uint64_t *body_size, uint32_t *stage_version,
                              uint32_t *version_out, sl_error *err)
{
    *body = NULL;
    *body_size = 0;
    int fd = -1;
    sl_artifact_info info;
    int rc = sl_artifact_open(path, magic, oldest, newest, &fd, &info, err);
    if (rc)
        return rc;
    uint64_t size = info.body_size;
    *version_out = info.version;
    void *data = NULL;
    if (size > max_body_size) {
        rc = sl_error_set(err, SL_E_LIMIT, 0, path, "body of %llu bytes exceeds limit %llu",
                          (unsigned long long)size, (unsigned long long)max_body_size);
        goto done;
    }
    data = malloc(size ? size : 1);
    if (!data) {
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
        goto done;
    }
    if (read_all(fd, data, size)) {
        rc = sl_error_set(err, SL_E_CORRUPT, 0, path, "truncated artifact body");
        goto done;
    }
    if (XXH3_64bits(data, size) != info.checksum) {
        rc = sl_error_set(err, SL_E_CORRUPT, 0, path, "checksum mismatch");
        goto done;
    }
    if (stage_version)
        *stage_version = info.stage_version;
    *body = data;
    *body_size = size;
    data = NULL;
done:
    free(data);
    close(fd);
    return rc;
}

int sl_artifact_reader_open(sl_artifact_reader *r, const char *path, const char magic[8],
                            uint32_t oldest, uint32_t newest, uint64_t max_body_size,
                            sl_error *err)
{
    memset(r, 0, sizeof *r);
    r->fd = -1;
    r->path = path;
    int rc = sl_artifact_open(path, magic, oldest, newest, &r->fd, &r->info, err);
    if (rc)
        return rc;
    if (r->info.body_size > max_body_size)
        rc = sl_error_set(err, SL_E_LIMIT, 0, path, "body of %llu bytes exceeds limit %llu",
                          (unsigned long long)r->info.body_size,
                          (unsigned long long)max_body_size);
    else if (!(r->hash = XXH3_createState()))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    else
        XXH3_64bits_reset(r->hash);
    if (rc)
        sl_artifact_reader_close(r);
    return rc;
}

int sl_artifact_reader_take(sl_artifact_reader *r, void *dest, uint64_t size, sl_error *err)
{
    if (size > r->info.body_size - r->at)
        return sl_error_set(err, SL_E_CORRUPT, 0, r->path, "counts exceed the bytes present");
    if (size && read_all(r->fd, dest, size))
        return sl_error_set(err, SL_E_CORRUPT, 0, r->path, "truncated artifact body");
    if (size)
        XXH3_64bits_update(r->hash, dest, size);
    r->at += size;
    return 0;
}

int sl_artifact_reader_take_new(sl_artifact_reader *r, void **dest, uint64_t size, sl_error *err)
{
    *dest = NULL;
    if (size > r->info.body_size - r->at) /* before the allocation it would size */
        return sl_error_set(err, SL_E_CORRUPT, 0, r->path, "counts exceed the bytes present");
    void *p = malloc(size ? size : 1);
    if (!p)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, r->path, "out of memory");
    int rc = sl_artifact_reader_take(r, p, size, err);
    if (rc)
        free(p);
    else
        *dest = p;
    return rc;
}

int sl_artifact_reader_finish(sl_artifact_reader *r, sl_error *err)
{
    if (r->at != r->info.body_size)
        return sl_error_set(err, SL_E_CORRUPT, 0, r->path, "trailing bytes");
    if (XXH3_64bits_digest(r->hash) != r->info.checksum)
        return sl_error_set(err, SL_E_CORRUPT, 0, r->path, "checksum mismatch");
    return 0;
}

void sl_artifact_reader_close(sl_artifact_reader *r)
{
    if (r->fd >= 0)
        close(r->fd);
    if (r->hash)
        XXH3_freeState(r->hash);
    r->fd = -1;
    r->hash = NULL;
}
