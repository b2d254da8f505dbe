#include "scene/gltf_compression.h"

#include <cstring>
#include <string_view>
#include <vector>

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "scene/input_error.h"

namespace cuberille::scene {
namespace {

constexpr std::string_view kMeshopt = "EXT_meshopt_compression";

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

}  // namespace

bool mentionsMeshoptCompression(const std::string& json) { return json.find(kMeshopt) != std::string::npos; }

std::string withLoadableFallbackBuffers(const std::string& json) {
    nlohmann::json doc = nlohmann::json::parse(json, nullptr, false);
    if (doc.is_discarded()) return json;  // tinygltf reports the parse error with its place
    auto buffers = doc.find("buffers");
    if (buffers == doc.end() || !buffers->is_array()) return json;
    bool changed = false;
    for (nlohmann::json& buffer : *buffers)
        if (isFallbackBuffer(buffer)) {
            buffer["uri"] = "data:application/octet-stream;base64,AAAAAA==";  // tinygltf refuses an empty one
            buffer["byteLength"] = 4;
            changed = true;
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
