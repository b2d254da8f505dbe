// Compressed glTF geometry (scene/gltf_compression.h): EXT_meshopt_compression and
// KHR_draco_mesh_compression in files the tests make with meshoptimizer's and Draco's encoders, and
// in files gltfpack and draco_transcoder make from the models in ../shared/data.

#include <gtest/gtest.h>

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <meshoptimizer.h>

#include <dlfcn.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>

#include "apps/image_error.h"
#include "apps/render_command.h"
#include "scene/gltf_loader.h"
#include "scene/input_error.h"
#include "tests/scene/gltf_builder.h"
#include "tests/temp_paths.h"

namespace cuberille::scene {
namespace {

namespace fs = std::filesystem;

// A wavy grid: positions, unit normals and texture coordinates, and its triangles.
struct Grid {
    std::vector<float> positions, normals4, uvs;  // normals as 4 floats each (the octahedral filter's input)
    std::vector<uint32_t> indices;
    size_t vertices = 0;
};

Grid wavyGrid(int side) {
    Grid g;
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
            const float u = float(x) / float(side - 1), v = float(y) / float(side - 1);
            const float h = 0.2f * std::sin(6.0f * u) * std::cos(5.0f * v);
            g.positions.insert(g.positions.end(), {u * 4.0f - 2.0f, h, v * 4.0f - 2.0f});
            const float dx = 0.2f * 6.0f * std::cos(6.0f * u) * std::cos(5.0f * v) / 4.0f,
                        dz = -0.2f * 5.0f * std::sin(6.0f * u) * std::sin(5.0f * v) / 4.0f;
            const float len = std::sqrt(dx * dx + 1.0f + dz * dz);
            g.normals4.insert(g.normals4.end(), {-dx / len, 1.0f / len, -dz / len, 0.0f});
            g.uvs.insert(g.uvs.end(), {u, v});
        }
    for (int y = 0; y + 1 < side; ++y)
        for (int x = 0; x + 1 < side; ++x) {
            const uint32_t a = uint32_t(y * side + x), b = a + 1, c = a + uint32_t(side), d = c + 1;
            g.indices.insert(g.indices.end(), {a, c, b, b, c, d});
        }
    g.vertices = size_t(side) * side;
    return g;
}

// What a view's decoder gives back: the twin file stores these bytes plainly, the compressed one
// stores the encoded stream, so both must load to the same mesh.
struct Encoded {
    std::vector<unsigned char> plain, compressed;
    size_t stride = 0, count = 0;
    std::string mode, filter = "NONE";
};

Encoded vertexStream(const void* data, size_t count, size_t stride, const std::string& filter) {
    Encoded e;
    e.plain.assign(static_cast<const unsigned char*>(data), static_cast<const unsigned char*>(data) + count * stride);
    e.compressed.resize(meshopt_encodeVertexBufferBound(count, stride));
    e.compressed.resize(meshopt_encodeVertexBuffer(e.compressed.data(), e.compressed.size(), data, count, stride));
    e.stride = stride, e.count = count, e.mode = "ATTRIBUTES", e.filter = filter;
    return e;
}

// A float stream through one of meshoptimizer's filters (its encoder and decoder), then the vertex
// codec: the plain twin holds what the filter decodes to.
using FilterEncoder = void (*)(void*, size_t, size_t, int, const float*);
using FilterDecoder = void (*)(void*, size_t, size_t);
Encoded filteredStream(const std::vector<float>& data, size_t count, size_t stride, int bits, FilterEncoder encode,
                       FilterDecoder decode, const std::string& filter) {
    std::vector<unsigned char> encoded(count * stride);
    encode(encoded.data(), count, stride, bits, data.data());
    Encoded e = vertexStream(encoded.data(), count, stride, filter);
    decode(e.plain.data(), count, stride);
    return e;
}

// Positions through the exponential filter (15-bit mantissas), normals through the octahedral one
// (8-bit).
Encoded filteredPositions(const Grid& g) {
    return filteredStream(g.positions, g.vertices, 12, 15, meshopt_encodeFilterExp, meshopt_decodeFilterExp, "EXPONENTIAL");
}

Encoded filteredNormals(const Grid& g) {
    return filteredStream(g.normals4, g.vertices, 4, 8, meshopt_encodeFilterOct, meshopt_decodeFilterOct, "OCTAHEDRAL");
}

Encoded indexStream(const std::vector<uint32_t>& indices, bool triangles) {
    Encoded e;
    std::vector<uint16_t> narrow(indices.begin(), indices.end());
    e.plain.assign(reinterpret_cast<const unsigned char*>(narrow.data()), reinterpret_cast<const unsigned char*>(narrow.data()) + narrow.size() * 2);
    const size_t vertices = *std::max_element(indices.begin(), indices.end()) + 1;
    e.compressed.resize(triangles ? meshopt_encodeIndexBufferBound(indices.size(), vertices)
                                  : meshopt_encodeIndexSequenceBound(indices.size(), vertices));
    e.compressed.resize(triangles ? meshopt_encodeIndexBuffer(e.compressed.data(), e.compressed.size(), indices.data(), indices.size())
                                  : meshopt_encodeIndexSequence(e.compressed.data(), e.compressed.size(), indices.data(), indices.size()));
    e.stride = 2, e.count = indices.size(), e.mode = triangles ? "TRIANGLES" : "INDICES";
    return e;
}

// Builds the grid twice over: `compressed` puts every stream in an EXT_meshopt_compression view
// whose parent view reads a fallback buffer without data (buffer 1), as gltfpack writes them.
// Two primitives: one indexed through a TRIANGLES stream, one through an INDICES stream.
class MeshoptFile {
public:
    MeshoptFile(const Grid& g, bool compressed) : compressed_(compressed) {
        const int position = accessor(filteredPositions(g), 5126, false, "VEC3");
        const int normal = accessor(filteredNormals(g), 5120, true, "VEC3");
        const int uv = accessor(vertexStream(g.uvs.data(), g.vertices, 8, "NONE"), 5126, false, "VEC2");
        const size_t half = g.indices.size() / 2;
        const std::vector<uint32_t> first(g.indices.begin(), g.indices.begin() + long(half)), second(g.indices.begin() + long(half), g.indices.end());
        const int triangles = accessor(indexStream(first, true), 5123, false, "SCALAR");
        const int sequence = accessor(indexStream(second, false), 5123, false, "SCALAR");
        nlohmann::json& pos = b_.json()["accessors"][size_t(position)];
        pos["min"] = {-2, -1, -2}, pos["max"] = {2, 1, 2};
        const nlohmann::json attributes = {{"POSITION", position}, {"NORMAL", normal}, {"TEXCOORD_0", uv}};
        b_.push("nodes", {{"mesh", b_.push("meshes", {{"primitives", {{{"attributes", attributes}, {"indices", triangles}},
                                                                       {{"attributes", attributes}, {"indices", sequence}}}}})}});
        b_.json()["scenes"] = {{{"nodes", {0}}}};
        b_.json()["scene"] = 0;
        if (compressed) b_.json()["extensionsUsed"] = b_.json()["extensionsRequired"] = {"EXT_meshopt_compression"};
    }

