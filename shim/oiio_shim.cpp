// extern "C" shim around OpenImageIO (see oiio_shim.h for the contract), built as the
// module scanlod-oiio.so: it exports one table (oiio_module.h) that oiio_loader.c loads
// on the first image call.
//
// Rules of the C++ edge: every entry point catches every exception; OIIO's per-thread
// error text (OIIO::geterror / ImageInput::geterror) becomes one sl_error naming the file;
// OIIO's own thread pool is set to one thread before first use because we call it from
// inside OpenMP regions (OIIO's imageio.h: applications with their own threads should set
// "threads" to 1). Writes go to a temp name in the destination directory with the same
// extension (OIIO picks the format from it), then fsync, rename, fsync of the directory.
// core/error.h has no extern "C" guard of its own: give its declarations C linkage
// here, before oiio_shim.h includes it again (then a no-op behind its include guard).
extern "C" {
#include "core/error.h"
}
#include "shim/oiio_module.h"
#include "shim/oiio_shim.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/oiioversion.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <memory>
#include <mutex>
#include <string>
#include <vector>
#include <unistd.h>

namespace {

std::once_flag init_once;

void init_threads()
{
    std::call_once(init_once, [] { OIIO::attribute("threads", 1); });
}

int fail(sl_error *err, int code, const char *path, const std::string &what)
{
    return sl_error_set(err, code, 0, path, "%s", what.c_str());
}

std::string extension_of(const std::string &path)
{
    size_t slash = path.find_last_of('/');
    size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
        return "";
    return path.substr(dot);
}

std::string directory_of(const std::string &path)
{
    size_t slash = path.find_last_of('/');
    if (slash == std::string::npos)
        return ".";
    return slash == 0 ? "/" : path.substr(0, slash);
}

int fsync_path(const std::string &path, int flags, sl_error *err, const char *what)
{
    int fd = open(path.c_str(), flags | O_CLOEXEC);
    if (fd < 0)
        return sl_error_errno(err, errno, path.c_str(), what);
    int rc = fsync(fd);
    int e = errno;
    close(fd);
    return rc == 0 ? SL_OK : sl_error_errno(err, e, path.c_str(), "fsync");
}

std::string temp_name(const std::string &path)
{
    static std::atomic<unsigned> counter{0};
    std::string dir = directory_of(path);
    size_t slash = path.find_last_of('/');
    std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    char tail[64];
    std::snprintf(tail, sizeof tail, ".%ld.%u.tmp", (long)getpid(), counter++);
    return dir + "/." + base + tail + extension_of(path);
}

int write_image(const char *path, int width, int height, int channels, const float *pixels,
                sl_error *err)
{
    std::string final_path(path), tmp = temp_name(final_path);
    std::string ext = extension_of(final_path);
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out)
        return fail(err, SL_E_UNSUPPORTED, path, "no image writer: " + OIIO::geterror());
    bool exr = ext == ".exr" || ext == ".EXR";
    bool png = ext == ".png" || ext == ".PNG";
    OIIO::ImageSpec spec(width, height, channels,
                         png ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT);
    if (exr)
        spec.attribute("compression", "zip"); // lossless; depth needs full float
    if (!out->open(tmp, spec))
        return fail(err, SL_E_IO, path, "cannot open for writing: " + out->geterror());
    bool ok = out->write_image(OIIO::TypeDesc::FLOAT, pixels);
    std::string why = ok ? "" : out->geterror();
    ok = out->close() && ok;
    if (!ok) {
        unlink(tmp.c_str());
        return fail(err, SL_E_IO, path, "write failed: " + (why.empty() ? out->geterror() : why));
    }
    int rc = fsync_path(tmp, O_RDONLY, err, "open");
    if (rc == SL_OK && rename(tmp.c_str(), path) != 0)
        rc = sl_error_errno(err, errno, path, "rename");
    if (rc != SL_OK) {
        unlink(tmp.c_str());
        return rc;
    }
    return fsync_path(directory_of(final_path), O_RDONLY | O_DIRECTORY, err, "open directory");
}

// Reads an opened image whole as float; `path` names it in messages.
int read_opened(OIIO::ImageInput &in, const char *path, uint64_t max_pixels, sl_image *out,
                sl_error *err)
{
    const OIIO::ImageSpec &spec = in.spec();
    uint64_t w = spec.width > 0 ? (uint64_t)spec.width : 0;
    uint64_t h = spec.height > 0 ? (uint64_t)spec.height : 0;
    int ch = spec.nchannels;
    if (w == 0 || h == 0 || ch <= 0 || ch > 64)
        return fail(err, SL_E_BADINPUT, path, "image has no pixels or a bad channel count");
    if (w > max_pixels / h)
        return sl_error_set(err, SL_E_LIMIT, 0, path, "image %llux%llu exceeds %llu pixels",
                            (unsigned long long)w, (unsigned long long)h,
                            (unsigned long long)max_pixels);
    float *pixels = (float *)std::malloc(w * h * (uint64_t)ch * sizeof(float));
    if (!pixels)
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for the image");
    if (!in.read_image(0, 0, 0, ch, OIIO::TypeDesc::FLOAT, pixels)) {
        std::free(pixels);
        return fail(err, SL_E_BADINPUT, path, "cannot decode image: " + in.geterror());
    }
    out->width = (int)w;
    out->height = (int)h;
    out->channels = ch;
    out->pixels = pixels;
    return SL_OK;
}

int read_image(const char *path, uint64_t max_pixels, sl_image *out, sl_error *err)
{
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return fail(err, SL_E_BADINPUT, path, "cannot read image: " + OIIO::geterror());
    return read_opened(*in, path, max_pixels, out, err);
}

