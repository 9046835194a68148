// extern "C" shim around Draco (see draco_shim.h for the contract).
//
// The mesh is built the way Draco's own glTF tooling builds it: one point per glTF vertex
// (identity attribute mapping), faces as point triples, one attribute per glTF semantic.
// Decoding reads each attribute per point through the point -> value map, so vertices Draco
// deduplicated or split come out as the points of the decoded mesh.
extern "C" {
#include "core/error.h"
}
#include "shim/draco_shim.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>

namespace {

draco::GeometryAttribute::Type semantic_type(int s)
{
    switch (s) {
    case SL_DRACO_POSITION: return draco::GeometryAttribute::POSITION;
    case SL_DRACO_NORMAL: return draco::GeometryAttribute::NORMAL;
    case SL_DRACO_COLOR: return draco::GeometryAttribute::COLOR;
    default: return draco::GeometryAttribute::TEX_COORD;
    }
}

const struct {
    int type;
    draco::DataType draco;
    int size;
} types[] = {
    {SL_DRACO_F32, draco::DT_FLOAT32, 4}, {SL_DRACO_U8, draco::DT_UINT8, 1},
    {SL_DRACO_U16, draco::DT_UINT16, 2},  {SL_DRACO_I8, draco::DT_INT8, 1},
    {SL_DRACO_I16, draco::DT_INT16, 2},   {SL_DRACO_U32, draco::DT_UINT32, 4},
};

draco::DataType data_type(int t)
{
    for (const auto &k : types)
        if (k.type == t)
            return k.draco;
    return draco::DT_INVALID;
}

int type_of(draco::DataType d)
{
    for (const auto &k : types)
        if (k.draco == d)
            return k.type;
    return SL_DRACO_ANY;
}

int type_size(int t)
{
    for (const auto &k : types)
        if (k.type == t)
            return k.size;
    return 0;
}

int encode(sl_draco_mesh *m, int speed, void **out, size_t *out_size, sl_error *err)
{
    if (m->vertex_count >= (1u << 31) || m->triangle_count >= (1u << 31) ||
        m->attribute_count < 1 || m->attribute_count > SL_DRACO_MAX_ATTRIBUTES)
        return sl_error_set(err, SL_E_LIMIT, 0, nullptr,
                            "Draco: %llu vertices, %llu triangles, %d attributes",
                            (unsigned long long)m->vertex_count,
                            (unsigned long long)m->triangle_count, m->attribute_count);
    draco::Mesh mesh;
    mesh.set_num_points((uint32_t)m->vertex_count);
    mesh.SetNumFaces((size_t)m->triangle_count);
    for (uint64_t f = 0; f < m->triangle_count; f++) {
        draco::Mesh::Face face;
        for (int k = 0; k < 3; k++)
            face[k] = draco::PointIndex(m->triangles[3 * f + k]);
        mesh.SetFace(draco::FaceIndex((uint32_t)f), face);
    }
    draco::Encoder enc;
    for (int a = 0; a < m->attribute_count; a++) {
        sl_draco_attribute *at = &m->attributes[a];
        const int stride = at->components * type_size(at->type);
        draco::GeometryAttribute ga;
        ga.Init(semantic_type(at->semantic), nullptr, (uint8_t)at->components,
                data_type(at->type), at->normalized != 0, stride, 0);
        const int id = mesh.AddAttribute(ga, true, (uint32_t)m->vertex_count);
        draco::PointAttribute *pa = mesh.attribute(id);
        const unsigned char *src = static_cast<const unsigned char *>(at->data);
        for (uint64_t i = 0; i < m->vertex_count; i++)
            pa->SetAttributeValue(draco::AttributeValueIndex((uint32_t)i), src + i * stride);
        at->unique_id = (int)pa->unique_id();
        if (at->type == SL_DRACO_F32)
            enc.SetAttributeQuantization(semantic_type(at->semantic), at->bits);
    }
    enc.SetSpeedOptions(speed, speed);
    enc.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
    draco::EncoderBuffer buffer;
    const draco::Status s = enc.EncodeMeshToBuffer(mesh, &buffer);
    if (!s.ok())
        return sl_error_set(err, SL_E_INTERNAL, 0, nullptr, "Draco encoder: %s", s.error_msg());
    *out = std::malloc(buffer.size() ? buffer.size() : 1);
    if (!*out)
        return sl_error_set(err, SL_E_NOMEM, 0, nullptr, "Draco: out of memory");
    std::memcpy(*out, buffer.data(), buffer.size());
    *out_size = buffer.size();
    return SL_OK;
}

int decode(const void *data, size_t size, sl_draco_mesh *out, sl_error *err)
{
    draco::DecoderBuffer in;
    in.Init(static_cast<const char *>(data), size);
    draco::Decoder dec;
    auto res = dec.DecodeMeshFromBuffer(&in);
    if (!res.ok())
        return sl_error_set(err, SL_E_CORRUPT, 0, nullptr, "Draco decoder: %s",
                            res.status().error_msg());
    std::unique_ptr<draco::Mesh> mesh = std::move(res).value();
    out->vertex_count = mesh->num_points();
    out->triangle_count = mesh->num_faces();
    out->triangles = static_cast<uint32_t *>(std::malloc(12 * out->triangle_count + 12));
    if (!out->triangles)
        return sl_error_set(err, SL_E_NOMEM, 0, nullptr, "Draco: out of memory");
    for (uint32_t f = 0; f < mesh->num_faces(); f++)
        for (int k = 0; k < 3; k++)
            out->triangles[3 * f + k] = mesh->face(draco::FaceIndex(f))[k].value();
    for (int a = 0; a < out->attribute_count; a++) {
        sl_draco_attribute *at = &out->attributes[a];
        const draco::PointAttribute *pa = mesh->GetAttributeByUniqueId((uint32_t)at->unique_id);
        if (pa && at->type == SL_DRACO_ANY)
            at->type = type_of(pa->data_type());
        if (pa && at->components == 0)
            at->components = pa->num_components();
        if (pa)
            at->normalized = pa->normalized();
        if (!pa || at->type == SL_DRACO_ANY || pa->data_type() != data_type(at->type) ||
            pa->num_components() != at->components || at->components < 1 || at->components > 4)
            return sl_error_set(err, SL_E_CORRUPT, 0, nullptr,
                                "Draco: attribute %d missing or of another type", at->unique_id);
        const size_t stride = (size_t)at->components * type_size(at->type);
        unsigned char *dst = static_cast<unsigned char *>(std::malloc(stride * out->vertex_count + 1));
        if (!dst)
            return sl_error_set(err, SL_E_NOMEM, 0, nullptr, "Draco: out of memory");
        at->data = dst;
        for (uint32_t p = 0; p < mesh->num_points(); p++) {
            // A stream's point -> value map is data too: checked before it is followed.
            if (pa->mapped_index(draco::PointIndex(p)).value() >= pa->size())
                return sl_error_set(err, SL_E_CORRUPT, 0, nullptr,
                                    "Draco: attribute %d maps point %u to no value",
                                    at->unique_id, p);
            pa->GetMappedValue(draco::PointIndex(p), dst + p * stride);
        }
    }
    return SL_OK;
}

} // namespace