    nlohmann::json& json() { return b_.json(); }

    fs::path writeGltf(const std::string& name) {
        const fs::path path = testing::uniqueTempPath(name + ".gltf");
        b_.write(path);
        if (!compressed_) return path;
        nlohmann::json j = nlohmann::json::parse(std::ifstream(path));
        j["buffers"].push_back(fallbackBuffer());
        std::ofstream(path) << j.dump();
        return path;
    }

    // The same as a GLB: buffer 0 is the BIN chunk, the fallback buffer has no data at all.
    fs::path writeGlb(const std::string& name) {
        nlohmann::json j = b_.json();
        const std::string& bin = b_.bytes();
        j["buffers"] = {{{"byteLength", bin.size()}}};
        if (compressed_) j["buffers"].push_back(fallbackBuffer());
        std::string text = j.dump();
        text.resize((text.size() + 3) / 4 * 4, ' ');
        std::string binChunk = bin;
        binChunk.resize((binChunk.size() + 3) / 4 * 4, '\0');
        auto u32 = [](std::string& out, uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
        std::string glb = "glTF";
        u32(glb, 2);
        u32(glb, uint32_t(12 + 8 + text.size() + 8 + binChunk.size()));
        u32(glb, uint32_t(text.size()));
        glb += "JSON" + text;
        u32(glb, uint32_t(binChunk.size()));
        glb += std::string("BIN\0", 4) + binChunk;
        const fs::path path = testing::uniqueTempPath(name + ".glb");
        std::ofstream(path, std::ios::binary) << glb;
        return path;
    }

private:
    nlohmann::json fallbackBuffer() const {
        return {{"byteLength", fallbackBytes_}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}};
    }