// The file extension OpenImageIO picks a decoder by, from a MIME type or else the bytes'
// signature; "" when neither names one it has.
std::string extension_for(const char *mime, const unsigned char *p, size_t size)
{
    static const struct { const char *mime, *ext; } types[] = {
        {"image/jpeg", ".jpg"}, {"image/png", ".png"}, {"image/webp", ".webp"},
        {"image/bmp", ".bmp"},  {"image/gif", ".gif"}, {"image/tiff", ".tif"}};
    for (const auto &t : types)
        if (mime && !std::strcmp(mime, t.mime))
            return t.ext;
    if (size >= 3 && p[0] == 0xFF && p[1] == 0xD8 && p[2] == 0xFF)
        return ".jpg";
    if (size >= 8 && !std::memcmp(p, "\x89PNG\r\n\x1a\n", 8))
        return ".png";
    if (size >= 12 && !std::memcmp(p, "RIFF", 4) && !std::memcmp(p + 8, "WEBP", 4))
        return ".webp";
    return "";
}

int read_memory_image(const void *data, size_t size, const char *mime, const char *name,
                      uint64_t max_pixels, sl_image *out, sl_error *err)
{
    std::string ext = extension_for(mime, static_cast<const unsigned char *>(data), size);
    if (ext.empty())
        return sl_error_set(err, SL_E_UNSUPPORTED, 0, name, "an embedded image of type '%s' "
                            "OpenImageIO cannot decode from memory", mime && *mime ? mime : "?");
    OIIO::Filesystem::IOMemReader proxy(data, size);
    auto in = OIIO::ImageInput::open("embedded" + ext, nullptr, &proxy);
    if (!in)
        return fail(err, SL_E_BADINPUT, name, "cannot read the embedded image: " + OIIO::geterror());
    return read_opened(*in, name, max_pixels, out, err);
}

} // namespace

// Runs `body` with every exception turned into an sl_error about `path`; `code` is the
// class of a std::exception (bad input when reading, I/O when writing).
namespace {
template <class Body> int guarded(const char *path, int code, sl_error *err, Body body)
{
    try {
        init_threads();
        return body();
    } catch (const std::bad_alloc &) {
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory in OpenImageIO");
    } catch (const std::exception &e) {
        return sl_error_set(err, code, 0, path, "OpenImageIO: %s", e.what());
    } catch (...) {
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "OpenImageIO: unknown exception");
    }
}
} // namespace

static int image_read(const char *path, uint64_t max_pixels, sl_image *out, sl_error *err)
{
    // *out is cleared by the caller (oiio_loader.c), which fails without the module too.
    return guarded(path, SL_E_BADINPUT, err,
                   [&] { return read_image(path, max_pixels, out, err); });
}

static int image_read_memory(const void *data, size_t size, const char *mime, const char *name,
                             uint64_t max_pixels, sl_image *out, sl_error *err)
{
    return guarded(name, SL_E_BADINPUT, err, [&] {
        return read_memory_image(data, size, mime, name, max_pixels, out, err);
    });
}

static int image_write(const char *path, int width, int height, int channels,
                       const float *pixels, sl_error *err)
{
    if (width <= 0 || height <= 0 || channels <= 0)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "image write: bad size %dx%dx%d",
                            width, height, channels);
    return guarded(path, SL_E_IO, err,
                   [&] { return write_image(path, width, height, channels, pixels, err); });
}

namespace {
int encode_image(const char *format, int width, int height, int channels, const float *pixels,
                 int quality, void **out, size_t *out_size, sl_error *err)
{
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput proxy(bytes);
    const std::string name = std::string("image.") + format; // OIIO picks the plugin by name
    auto o = OIIO::ImageOutput::create(name, &proxy);
    if (!o || !o->supports("ioproxy"))
        return fail(err, SL_E_INTERNAL, nullptr,
                    std::string("OpenImageIO cannot encode ") + format + " in memory");
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    if (!std::strcmp(format, "jpg"))
        spec.attribute("Compression", "jpeg:" + std::to_string(quality));
    if (!std::strcmp(format, "webp")) // lossy at that quality (OpenImageIO's WebP writer)
        spec.attribute("Compression", "webp:" + std::to_string(quality));
    bool ok = o->open(name, spec) &&
              o->write_image(OIIO::TypeDesc::FLOAT, pixels);
    ok = o->close() && ok;
    if (!ok)
        return fail(err, SL_E_INTERNAL, nullptr, "encoding failed: " + o->geterror());
    *out = std::malloc(bytes.size() ? bytes.size() : 1);
    if (!*out)
        return sl_error_set(err, SL_E_NOMEM, 0, nullptr, "out of memory for an image");
    std::memcpy(*out, bytes.data(), bytes.size());
    *out_size = bytes.size();
    return SL_OK;
}
} // namespace

static int image_encode(const char *format, int width, int height, int channels,
                        const float *pixels, int quality, void **out, size_t *out_size,
                        sl_error *err)
{
    // *out and *out_size are cleared by the caller (oiio_loader.c).
    if (width <= 0 || height <= 0 || channels <= 0)
        return sl_error_set(err, SL_E_INTERNAL, 0, nullptr, "image encode: bad size %dx%dx%d",
                            width, height, channels);
    return guarded(nullptr, SL_E_INTERNAL, err, [&] {
        return encode_image(format, width, height, channels, pixels, quality, out, out_size, err);
    });
}

// The module's one export (everything else is hidden: -fvisibility=hidden).
extern "C" __attribute__((visibility("default"))) const sl_oiio_api *sl_oiio_module_api(void)
{
    static const sl_oiio_api api = {SL_OIIO_MODULE_VERSION, OIIO_VERSION_STRING, image_read,
                                    image_read_memory, image_write, image_encode};
    return &api;
}
