// extern "C" shim around OpenVDB (see vdb_shim.h for the contract and the file layout).
//
// Rules of the C++ edge: every entry point catches every exception into an sl_error
// naming the file; openvdb::initialize() runs once (std::call_once) before any grid is
// made or read; TBB is capped through one process-wide tbb::global_control.
//
// Determinism: OpenVDB's Archive::writeHeader puts a random UUID (36 ASCII characters,
// right after magic, file version, library version and the grid-offsets flag) in every
// file, and Archive::writeGrid adds grid statistics metadata unless disabled. We disable
// the statistics and, after OpenVDB has serialised the grids into memory, overwrite the
// UUID with the XXH3-128 of the file taken with those 36 bytes set to '0'. The result is a
// pure function of the samples, and the reader gets a checksum for free: it recomputes
// the hash before handing the bytes to OpenVDB, whose decoders trust their input.
// pipeline headers have no extern "C" guards of their own: give them C linkage here,
// before vdb_shim.h includes error.h again (a no-op behind its include guard).
extern "C" {
#include "core/atomicfile.h"
#include "core/error.h"
#include "core/hash.h"
}
#include "shim/vdb_shim.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <tbb/global_control.h>
#include <tbb/parallel_sort.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <vector>

namespace {

// Header layout of OpenVDB files of format >= 222 (io/Archive.cc writeHeader): int64
// magic, u32 file version, u32 library major, u32 library minor, u8 has-grid-offsets,
// then the UUID as 36 ASCII characters ("8-4-4-4-12" hex digits).
constexpr size_t kVersionOffset = 8;
constexpr size_t kUuidOffset = 21;
constexpr size_t kUuidSize = 36;
constexpr uint32_t kMinFileVersion = 222;
const char *const kDistanceName = "distance";
const char *const kColorName = "color";
const char *const kVersionKey = "scanlod_samples_version";

std::once_flag init_once;
std::mutex cap_mutex;
std::unique_ptr<tbb::global_control> thread_cap;

void init_openvdb()
{
    std::call_once(init_once, [] { openvdb::initialize(); });
}

bool is_uuid_hyphen(size_t i)
{
    return i == 8 || i == 13 || i == 18 || i == 23;
}

// The content hash spelled as a UUID (32 lowercase hex digits, four hyphens): XXH3-128
// of the file with its UUID field set to '0's. The field is restored before returning.
std::string content_uuid(char *bytes, size_t size)
{
    std::string stored(bytes + kUuidOffset, kUuidSize);
    std::memset(bytes + kUuidOffset, '0', kUuidSize);
    char hex[SL_HASH_HEX_SIZE];
    sl_hash_hex(sl_hash_bytes(bytes, size), hex);
    std::memcpy(bytes + kUuidOffset, stored.data(), kUuidSize);
    std::string uuid;
    for (size_t i = 0, h = 0; i < kUuidSize; i++)
        uuid += is_uuid_hyphen(i) ? '-' : hex[h++];
    return uuid;
}

bool header_looks_right(const std::string &bytes)
{
    if (bytes.size() < kUuidOffset + kUuidSize)
        return false;
    int64_t magic;
    uint32_t version;
    std::memcpy(&magic, bytes.data(), sizeof magic);
    std::memcpy(&version, bytes.data() + kVersionOffset, sizeof version);
    if (magic != openvdb::OPENVDB_MAGIC || version < kMinFileVersion)
        return false;
    for (size_t i = 0; i < kUuidSize; i++)
        if (is_uuid_hyphen(i) != (bytes[kUuidOffset + i] == '-'))
            return false;
    return true;
}

// Built as a uniform scale, then translated: Transform's constructor from a map would
// "simplify" it through an affine matrix and lose the last bit of the voxel size.
openvdb::math::Transform::Ptr make_transform(const sl_vdb_samples *s)
{
    openvdb::math::Transform::Ptr t = openvdb::math::Transform::createLinearTransform(s->leaf_size);
    t->postTranslate(openvdb::Vec3d(s->origin[0], s->origin[1], s->origin[2]));
    return t;
}

openvdb::Coord coord_at(const sl_vdb_samples *s, uint64_t i)
{
    return openvdb::Coord(s->coords[3 * i], s->coords[3 * i + 1], s->coords[3 * i + 2]);
}

int check_samples(const char *path, const sl_vdb_samples *s, sl_error *err)
{
    if (!(std::isfinite(s->leaf_size) && s->leaf_size > 0.0))
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "samples: voxel size %g is not positive",
                            s->leaf_size);
    for (int k = 0; k < 3; k++)
        if (!std::isfinite(s->origin[k]))
            return sl_error_set(err, SL_E_INTERNAL, 0, path, "samples: non-finite origin");
    if (s->count > 0 && (!s->coords || !s->distance))
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "samples: missing arrays");
    for (uint64_t i = 0; i < s->count; i++) {
        if (!std::isfinite(s->distance[i]))
            return sl_error_set(err, SL_E_INTERNAL, 0, path, "samples: distance %llu is not finite",
                                (unsigned long long)i);
        if (i > 0 && !(coord_at(s, i - 1) < coord_at(s, i)))
            return sl_error_set(err, SL_E_INTERNAL, 0, path,
                                "samples: coordinates not strictly increasing at %llu",
                                (unsigned long long)i);
    }
    return SL_OK;
}