    int accessor(const Encoded& e, int componentType, bool normalized, const char* type) {
        int view = 0;
        if (!compressed_) {
            view = b_.view(e.plain.data(), e.plain.size());
        } else {
            view = b_.view(e.compressed.data(), e.compressed.size());
            nlohmann::json& v = b_.json()["bufferViews"][size_t(view)];
            const nlohmann::json stream = {{"buffer", 0},        {"byteOffset", v["byteOffset"]}, {"byteLength", v["byteLength"]},
                                           {"byteStride", e.stride}, {"count", e.count},           {"mode", e.mode},
                                           {"filter", e.filter}};
            v = {{"buffer", 1}, {"byteOffset", fallbackBytes_}, {"byteLength", e.plain.size()},
                 {"extensions", {{"EXT_meshopt_compression", stream}}}};
            fallbackBytes_ += (e.plain.size() + 3) / 4 * 4;
        }
        if (e.mode == "ATTRIBUTES") b_.json()["bufferViews"][size_t(view)]["byteStride"] = e.stride;
        return b_.push("accessors", {{"bufferView", view}, {"componentType", componentType}, {"normalized", normalized},
                                     {"count", e.count}, {"type", type}});
    }

    testing::GltfBuilder b_;
    bool compressed_;
    size_t fallbackBytes_ = 0;
};

void expectSameMeshes(const GltfScene& a, const GltfScene& b, const std::string& what) {
    ASSERT_EQ(a.meshes.size(), b.meshes.size()) << what;
    for (size_t m = 0; m < a.meshes.size(); ++m) {
        EXPECT_EQ(a.meshes[m].positions, b.meshes[m].positions) << what << ", mesh " << m;
        EXPECT_EQ(a.meshes[m].normals, b.meshes[m].normals) << what << ", mesh " << m;
        EXPECT_EQ(a.meshes[m].texCoords, b.meshes[m].texCoords) << what << ", mesh " << m;
        EXPECT_EQ(a.meshes[m].indices, b.meshes[m].indices) << what << ", mesh " << m;
    }
}

const WarningSink kQuiet = [](const std::string&) {};

TEST(MeshoptCompression, EveryModeAndFilterLoadsAsItsUncompressedTwin) {
    const Grid g = wavyGrid(23);
    MeshoptFile plain(g, false), compressed(g, true);
    const GltfScene reference = loadGltf(plain.writeGltf("meshopt-plain"), kQuiet);
    ASSERT_EQ(reference.meshes.size(), 2u);
    EXPECT_EQ(reference.meshes[0].indices.size() + reference.meshes[1].indices.size(), g.indices.size());
    std::vector<std::string> warnings;
    const WarningSink collect = [&](const std::string& w) { warnings.push_back(w); };
    expectSameMeshes(loadGltf(compressed.writeGltf("meshopt"), collect), reference, ".gltf");
    expectSameMeshes(loadGltf(compressed.writeGlb("meshopt"), collect), reference, ".glb");
    expectSameMeshes(loadGltf(plain.writeGlb("meshopt-plain"), kQuiet), reference, "plain .glb");
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    // The filters ran: the octahedral normals are unit length to 8-bit precision, which the
    // encoded bytes (x and y, then z = 127) are not.
    for (const glm::vec3& n : reference.meshes[0].normals) ASSERT_NEAR(glm::length(n), 1.0f, 0.02f);
}

// A file whose compressed data is damaged or whose parameters are wrong is bad input naming the
// file, the view and the problem, never a crash.
// Standard base64 back to bytes (the test files' data URIs).
std::string base64Decode(const std::string& in) {
    std::string out;
    uint32_t bits = 0;
    int count = 0;
    for (const char ch : in) {
        const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        const char* at = std::strchr(k, ch);
        if (ch == '=' || !at || !*at) break;
        bits = (bits << 6) | uint32_t(at - k);
        if ((count += 6) >= 8) out += char((bits >> (count -= 8)) & 0xff);
    }
    return out;
}

// A file edited into a bad one, and what its refusal must say.
struct BadFileCase {
    const char* what;
    std::function<void(nlohmann::json&)> edit;
    std::string expected;
};

// Loading `path` is an InputError that starts with the file and says `expected`.
void expectRefused(const fs::path& path, const BadFileCase& c) {
    try {
        loadGltf(path, kQuiet);
        ADD_FAILURE() << c.what << ": loaded";
    } catch (const InputError& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << c.what << ": " << message;
        EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
    }
}

TEST(MeshoptCompression, DamagedStreamsAreInputErrorsNamingTheView) {
    const Grid g = wavyGrid(9);
    const std::vector<BadFileCase> cases = {
        {"a short stream", [](nlohmann::json& j) { j["bufferViews"][3]["extensions"]["EXT_meshopt_compression"]["byteLength"] = 5; },
         "buffer view 3, EXT_meshopt_compression: the TRIANGLES data do not decode"},
        {"an unknown mode", [](nlohmann::json& j) { j["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["mode"] = "POINTS"; },
         "buffer view 0, EXT_meshopt_compression: unknown mode POINTS"},
        {"an unknown filter", [](nlohmann::json& j) { j["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["filter"] = "WAVELET"; },
         "buffer view 2, EXT_meshopt_compression: unknown filter WAVELET"},
        {"a stream past its buffer",
         [](nlohmann::json& j) { j["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["byteOffset"] = 1u << 30; },
         "buffer view 1, EXT_meshopt_compression: bytes 1073741824+"},
        {"a count that does not fill the view",
         [](nlohmann::json& j) { j["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["count"] = 80; },
         "buffer view 2, EXT_meshopt_compression: decodes to 640 bytes, but the view's byteLength is 648"},
        {"an odd attribute stride",
         [](nlohmann::json& j) {
             nlohmann::json& stream = j["bufferViews"][2]["extensions"]["EXT_meshopt_compression"];
             stream["byteStride"] = 6, stream["count"] = 108;  // still the view's 648 bytes
         },
         "ATTRIBUTES need a byteStride that is a multiple of 4"},
        {"a view reading the fallback buffer itself", [](nlohmann::json& j) { j["bufferViews"][0].erase("extensions"); },
         "its buffer view runs past the end of buffer 1"},
    };
    for (const BadFileCase& c : cases) {
        MeshoptFile file(g, true);
        c.edit(file.json());
        expectRefused(file.writeGltf("meshopt-damaged"), c);
    }
}

// The JSON is adjusted before tinygltf checks the container, so a GLB whose header or first chunk
// does not hold together must reach tinygltf's refusal untouched (the fuzzer's first finds).
TEST(MeshoptCompression, GlbsWhoseChunksDoNotFitAreRefusedBeforeAnyAdjustment) {
    auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
    const std::string json = R"({"asset":{"version":"2.0"},"extensionsUsed":["EXT_meshopt_compression"]})";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"a header length of 12", "glTF" + u32(2) + u32(12) + u32(1024) + "JSON" + json},
        {"a JSON chunk past the header's length", "glTF" + u32(2) + u32(uint32_t(20 + json.size())) + u32(1024) + "JSON" + json},
        {"a first chunk that is not JSON", "glTF" + u32(2) + u32(uint32_t(20 + json.size())) + u32(uint32_t(json.size())) + "BIN" +
                                               std::string(1, '\0') + json},
    };
    for (const auto& [what, bytes] : cases) {
        const fs::path path = testing::uniqueTempPath("bad-container.glb");
        std::ofstream(path, std::ios::binary) << bytes;
        try {
            loadGltf(path, kQuiet);
            ADD_FAILURE() << what << ": loaded";
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << what << ": " << e.what();
        }
    }
}

// A Draco-compressed grid as exporters write it: accessors with a count and a type but no buffer
// view, the primitive's extension naming its compressed view and each attribute's Draco id. The
// encoder runs without quantization (lossless) unless `positionBits` > 0.
fs::path writeDracoGrid(const Grid& g, const std::string& name, int positionBits, const std::function<void(nlohmann::json&)>& edit = {}) {
    draco::TriangleSoupMeshBuilder builder;
    const int faces = int(g.indices.size() / 3);
    builder.Start(faces);
    const int position = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
    const int normal = builder.AddAttribute(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32);
    const int uv = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
    for (int f = 0; f < faces; ++f) {
        const uint32_t* v = &g.indices[size_t(f) * 3];
        auto set = [&](int attribute, const std::vector<float>& data, size_t stride) {
            builder.SetAttributeValuesForFace(attribute, draco::FaceIndex(f), &data[v[0] * stride], &data[v[1] * stride], &data[v[2] * stride]);
        };
        set(position, g.positions, 3);
        set(normal, g.normals4, 4);  // the first three of each four
        set(uv, g.uvs, 2);
    }
    const std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
    draco::Encoder encoder;
    if (positionBits > 0) encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, positionBits);
    draco::EncoderBuffer encoded;
    EXPECT_TRUE(encoder.EncodeMeshToBuffer(*mesh, &encoded).ok());
    testing::GltfBuilder b;
    const int view = b.view(encoded.data(), encoded.size());
    auto accessor = [&](int componentType, const char* type) {
        return b.push("accessors", {{"componentType", componentType}, {"count", g.vertices}, {"type", type}});
    };
    const nlohmann::json attributes = {{"POSITION", accessor(5126, "VEC3")}, {"NORMAL", accessor(5126, "VEC3")}, {"TEXCOORD_0", accessor(5126, "VEC2")}};
    b.json()["accessors"][0]["min"] = {-2, -1, -2}, b.json()["accessors"][0]["max"] = {2, 1, 2};
    const int indices = b.push("accessors", {{"componentType", 5125}, {"count", g.indices.size()}, {"type", "SCALAR"}});
    const nlohmann::json draco = {{"bufferView", view},
                                  {"attributes", {{"POSITION", mesh->attribute(position)->unique_id()},
                                                  {"NORMAL", mesh->attribute(normal)->unique_id()},
                                                  {"TEXCOORD_0", mesh->attribute(uv)->unique_id()}}}};
    b.push("nodes", {{"mesh", b.push("meshes", {{"primitives", {{{"attributes", attributes}, {"indices", indices},
                                                                  {"extensions", {{"KHR_draco_mesh_compression", draco}}}}}}})}});
    b.json()["scenes"] = {{{"nodes", {0}}}};
    b.json()["scene"] = 0;
    b.json()["extensionsUsed"] = b.json()["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    if (edit) edit(b.json());
    const fs::path path = testing::uniqueTempPath(name + ".gltf");
    b.write(path);
    return path;
}

// A mesh's triangles as corners (position, normal; texture coordinates are read only for a textured
// material), each triangle rotated to
// start at its smallest corner, sorted: the same surface compares equal whatever order the
// vertices and triangles are in (Draco's connectivity coder reorders both).
std::vector<std::array<float, 18>> triangleSet(const Mesh& m) {
    std::vector<std::array<float, 18>> out;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
        std::array<std::array<float, 6>, 3> corners;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.indices[t + size_t(k)];
            corners[size_t(k)] = {m.positions[v].x, m.positions[v].y, m.positions[v].z, m.normals[v].x, m.normals[v].y, m.normals[v].z};
        }
        const size_t first = size_t(std::min_element(corners.begin(), corners.end()) - corners.begin());
        std::array<float, 18> triangle;
        for (size_t k = 0; k < 3; ++k) std::copy(corners[(first + k) % 3].begin(), corners[(first + k) % 3].end(), triangle.begin() + long(k * 6));
        out.push_back(triangle);
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST(DracoCompression, ALosslessMeshDecodesToTheSameTrianglesAsItsSource) {
    const Grid g = wavyGrid(17);
    const GltfScene draco = loadGltf(writeDracoGrid(g, "draco", 0), kQuiet);
    ASSERT_EQ(draco.meshes.size(), 1u);
    ASSERT_EQ(draco.meshes[0].indices.size(), g.indices.size());
    ASSERT_EQ(draco.meshes[0].normals.size(), draco.meshes[0].positions.size());
    // The reference: the same grid in a plain file, through the same loader (which transforms and
    // renormalises normals).
    testing::GltfBuilder b;
    std::vector<float> normals;
    for (size_t v = 0; v < g.vertices; ++v) normals.insert(normals.end(), {g.normals4[v * 4], g.normals4[v * 4 + 1], g.normals4[v * 4 + 2]});
    const int position = b.floats(g.positions, 3, true), normal = b.floats(normals, 3);
    const std::vector<uint16_t> narrow(g.indices.begin(), g.indices.end());
    b.push("nodes", {{"mesh", b.push("meshes", {{"primitives", {{{"attributes", {{"POSITION", position}, {"NORMAL", normal}}},
                                                                  {"indices", b.indices(narrow)}}}}})}});
    b.json()["scenes"] = {{{"nodes", {0}}}};
    b.json()["scene"] = 0;
    const fs::path plainPath = testing::uniqueTempPath("draco-plain.gltf");
    b.write(plainPath);
    const GltfScene plain = loadGltf(plainPath, kQuiet);
    ASSERT_EQ(plain.meshes.size(), 1u);
    const Mesh& source = plain.meshes[0];
    EXPECT_TRUE(triangleSet(draco.meshes[0]) == triangleSet(source)) << "the decoded triangles differ from the source's";
    // Quantized positions (11 bits, draco_transcoder's default) land within half a step of the
    // source's: the grid spans 4 units, a step is 4 / 2047.
    const GltfScene quantized = loadGltf(writeDracoGrid(g, "draco-quantized", 11), kQuiet);
    ASSERT_EQ(quantized.meshes.size(), 1u);
    ASSERT_EQ(quantized.meshes[0].indices.size(), g.indices.size());
    float farthest = 0.0f;
    for (const glm::vec3& p : quantized.meshes[0].positions) {
        float nearest = 1e30f;
        for (const glm::vec3& q : source.positions) nearest = std::min(nearest, glm::length(p - q));
        farthest = std::max(farthest, nearest);
    }
    EXPECT_LE(farthest, 0.5f * 4.0f / 2047.0f * std::sqrt(3.0f));
}

TEST(DracoCompression, BadStreamsAndAccessorsAreInputErrorsNamingThePrimitive) {
    const Grid g = wavyGrid(9);
    const std::vector<BadFileCase> cases = {
        {"a cut stream", [](nlohmann::json& j) { j["bufferViews"][0]["byteLength"] = 40; },
         "mesh 0, primitive 0, KHR_draco_mesh_compression: the mesh does not decode"},
        {"an attribute id Draco does not have",
         [](nlohmann::json& j) { j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["attributes"]["NORMAL"] = 7; },
         "NORMAL: no Draco attribute with that id"},
        {"8-bit indices for 81 points (they fit)", [](nlohmann::json& j) { j["accessors"][3]["componentType"] = 5121; }, ""},
        {"a view that does not exist",
         [](nlohmann::json& j) { j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"] = 9; },
         "accessor[3] invalid bufferView"},  // tinygltf's words: the index accessor borrows the view (parseableByTinygltf)
    };
    for (const BadFileCase& c : cases) {
        const fs::path path = writeDracoGrid(g, "draco-bad", 0, c.edit);
        if (c.expected.empty())  // 81 points fit 8-bit indices: it loads
            EXPECT_EQ(loadGltf(path, kQuiet).meshes.size(), 1u) << c.what;
        else
            expectRefused(path, c);
    }
    // Points past what the index accessor's type holds: 17 x 17 = 289 points, 8-bit indices.
    const BadFileCase narrow = {"289 points in 8-bit indices", [](nlohmann::json& j) { j["accessors"][3]["componentType"] = 5121; },
                                "289 points do not fit its 8-bit indices"};
    expectRefused(writeDracoGrid(wavyGrid(17), "draco-narrow", 0, narrow.edit), narrow);
}

// Every byte of a Draco stream replaced by each of a few values: the file loads or is refused
// with an input error, never undefined behaviour (under the sanitizer build: Draco leaves a
// damaged stream's `normalized` flag an invalid bool, which the fuzzer found through Draco's own
// value conversion; the reader converts values itself).
TEST(DracoCompression, EveryCorruptedByteOfAStreamLoadsOrIsRefused) {
    const fs::path path = writeDracoGrid(wavyGrid(4), "draco-corrupt", 0);
    nlohmann::json j = nlohmann::json::parse(std::ifstream(path));
    const std::string uri = j["buffers"][0]["uri"];
    std::string stream = base64Decode(uri.substr(uri.find(',') + 1));
    const size_t streamBytes = j["bufferViews"][0]["byteLength"];
    int loaded = 0, refused = 0;
    for (size_t i = 0; i < streamBytes; ++i)
        for (const uint8_t value : {0x00, 0x65, 0xff}) {
            std::string damaged = stream;
            damaged[i] = char(value);
            j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + testing::base64(damaged);
            std::ofstream(path) << j.dump();
            try {
                loadGltf(path, kQuiet);
                ++loaded;
            } catch (const InputError&) {
                ++refused;
            }
        }
    EXPECT_GT(refused, 0);
    EXPECT_EQ(loaded + refused, int(streamBytes) * 3);
}

// Debian's libdraco exports its own copy of tinygltf; linked in the wrong order, the loader's
// tinygltf calls bind to it, and files the two versions parse differently crash the loader
// (CMakeLists.txt orders draco after tinygltf). The symbol the process resolves must be libtinygltf's.
TEST(DracoCompression, TinygltfCallsBindToDebiansTinygltfNotDracosCopy) {
    const char* symbol =
        "_ZN8tinygltf8TinyGLTF14LoadFromStringEPNS_5ModelEPNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEES9_PKcjRKS8_j";
    void* address = dlsym(RTLD_DEFAULT, symbol);
    ASSERT_NE(address, nullptr) << symbol;
    Dl_info info{};
    ASSERT_NE(dladdr(address, &info), 0);
    EXPECT_NE(std::string(info.dli_fname).find("libtinygltf"), std::string::npos) << "bound in " << info.dli_fname;
}

// gltfpack and draco_transcoder (Debian's, installed by .ci/install-deps) compress sample models as
// exporters do: quantized attributes, meshopt streams with filters, Draco's connectivity coding,
// reordered vertices and triangles. The compressed model renders like the original: 40 dB or more
// (the quantization moves vertices by up to 2^-11 (Draco) or 2^-14 (gltfpack) of the model's size;
// measured 44-53 dB at 160x120).
TEST(CompressedGltf, SampleModelsRenderLikeTheirOriginals) {
    const fs::path data = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "gltf";
    if (!fs::exists(data)) GTEST_SKIP() << data << " is absent; real-data checks skipped";
    if (std::system("command -v gltfpack > /dev/null 2>&1 && command -v draco_transcoder > /dev/null 2>&1") != 0)
        GTEST_SKIP() << "gltfpack or draco_transcoder is not installed (.ci/install-deps installs both)";
    auto render = [](const fs::path& file) {
        apps::RenderOptions o;
        o.scene = file.string();
        o.width = 160;
        o.height = 120;
        o.quiet = true;
        return apps::renderScene(o).image;
    };
    for (const char* model : {"DamagedHelmet/DamagedHelmet.glb", "BrainStem/BrainStem.glb"}) {
        const fs::path original = data / model;
        const raster::Image reference = render(original);
        for (const std::string tool : {"gltfpack -c", "gltfpack -cc", "draco_transcoder"}) {
            const fs::path packed = testing::uniqueTempPath("compressed.glb");
            const std::string command = tool + " -i '" + original.string() + "' -o '" + packed.string() + "' > /dev/null 2>&1";
            ASSERT_EQ(std::system(command.c_str()), 0) << command;
            const double psnr = apps::compareImages(render(packed), reference).psnrDb;
            EXPECT_GE(psnr, 40.0) << model << " through " << tool;
            std::printf("%s through %s: %.1f dB\n", model, tool.c_str(), psnr);
            fs::remove(packed);
        }
    }
}

}  // namespace
}  // namespace cuberille::scene
