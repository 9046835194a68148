/* Content hashing and the stat-keyed hash cache (see hash.h). */
#include "core/hash.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "core/atomicfile.h"
#include "core/io.h"

void sl_hash_hex(sl_hash h, char out[SL_HASH_HEX_SIZE])
{
    snprintf(out, SL_HASH_HEX_SIZE, "%016" PRIx64 "%016" PRIx64, h.hi, h.lo);
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    return -1;
}

int sl_hash_parse(const char *hex, sl_hash *out)
{
    uint64_t words[2] = {0, 0};
    for (int i = 0; i < 32; i++) {
        int d = hex_digit(hex[i]);
        if (d < 0)
            return -1;
        words[i / 16] = (words[i / 16] << 4) | (uint64_t)d;
    }
    if (hex[32] != '\0' && hex[32] != '\n' && hex[32] != ' ')
        return -1;
    out->hi = words[0];
    out->lo = words[1];
    return 0;
}

int sl_hash_equal(sl_hash a, sl_hash b)
{
    return a.hi == b.hi && a.lo == b.lo;
}

sl_hash sl_hash_bytes(const void *data, size_t size)
{
    XXH128_hash_t h = XXH3_128bits(data, size);
    return (sl_hash){h.high64, h.low64};
}

int sl_hash_file(const char *path, sl_hash *out, uint64_t *size, sl_error *err)
{
    int fd = sl_io_open_regular(path, NULL, err); /* a FIFO must not block a scan */
    if (fd < 0)
        return fd;
    enum { CHUNK = 1 << 20 };
    unsigned char *buf = malloc(CHUNK);
    XXH3_state_t *state = XXH3_createState();
    int rc = 0;
    uint64_t total = 0;
    if (!buf || !state) {
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
        goto done;
    }
    XXH3_128bits_reset(state);
    for (;;) {
        ssize_t r = read(fd, buf, CHUNK);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0) {
            rc = sl_error_errno(err, errno, path, "read");
            goto done;
        }
        if (r == 0)
            break;
        XXH3_128bits_update(state, buf, (size_t)r);
        total += (uint64_t)r;
    }
    XXH128_hash_t h = XXH3_128bits_digest(state);
    *out = (sl_hash){h.high64, h.low64};
    if (size)
        *size = total;
done:
    XXH3_freeState(state);
    free(buf);
    close(fd);
    return rc;
}

void sl_stat_identity(const struct stat *st, char *buf, size_t size)
{
    snprintf(buf, size, "%llu %llu %llu %lld.%09ld %lld.%09ld",
             (unsigned long long)st->st_dev, (unsigned long long)st->st_ino,
             (unsigned long long)st->st_size, (long long)st->st_mtim.tv_sec,
             st->st_mtim.tv_nsec, (long long)st->st_ctim.tv_sec, st->st_ctim.tv_nsec);
}

int sl_hash_file_cached(const char *path, const char *cache_path, sl_hash *out, sl_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return sl_error_errno(err, errno, path, "stat");
    char identity[160];
    sl_stat_identity(&st, identity, sizeof identity);

    char *cached = NULL;
    size_t cached_size = 0;
    sl_error ignored;
    sl_error_init(&ignored);
    if (sl_read_file(cache_path, 4096, &cached, &cached_size, &ignored) == 0) {
        char *nl = strchr(cached, '\n');
        if (nl && (size_t)(nl - cached) == strlen(identity) &&
            memcmp(cached, identity, strlen(identity)) == 0 && sl_hash_parse(nl + 1, out) == 0) {
            free(cached);
            return 0;
        }
    }
    free(cached);

    int rc = sl_hash_file(path, out, NULL, err);
    if (rc)
        return rc;
    /* The file may have changed while we read it: only cache what we can vouch for. */
    struct stat after;
    if (stat(path, &after) != 0 || after.st_mtim.tv_nsec != st.st_mtim.tv_nsec ||
        after.st_mtim.tv_sec != st.st_mtim.tv_sec || after.st_size != st.st_size)
        return sl_error_set(err, SL_E_IO, 0, path, "file changed while it was hashed");
    char hex[SL_HASH_HEX_SIZE], line[256];
    sl_hash_hex(*out, hex);
    int n = snprintf(line, sizeof line, "%s\n%s\n", identity, hex);
    sl_error cache_err;
    sl_error_init(&cache_err);
    /* A cache write failure only costs a re-hash next time; it must not fail the item.
     * (A full disk is caught by the stage's own writes.) */
    sl_write_file_atomic(cache_path, line, (size_t)n, &cache_err);
    return 0;
}
