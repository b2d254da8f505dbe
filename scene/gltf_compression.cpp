#include "scene/gltf_compression.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <type_traits>
#include <string_view>
#include <vector>

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "scene/input_error.h"

namespace cuberille::scene {
namespace {

constexpr std::string_view kMeshopt = "EXT_meshopt_compression", kDraco = "KHR_draco_mesh_compression";

/// One compressed view's parameters (EXT_meshopt_compression, "bufferView extension").
struct MeshoptView {
    int buffer = -1;
    size_t byteOffset = 0, byteLength = 0, byteStride = 0, count = 0;
    std::string mode, filter = "NONE";
};

[[noreturn]] void fail(const std::string& file, size_t view, const std::string& problem) {
    throw InputError(file + ": buffer view " + std::to_string(view) + ", " + std::string(kMeshopt) + ": " + problem);
}

size_t unsignedField(const tinygltf::Value& ext, const char* name, bool required, const std::string& file, size_t view) {
    if (!ext.Has(name)) {
        if (required) fail(file, view, std::string("has no ") + name);
        return 0;
    }
    const tinygltf::Value& v = ext.Get(name);
    if (!v.IsNumber() || v.GetNumberAsDouble() < 0 || v.GetNumberAsDouble() != double(size_t(v.GetNumberAsDouble())))
        fail(file, view, std::string(name) + " is not a whole number of 0 or more");
    return size_t(v.GetNumberAsDouble());
}

MeshoptView readMeshoptView(const tinygltf::Value& ext, const std::string& file, size_t view) {
    MeshoptView m;
    m.buffer = int(unsignedField(ext, "buffer", true, file, view));
    m.byteOffset = unsignedField(ext, "byteOffset", false, file, view);
    m.byteLength = unsignedField(ext, "byteLength", true, file, view);
    m.byteStride = unsignedField(ext, "byteStride", true, file, view);
    m.count = unsignedField(ext, "count", true, file, view);
    if (!ext.Has("mode") || !ext.Get("mode").IsString()) fail(file, view, "has no mode");
    m.mode = ext.Get("mode").Get<std::string>();
    if (ext.Has("filter") && ext.Get("filter").IsString()) m.filter = ext.Get("filter").Get<std::string>();
    return m;
}

// The decoded bytes of one view: count elements of byteStride bytes (glTF's meshopt extension,
// "Decoding"). Strides and filters are checked as the specification states them before the
// decoder sees the data; the decoders check the data themselves (a non-zero return).
std::vector<unsigned char> decodeView(const MeshoptView& m, const unsigned char* src, const std::string& file, size_t view) {
    std::vector<unsigned char> out(m.count * m.byteStride);
    int status = 0;
    if (m.mode == "ATTRIBUTES") {
        if (m.byteStride % 4 != 0) fail(file, view, "ATTRIBUTES need a byteStride that is a multiple of 4");
        status = meshopt_decodeVertexBuffer(out.data(), m.count, m.byteStride, src, m.byteLength);
    } else if (m.mode == "TRIANGLES" || m.mode == "INDICES") {
        if (m.byteStride != 2 && m.byteStride != 4) fail(file, view, m.mode + " need a byteStride of 2 or 4");
        if (m.mode == "TRIANGLES" && m.count % 3 != 0) fail(file, view, "TRIANGLES need a count that is a multiple of 3");
        status = m.mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(out.data(), m.count, m.byteStride, src, m.byteLength)
                                       : meshopt_decodeIndexSequence(out.data(), m.count, m.byteStride, src, m.byteLength);
    } else {
        fail(file, view, "unknown mode " + m.mode);
    }
    if (status != 0) fail(file, view, "the " + m.mode + " data do not decode (meshoptimizer error " + std::to_string(status) + ")");
    if (m.filter != "NONE" && m.mode != "ATTRIBUTES") fail(file, view, "filter " + m.filter + " on " + m.mode);
    if (m.filter == "OCTAHEDRAL") {
        if (m.byteStride != 4 && m.byteStride != 8) fail(file, view, "OCTAHEDRAL needs a byteStride of 4 or 8");
        meshopt_decodeFilterOct(out.data(), m.count, m.byteStride);
    } else if (m.filter == "QUATERNION") {
        if (m.byteStride != 8) fail(file, view, "QUATERNION needs a byteStride of 8");
        meshopt_decodeFilterQuat(out.data(), m.count, m.byteStride);
    } else if (m.filter == "EXPONENTIAL") {
        meshopt_decodeFilterExp(out.data(), m.count, m.byteStride);
    } else if (m.filter != "NONE") {
        fail(file, view, "unknown filter " + m.filter);
    }
    return out;
}

bool isFallbackBuffer(const nlohmann::json& buffer) {
    if (!buffer.is_object() || buffer.contains("uri")) return false;
    const auto ext = buffer.find("extensions");
    if (ext == buffer.end() || !ext->is_object()) return false;
    const auto meshopt = ext->find(std::string(kMeshopt));
    return meshopt != ext->end() && meshopt->is_object() && meshopt->value("fallback", false) == true;
}

[[noreturn]] void failPrimitive(const std::string& file, const std::string& at, const std::string& problem) {
    throw InputError(file + ": " + at + ", KHR_draco_mesh_compression: " + problem);
}

// One stored component of Draco type `type` as the accessor's component type T. The accessor
// describes the decoded data (KHR_draco_mesh_compression), so values are cast, never normalised;
// a float out of an integer type's range (or NaN) becomes 0 rather than undefined behaviour.
template <class T>
T castComponent(draco::DataType type, const uint8_t* src) {
    auto read = [&](auto value) {
        std::memcpy(&value, src, sizeof value);
        return value;
    };
    double v = 0.0;
    switch (type) {
    case draco::DT_INT8: v = read(int8_t{}); break;
    case draco::DT_UINT8: v = read(uint8_t{}); break;
    case draco::DT_INT16: v = read(int16_t{}); break;
    case draco::DT_UINT16: v = read(uint16_t{}); break;
    case draco::DT_INT32: v = read(int32_t{}); break;
    case draco::DT_UINT32: v = read(uint32_t{}); break;
    case draco::DT_INT64: v = double(read(int64_t{})); break;
    case draco::DT_UINT64: v = double(read(uint64_t{})); break;
    case draco::DT_FLOAT32: v = read(float{}); break;
    case draco::DT_FLOAT64: v = read(double{}); break;
    case draco::DT_BOOL: v = read(uint8_t{}) != 0; break;
    default: break;
    }
    if constexpr (std::is_floating_point_v<T>) return T(v);
    else return v >= double(std::numeric_limits<T>::min()) && v <= double(std::numeric_limits<T>::max()) ? T(v) : T(0);
}

// `points` elements of `components` values of the accessor's component type from a decoded Draco
// attribute, point by point (a point's value through the attribute's own mapping: Draco stores
// each distinct value once), as little-endian bytes the accessor reads in place. The attribute's
// bytes are read here, bounds checked, not through Draco's ConvertValue: that reads the
// attribute's `normalized` flag, which a damaged stream leaves an invalid bool (UBSan, the
// fuzzer's find). Components the attribute lacks are 0. False when the data is out of range.
template <class T>
bool appendConverted(const draco::PointAttribute& attribute, size_t points, int components, std::vector<unsigned char>& out) {
    const size_t size = size_t(std::max(draco::DataTypeLength(attribute.data_type()), 0));
    const draco::DataBuffer* buffer = attribute.buffer();
    const int stored = std::min(int(attribute.num_components()), components);
    if (size == 0 || !buffer || attribute.byte_stride() < 0 || attribute.byte_offset() < 0) return false;
    if (!attribute.is_mapping_identity() && attribute.indices_map_size() < points) return false;
    for (size_t p = 0; p < points; ++p) {
        const uint64_t index = attribute.mapped_index(draco::PointIndex(uint32_t(p))).value();
        const uint64_t at = uint64_t(attribute.byte_offset()) + uint64_t(attribute.byte_stride()) * index;
        if (index > (uint64_t(1) << 32) || at + uint64_t(stored) * size > buffer->data_size()) return false;
        for (int c = 0; c < components; ++c) {
            const T value = c < stored ? castComponent<T>(attribute.data_type(), buffer->data() + at + size_t(c) * size) : T(0);
            const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
            out.insert(out.end(), bytes, bytes + sizeof(T));
        }
    }
    return true;
}

// A new buffer and a view over all of it: where decoded data lives.
int appendBufferView(tinygltf::Model& model, std::vector<unsigned char> bytes) {
    tinygltf::Buffer buffer;
    buffer.data = std::move(bytes);
    tinygltf::BufferView view;
    view.buffer = int(model.buffers.size());
    view.byteLength = buffer.data.size();
    model.buffers.push_back(std::move(buffer));
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size() - 1);
}

// The accessor `index` made to read `bytes` (count elements, tightly packed), in place of the
// accessor's missing or fallback data.
void pointAccessorAt(tinygltf::Model& model, int index, size_t count, std::vector<unsigned char> bytes) {
    tinygltf::Accessor& a = model.accessors[size_t(index)];
    a.bufferView = appendBufferView(model, std::move(bytes));
    a.byteOffset = 0;
    a.count = count;
    a.sparse.isSparse = false;
}

void decodeDracoPrimitive(tinygltf::Model& model, tinygltf::Primitive& primitive, const tinygltf::Value& ext, const std::string& file,
                          const std::string& at) {
    if (!ext.Has("bufferView") || !ext.Get("bufferView").IsInt()) failPrimitive(file, at, "has no bufferView");
    const int viewIndex = ext.Get("bufferView").Get<int>();
    if (viewIndex < 0 || size_t(viewIndex) >= model.bufferViews.size()) failPrimitive(file, at, "buffer view " + std::to_string(viewIndex) + " does not exist");
    const tinygltf::BufferView& bv = model.bufferViews[size_t(viewIndex)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size()) failPrimitive(file, at, "its buffer view has no valid buffer");
    const std::vector<unsigned char>& source = model.buffers[size_t(bv.buffer)].data;
    if (bv.byteOffset > source.size() || bv.byteLength > source.size() - bv.byteOffset)
        failPrimitive(file, at, "buffer view " + std::to_string(viewIndex) + " runs past the end of its buffer");
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(source.data() + bv.byteOffset), bv.byteLength);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok()) failPrimitive(file, at, "the mesh does not decode (" + decoded.status().error_msg_string() + ")");
    const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
    const size_t points = mesh->num_points(), faces = mesh->num_faces();
    if (points > (size_t(1) << 32) - 1) failPrimitive(file, at, "too many points");

    // Triangles: the primitive's index accessor, in its own component type where the points fit.
    if (primitive.indices < 0) {
        tinygltf::Accessor indices;
        indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        indices.type = TINYGLTF_TYPE_SCALAR;
        model.accessors.push_back(indices);
        primitive.indices = int(model.accessors.size() - 1);
    }
    if (size_t(primitive.indices) >= model.accessors.size()) failPrimitive(file, at, "its index accessor does not exist");
    const int indexType = model.accessors[size_t(primitive.indices)].componentType;
    const size_t indexBytes = indexType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ? 1 : indexType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2 : 4;
    if (indexBytes < 4 && points > (size_t(1) << (8 * indexBytes)))
        failPrimitive(file, at, std::to_string(points) + " points do not fit its " + std::to_string(8 * indexBytes) + "-bit indices");
    std::vector<unsigned char> indexData(faces * 3 * indexBytes);
    for (size_t f = 0; f < faces; ++f)
        for (int c = 0; c < 3; ++c) {
            const uint32_t point = mesh->face(draco::FaceIndex(uint32_t(f)))[c].value();
            std::memcpy(&indexData[(f * 3 + size_t(c)) * indexBytes], &point, indexBytes);  // little-endian: the low bytes
        }
    model.accessors[size_t(primitive.indices)].componentType = indexBytes == 4 ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT : indexType;
    pointAccessorAt(model, primitive.indices, faces * 3, std::move(indexData));

    // Attributes: each glTF attribute the extension names, by Draco's unique id.
    if (!ext.Has("attributes") || !ext.Get("attributes").IsObject()) failPrimitive(file, at, "has no attributes");
    const tinygltf::Value& attributes = ext.Get("attributes");
    for (const std::string& name : attributes.Keys()) {
        const auto accessor = primitive.attributes.find(name);
        if (accessor == primitive.attributes.end()) continue;  // the primitive does not use it
        if (accessor->second < 0 || size_t(accessor->second) >= model.accessors.size())
            failPrimitive(file, at, name + "'s accessor does not exist");
        const tinygltf::Value& id = attributes.Get(name);
        const draco::PointAttribute* attribute = id.IsInt() ? mesh->GetAttributeByUniqueId(uint32_t(id.Get<int>())) : nullptr;
        if (!attribute) failPrimitive(file, at, name + ": no Draco attribute with that id");
        const tinygltf::Accessor& a = model.accessors[size_t(accessor->second)];
        const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (components <= 0 || components > 4) failPrimitive(file, at, name + "'s accessor has an invalid type");
        std::vector<unsigned char> bytes;
        bool read = false;
        switch (a.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: read = appendConverted<float>(*attribute, points, components, bytes); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: read = appendConverted<uint8_t>(*attribute, points, components, bytes); break;
        case TINYGLTF_COMPONENT_TYPE_BYTE: read = appendConverted<int8_t>(*attribute, points, components, bytes); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: read = appendConverted<uint16_t>(*attribute, points, components, bytes); break;
        case TINYGLTF_COMPONENT_TYPE_SHORT: read = appendConverted<int16_t>(*attribute, points, components, bytes); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: read = appendConverted<uint32_t>(*attribute, points, components, bytes); break;
        default: failPrimitive(file, at, name + "'s accessor has an invalid component type");
        }
        if (!read) failPrimitive(file, at, name + ": the decoded attribute's values are out of range");
        pointAccessorAt(model, accessor->second, points, std::move(bytes));
    }
}

}  // namespace