int32_t pack_rgba(const uint8_t *c)
{
    uint32_t v = (uint32_t)c[0] | (uint32_t)c[1] << 8 | (uint32_t)c[2] << 16 |
                 (uint32_t)c[3] << 24;
    int32_t packed;
    std::memcpy(&packed, &v, sizeof packed);
    return packed;
}

void unpack_rgba(int32_t packed, uint8_t *c)
{
    uint32_t v;
    std::memcpy(&v, &packed, sizeof v);
    for (int k = 0; k < 4; k++)
        c[k] = (uint8_t)(v >> (8 * k));
}

// An output std::streambuf appending to a string we own: OpenVDB serialises into it and
// we patch and write those very bytes (an ostringstream would hand out a second copy).
class StringSink : public std::streambuf {
public:
    std::string bytes;

protected:
    std::streamsize xsputn(const char *data, std::streamsize n) override
    {
        bytes.append(data, (size_t)n);
        return n;
    }
    int_type overflow(int_type c) override
    {
        if (!traits_type::eq_int_type(c, traits_type::eof()))
            bytes.push_back(traits_type::to_char_type(c));
        return traits_type::not_eof(c);
    }
};

int write_samples(const char *path, const sl_vdb_samples *s, sl_error *err)
{
    int rc = check_samples(path, s, err);
    if (rc != SL_OK)
        return rc;
    openvdb::math::Transform::Ptr xform = make_transform(s);
    openvdb::FloatGrid::Ptr distance = openvdb::FloatGrid::create(0.0f);
    distance->setName(kDistanceName);
    distance->setTransform(xform);
    openvdb::GridPtrVec grids{distance};
    {
        openvdb::FloatGrid::Accessor acc = distance->getAccessor();
        for (uint64_t i = 0; i < s->count; i++)
            acc.setValue(coord_at(s, i), s->distance[i]);
    }
    if (s->colors) {
        openvdb::Int32Grid::Ptr color = openvdb::Int32Grid::create(0);
        color->setName(kColorName);
        color->setTransform(xform->copy());
        openvdb::Int32Grid::Accessor acc = color->getAccessor();
        for (uint64_t i = 0; i < s->count; i++)
            acc.setValue(coord_at(s, i), pack_rgba(s->colors + 4 * i));
        grids.push_back(color);
    }
    openvdb::MetaMap meta;
    meta.insertMeta(kVersionKey, openvdb::Int32Metadata(SL_VDB_SAMPLES_VERSION));
    StringSink sink;
    std::ostream os(&sink);
    openvdb::io::Stream vdb(os);
    vdb.setGridStatsMetadataEnabled(false); // no derived metadata: bytes = f(samples)
    vdb.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    vdb.write(grids, meta);
    grids.clear(); // the trees are serialised: give their memory back before the write
    distance.reset();
    std::string &bytes = sink.bytes;
    if (!os.good())
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "OpenVDB could not serialise the grids");
    if (!header_looks_right(bytes))
        return sl_error_set(err, SL_E_INTERNAL, 0, path,
                            "OpenVDB %s wrote a header of an unexpected layout (the UUID "
                            "cannot be made deterministic)", openvdb::getLibraryVersionString());
    std::string uuid = content_uuid(&bytes[0], bytes.size());
    std::memcpy(&bytes[kUuidOffset], uuid.data(), kUuidSize);
    return sl_write_file_atomic(path, bytes.data(), bytes.size(), err);
}

