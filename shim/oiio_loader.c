/* The public image calls of oiio_shim.h, forwarded to the OpenImageIO module
 * (oiio_module.h), which is loaded on the first call. Where it is looked for, in order:
 *   1. $SCANLOD_OIIO_MODULE, when set (a path to the module);
 *   2. beside the installed binary: <dir of /proc/self/exe>/SL_OIIO_MODULE_INSTALLED
 *      (../lib/<arch>/scanlod/scanlod-oiio.so under an install prefix);
 *   3. the build tree's copy (SL_OIIO_MODULE_BUILT, an absolute path the build sets), so
 *      binaries and tests run from the build folder without an install.
 * A module that cannot be loaded makes every image call fail with one error naming the
 * paths tried and dlerror(); the rest of scanlod (everything but textures, thumbnails
 * and image writing) works without it.
 *
 * Memory: loading the module maps about 70 MB of private writable memory (VmData of the
 * export's stage process before and after the load, Debian 12's OpenImageIO 2.4: 38.6 ->
 * 104.6 MB; a process without OpenVDB's libraries loaded already: 0.2 -> 101 MB): the
 * data and relocations of its ~260 libraries and their static constructors. Under an
 * RLIMIT_DATA too small for that ([run] memory_limit_mb) the loader failed half-way:
 * "cannot map zero-fill pages", or a constructor died of std::bad_alloc or a null pointer
 * inside dlopen, where nothing can catch it, and the engine quarantined the item as a
 * scanlod bug (issue 34). The room is therefore asked for first, and its absence, like
 * any mapping the loader is refused, is out of memory (SL_E_NOMEM: retried, never
 * quarantined). */
#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include "shim/oiio_module.h"

static pthread_once_t load_once = PTHREAD_ONCE_INIT;
static const sl_oiio_api *api;
static char module_path[PATH_MAX];
static char load_error[1024];
static int load_out_of_memory; /* a candidate failed for want of memory, not of a file */

/* What loading the module needs under RLIMIT_DATA in a scanlod stage process: the
 * measured 66 MB and a margin (cow's export loads it at a limit of 110 MB, not 100). */
#define MODULE_DATA_MB 80

/* Whether the process may map MODULE_DATA_MB more of private writable memory now: mapped
 * and unmapped at once, never touched (no memory is used). Only a finite RLIMIT_DATA is
 * asked; a cgroup's limit is the kernel OOM killer's business (a SIGKILL the engine takes
 * for out of memory). */
static int room_to_load(void)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_DATA, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY)
        return 1;
    size_t size = (size_t)MODULE_DATA_MB << 20;
    void *p = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE,
                   -1, 0);
    if (p == MAP_FAILED)
        return 0;
    munmap(p, size);
    return 1;
}

/* dlerror() texts of glibc's loader when a mapping or an allocation was refused. */
static int loader_out_of_memory(int saved_errno, const char *why)
{
    static const char *const signs[] = {"failed to map segment", "cannot map zero-fill pages",
                                        "annot allocate memory", "cannot create shared object",
                                        "cannot allocate", "out of memory"};
    if (saved_errno == ENOMEM)
        return 1;
    for (size_t i = 0; why && i < sizeof signs / sizeof signs[0]; i++)
        if (strstr(why, signs[i]))
            return 1;
    return 0;
}

/* Tries one candidate; 1 when the module is loaded, else appends why not to load_error. */
static int try_load(const char *path)
{
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    const char *why = NULL;
    if (h) {
        sl_oiio_api_fn fn;
        *(void **)&fn = dlsym(h, SL_OIIO_MODULE_SYMBOL);
        const sl_oiio_api *a = fn ? fn() : NULL;
        if (a && a->version == SL_OIIO_MODULE_VERSION) {
            api = a;
            snprintf(module_path, sizeof module_path, "%s", path);
            return 1;
        }
        why = a ? "another module version" : "no " SL_OIIO_MODULE_SYMBOL;
        dlclose(h);
    } else {
        int saved = errno;
        why = dlerror();
        if (loader_out_of_memory(saved, why))
            load_out_of_memory = 1;
    }
    size_t used = strlen(load_error);
    snprintf(load_error + used, sizeof load_error - used, "%s%s (%s)", used ? "; " : "", path,
             why ? why : "unknown");
    return 0;
}

static void load(void)
{
    if (!room_to_load()) {
        load_out_of_memory = 1;
        snprintf(load_error, sizeof load_error,
                 "out of memory: loading it needs about %d MB, more than the process's "
                 "limit ([run] memory_limit_mb, RLIMIT_DATA) leaves", MODULE_DATA_MB);
        return;
    }
    const char *env = getenv("SCANLOD_OIIO_MODULE");
    if (env && *env) {
        try_load(env); /* an explicit choice: no fallback behind it */
        return;
    }
    char exe[PATH_MAX], path[PATH_MAX + 64];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        exe[n] = 0;
        char *slash = strrchr(exe, '/');
        if (slash) {
            *slash = 0;
            snprintf(path, sizeof path, "%s/%s", exe, SL_OIIO_MODULE_INSTALLED);
            if (try_load(path))
                return;
        }
    }
#ifdef SL_OIIO_MODULE_BUILT
    try_load(SL_OIIO_MODULE_BUILT);
#endif
}

static const sl_oiio_api *module(const char *path, sl_error *err)
{
    pthread_once(&load_once, load);
    if (!api)
        sl_error_set(err, load_out_of_memory ? SL_E_NOMEM : SL_E_INTERNAL, 0, path,
                     "image support unavailable: cannot load the OpenImageIO module "
                     "scanlod-oiio.so: %s", load_error[0] ? load_error : "not found");
    return api;
}

void sl_oiio_init(void)
{
    pthread_once(&load_once, load);
}

const char *sl_oiio_module_info(const char **path, const char **version)
{
    pthread_once(&load_once, load);
    *path = api ? module_path : NULL;
    *version = api ? api->library_version : NULL;
    return api ? NULL : load_error[0] ? load_error : "not found";
}

int sl_image_read(const char *path, uint64_t max_pixels, sl_image *out, sl_error *err)
{
    out->width = out->height = out->channels = 0;
    out->pixels = NULL;
    const sl_oiio_api *a = module(path, err);
    return a ? a->read(path, max_pixels, out, err) : SL_E_INTERNAL;
}

int sl_image_read_memory(const void *data, size_t size, const char *mime_type, const char *name,
                         uint64_t max_pixels, sl_image *out, sl_error *err)
{
    out->width = out->height = out->channels = 0;
    out->pixels = NULL;
    const sl_oiio_api *a = module(name, err);
    return a ? a->read_memory(data, size, mime_type, name, max_pixels, out, err) : SL_E_INTERNAL;
}

int sl_image_write(const char *path, int width, int height, int channels, const float *pixels,
                   sl_error *err)
{
    const sl_oiio_api *a = module(path, err);
    return a ? a->write(path, width, height, channels, pixels, err) : SL_E_INTERNAL;
}

int sl_image_encode(const char *format, int width, int height, int channels, const float *pixels,
                    int quality, void **out, size_t *out_size, sl_error *err)
{
    *out = NULL;
    *out_size = 0;
    const sl_oiio_api *a = module(NULL, err);
    return a ? a->encode(format, width, height, channels, pixels, quality, out, out_size, err)
             : SL_E_INTERNAL;
}

void sl_image_release(sl_image *img)
{
    if (!img)
        return;
    free(img->pixels);
    img->pixels = NULL;
    img->width = img->height = img->channels = 0;
}