void decodeDracoPrimitives(tinygltf::Model& model, const std::string& file) {
    for (size_t m = 0; m < model.meshes.size(); ++m)
        for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
            tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
            const auto ext = primitive.extensions.find(std::string(kDraco));
            if (ext != primitive.extensions.end())
                decodeDracoPrimitive(model, primitive, ext->second, file, "mesh " + std::to_string(m) + ", primitive " + std::to_string(p));
        }
}

bool mentionsCompression(const std::string& json) {
    return json.find(kMeshopt) != std::string::npos || json.find(kDraco) != std::string::npos;
}

std::string parseableByTinygltf(const std::string& json) {
    nlohmann::json doc = nlohmann::json::parse(json, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return json;  // tinygltf reports the error with its place
    bool changed = false;
    if (auto buffers = doc.find("buffers"); buffers != doc.end() && buffers->is_array())
        for (nlohmann::json& buffer : *buffers)
            if (isFallbackBuffer(buffer)) {
                buffer["uri"] = "data:application/octet-stream;base64,AAAAAA==";  // tinygltf refuses an empty one
                buffer["byteLength"] = 4;
                changed = true;
            }
    auto meshes = doc.find("meshes");
    auto accessors = doc.find("accessors");
    if (meshes == doc.end() || !meshes->is_array() || accessors == doc.end() || !accessors->is_array()) return changed ? doc.dump() : json;
    for (nlohmann::json& mesh : *meshes) {
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
        for (nlohmann::json& primitive : mesh["primitives"]) {
            if (!primitive.is_object()) continue;
            const nlohmann::json* draco = nullptr;
            if (auto ext = primitive.find("extensions"); ext != primitive.end() && ext->is_object())
                if (auto d = ext->find(std::string(kDraco)); d != ext->end() && d->is_object()) draco = &*d;
            const auto indices = primitive.find("indices");
            if (!draco || indices == primitive.end() || !indices->is_number_unsigned() || !draco->contains("bufferView")) continue;
            const size_t index = indices->get<size_t>();
            if (index < accessors->size() && (*accessors)[index].is_object() && !(*accessors)[index].contains("bufferView")) {
                (*accessors)[index]["bufferView"] = (*draco)["bufferView"];
                changed = true;
            }
        }
    }
    return changed ? doc.dump() : json;
}

bool hasJsonChunk(const std::string& glb) {
    if (glb.size() < 20 || glb.compare(16, 4, "JSON") != 0) return false;
    uint32_t total = 0, length = 0;
    std::memcpy(&total, glb.data() + 8, 4);
    std::memcpy(&length, glb.data() + 12, 4);
    return total <= glb.size() && total >= 20 && length <= total - 20;
}

std::string glbJson(const std::string& glb) {
    uint32_t length = 0;
    std::memcpy(&length, glb.data() + 12, 4);
    return glb.substr(20, length);
}

std::string glbWithJson(const std::string& glb, const std::string& json) {
    uint32_t oldLength = 0, total = 0;
    std::memcpy(&oldLength, glb.data() + 12, 4);
    std::memcpy(&total, glb.data() + 8, 4);
    std::string padded = json;
    padded.resize((padded.size() + 3) / 4 * 4, ' ');  // chunks are 4-byte aligned, JSON padded with spaces
    const std::string rest = glb.substr(20 + size_t(oldLength), total - 20 - size_t(oldLength));
    std::string out = glb.substr(0, 12);
    const uint32_t jsonLength = uint32_t(padded.size()), newTotal = uint32_t(12 + 8 + padded.size() + rest.size());
    std::memcpy(out.data() + 8, &newTotal, 4);
    out.append(reinterpret_cast<const char*>(&jsonLength), 4);
    out.append(glb, 16, 4);  // the chunk type, "JSON"
    return out + padded + rest;
}

void decodeMeshoptBufferViews(tinygltf::Model& model, const std::string& file) {
    for (size_t v = 0; v < model.bufferViews.size(); ++v) {
        tinygltf::BufferView& bv = model.bufferViews[v];
        const auto ext = bv.extensions.find(std::string(kMeshopt));
        if (ext == bv.extensions.end()) continue;
        const MeshoptView m = readMeshoptView(ext->second, file, v);
        if (m.buffer < 0 || size_t(m.buffer) >= model.buffers.size()) fail(file, v, "buffer " + std::to_string(m.buffer) + " does not exist");
        const std::vector<unsigned char>& source = model.buffers[size_t(m.buffer)].data;
        if (m.byteOffset > source.size() || m.byteLength > source.size() - m.byteOffset)
            fail(file, v, "bytes " + std::to_string(m.byteOffset) + "+" + std::to_string(m.byteLength) + " run past buffer " +
                              std::to_string(m.buffer) + "'s " + std::to_string(source.size()));
        if (m.count > (size_t(1) << 32) || m.byteStride == 0 || m.byteStride > 256)
            fail(file, v, "count " + std::to_string(m.count) + " or byteStride " + std::to_string(m.byteStride) + " out of range");
        if (m.count * m.byteStride != bv.byteLength)
            fail(file, v, "decodes to " + std::to_string(m.count * m.byteStride) + " bytes, but the view's byteLength is " +
                              std::to_string(bv.byteLength));
        std::vector<unsigned char> decoded = decodeView(m, source.data() + m.byteOffset, file, v);
        tinygltf::Buffer buffer;
        buffer.data = std::move(decoded);
        model.buffers.push_back(std::move(buffer));
        bv.buffer = int(model.buffers.size() - 1);
        bv.byteOffset = 0;
        if (bv.byteStride == 0 && m.mode == "ATTRIBUTES") bv.byteStride = m.byteStride;
    }
}

}  // namespace cuberille::scene