// A read-only std::streambuf over bytes we already hold (no copy into a stringstream).
class MemoryBuffer : public std::streambuf {
public:
    MemoryBuffer(char *data, size_t size) { setg(data, data, data + size); }

protected:
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override
    {
        char *base = dir == std::ios_base::beg ? eback() : dir == std::ios_base::cur ? gptr() : egptr();
        if (off < eback() - base || off > egptr() - base)
            return pos_type(off_type(-1));
        setg(eback(), base + off, egptr());
        return pos_type(gptr() - eback());
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode mode) override
    {
        return seekoff(off_type(pos), std::ios_base::beg, mode);
    }
};

struct Entry {
    int32_t x, y, z;
    float distance;
    bool operator<(const Entry &o) const
    {
        return x != o.x ? x < o.x : y != o.y ? y < o.y : z < o.z;
    }
};

int corrupt(sl_error *err, const char *path, const char *why)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, path, "not a scanlod samples file: %s", why);
}

// Finds the distance and colour grids among `grids`; anything else is refused.
int pick_grids(const char *path, const openvdb::GridPtrVec &grids, openvdb::FloatGrid::Ptr *distance,
               openvdb::Int32Grid::Ptr *color, sl_error *err)
{
    for (const openvdb::GridBase::Ptr &g : grids) {
        if (!g)
            continue;
        if (g->getName() == kDistanceName && !*distance &&
            (*distance = openvdb::gridPtrCast<openvdb::FloatGrid>(g)))
            continue;
        if (g->getName() == kColorName && !*color &&
            (*color = openvdb::gridPtrCast<openvdb::Int32Grid>(g)))
            continue;
        return corrupt(err, path, ("unexpected grid \"" + g->getName() + "\" of type " +
                                   g->type()).c_str());
    }
    if (!*distance)
        return corrupt(err, path, "no FloatGrid \"distance\"");
    const openvdb::math::Transform &t = (*distance)->transform();
    if (!t.isLinear() || !t.hasUniformScale() || !(t.voxelSize()[0] > 0.0))
        return corrupt(err, path, "the transform is not a uniform scale + translation");
    if (*color && !((*color)->transform() == t))
        return corrupt(err, path, "the colour grid has another transform");
    return SL_OK;
}