extern "C" int sl_draco_encode(sl_draco_mesh *m, int speed, void **out, size_t *out_size,
                               sl_error *err)
{
    *out = nullptr;
    *out_size = 0;
    try {
        return encode(m, speed, out, out_size, err);
    } catch (const std::bad_alloc &) {
        return sl_error_set(err, SL_E_NOMEM, 0, nullptr, "Draco: out of memory");
    } catch (const std::exception &e) {
        return sl_error_set(err, SL_E_INTERNAL, 0, nullptr, "Draco: %s", e.what());
    } catch (...) {
        return sl_error_set(err, SL_E_INTERNAL, 0, nullptr, "Draco: unknown exception");
    }
}

extern "C" int sl_draco_decode(const void *data, size_t size, sl_draco_mesh *out, sl_error *err)
{
    out->vertex_count = out->triangle_count = 0;
    out->triangles = nullptr;
    for (int a = 0; a < out->attribute_count; a++)
        out->attributes[a].data = nullptr;
    int rc;
    try {
        rc = decode(data, size, out, err);
    } catch (const std::bad_alloc &) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, nullptr, "Draco: out of memory");
    } catch (const std::exception &e) {
        rc = sl_error_set(err, SL_E_CORRUPT, 0, nullptr, "Draco: %s", e.what());
    } catch (...) {
        rc = sl_error_set(err, SL_E_INTERNAL, 0, nullptr, "Draco: unknown exception");
    }
    if (rc)
        sl_draco_mesh_release(out);
    return rc;
}

extern "C" void sl_draco_mesh_release(sl_draco_mesh *m)
{
    std::free(m->triangles);
    m->triangles = nullptr;
    for (int a = 0; a < m->attribute_count; a++) {
        std::free(m->attributes[a].data);
        m->attributes[a].data = nullptr;
    }
}