int read_samples(const char *path, uint64_t max_count, sl_vdb_samples *out, sl_error *err)
{
    // Guard against absurd files before reading them; the real cap is the voxel count.
    uint64_t per_sample = 4096, cap = UINT64_C(1) << 40;
    uint64_t max_size = max_count < (cap >> 12) ? (1u << 20) + max_count * per_sample : cap;
    char *data = nullptr;
    size_t size = 0;
    int rc = sl_read_file(path, max_size, &data, &size, err);
    if (rc != SL_OK)
        return rc;
    std::unique_ptr<char, decltype(&std::free)> hold(data, &std::free);
    std::string head(data, size < kUuidOffset + kUuidSize ? size : kUuidOffset + kUuidSize);
    if (!header_looks_right(head))
        return corrupt(err, path, "no OpenVDB header of format >= 222");
    std::string stored(data + kUuidOffset, kUuidSize), expect = content_uuid(data, size);
    if (stored != expect)
        return sl_error_set(err, SL_E_CORRUPT, 0, path,
                            "content hash mismatch (header %s, content %s): the file is "
                            "damaged or was not written by scanlod", stored.c_str(), expect.c_str());

    MemoryBuffer buffer(data, size);
    std::istream is(&buffer);
    openvdb::io::Stream vdb(is, /*delayLoad=*/false);
    openvdb::MetaMap::Ptr meta = vdb.getMetadata();
    openvdb::Int32Metadata::Ptr version =
        meta ? meta->getMetadata<openvdb::Int32Metadata>(kVersionKey) : nullptr;
    if (!version || version->value() != SL_VDB_SAMPLES_VERSION)
        return corrupt(err, path, "missing or unknown scanlod_samples_version");
    openvdb::GridPtrVecPtr grids = vdb.getGrids();
    openvdb::FloatGrid::Ptr distance;
    openvdb::Int32Grid::Ptr color;
    if (!grids || (rc = pick_grids(path, *grids, &distance, &color, err)) != SL_OK)
        return grids ? rc : corrupt(err, path, "no grids");
    const openvdb::FloatTree &tree = distance->tree();
    uint64_t count = tree.activeVoxelCount();
    if (count > max_count)
        return sl_error_set(err, SL_E_LIMIT, 0, path, "%llu samples exceed the limit of %llu",
                            (unsigned long long)count, (unsigned long long)max_count);
    if (tree.activeTileCount() != 0 || (color && color->tree().activeTileCount() != 0) ||
        (color && color->tree().activeVoxelCount() != count))
        return corrupt(err, path, "grids with active tiles or different active voxels");

    std::vector<Entry> entries;
    entries.reserve(count);
    for (openvdb::FloatTree::LeafCIter leaf = tree.cbeginLeaf(); leaf; ++leaf)
        for (auto v = leaf->cbeginValueOn(); v; ++v) {
            openvdb::Coord c = v.getCoord();
            entries.push_back(Entry{c.x(), c.y(), c.z(), *v});
        }
    tbb::parallel_sort(entries.begin(), entries.end()); // keys are unique: deterministic

    sl_vdb_samples s;
    std::memset(&s, 0, sizeof s);
    s.count = count;
    s.coords = (int32_t *)std::malloc(3 * count * sizeof(int32_t) + 1);
    s.distance = (float *)std::malloc(count * sizeof(float) + 1);
    s.colors = color ? (uint8_t *)std::malloc(4 * count + 1) : nullptr;
    if (!s.coords || !s.distance || (color && !s.colors)) {
        sl_vdb_samples_release(&s);
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for %llu samples",
                            (unsigned long long)count);
    }
    std::unique_ptr<openvdb::Int32Grid::ConstAccessor> colors;
    if (color)
        colors.reset(new openvdb::Int32Grid::ConstAccessor(color->getConstAccessor()));
    for (uint64_t i = 0; i < count; i++) {
        const Entry &e = entries[i];
        s.coords[3 * i] = e.x, s.coords[3 * i + 1] = e.y, s.coords[3 * i + 2] = e.z;
        s.distance[i] = e.distance;
        int32_t packed = 0;
        if (color && !colors->probeValue(openvdb::Coord(e.x, e.y, e.z), packed)) {
            sl_vdb_samples_release(&s);
            return corrupt(err, path, "a sample without a colour");
        }
        if (color)
            unpack_rgba(packed, s.colors + 4 * i);
    }
    const openvdb::math::Transform &t = distance->transform();
    s.leaf_size = t.voxelSize()[0];
    openvdb::Vec3d o = t.indexToWorld(openvdb::Vec3d(0.0, 0.0, 0.0));
    for (int k = 0; k < 3; k++)
        s.origin[k] = o[k];
    *out = s;
    return SL_OK;
}

// Runs `body` with every exception turned into an sl_error about `path`.
template <class Body> int guarded(const char *path, int code, sl_error *err, Body body)
{
    try {
        init_openvdb();
        return body();
    } catch (const std::bad_alloc &) {
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory in OpenVDB");
    } catch (const std::exception &e) {
        return sl_error_set(err, code, 0, path, "OpenVDB: %s", e.what());
    } catch (...) {
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "OpenVDB: unknown exception");
    }
}

} // namespace

extern "C" void sl_vdb_set_threads(int n)
{
    try {
        std::unique_ptr<tbb::global_control> next;
        if (n > 0)
            next.reset(new tbb::global_control(tbb::global_control::max_allowed_parallelism,
                                               (size_t)n));
        std::lock_guard<std::mutex> lock(cap_mutex);
        thread_cap.swap(next); // the old cap (if any) ends when `next` goes out of scope
    } catch (...) {
        // Without memory for the cap TBB keeps its previous limit; nothing to report to.
    }
}

extern "C" int sl_vdb_samples_write(const char *path, const sl_vdb_samples *s, sl_error *err)
{
    return guarded(path, SL_E_INTERNAL, err, [&] { return write_samples(path, s, err); });
}

extern "C" int sl_vdb_samples_read(const char *path, uint64_t max_count, sl_vdb_samples *out,
                                   sl_error *err)
{
    std::memset(out, 0, sizeof *out);
    return guarded(path, SL_E_CORRUPT, err, [&] { return read_samples(path, max_count, out, err); });
}

extern "C" void sl_vdb_samples_release(sl_vdb_samples *s)
{
    if (!s)
        return;
    std::free(s->coords);
    std::free(s->distance);
    std::free(s->colors);
    std::memset(s, 0, sizeof *s);
}
