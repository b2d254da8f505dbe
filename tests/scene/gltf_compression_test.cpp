// EXT_meshopt_compression (scene/gltf_compression.h): files the tests make with meshoptimizer's
// encoders, and files gltfpack makes from the models in ../shared/data.

#include <gtest/gtest.h>

#include <meshoptimizer.h>

#include <cmath>
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

// Positions through the exponential filter (15-bit mantissas) and normals through the octahedral
// one (8-bit): the plain twin holds what the filters decode to.
Encoded filteredPositions(const Grid& g) {
    std::vector<unsigned char> encoded(g.vertices * 12);
    meshopt_encodeFilterExp(encoded.data(), g.vertices, 12, 15, g.positions.data());
    Encoded e = vertexStream(encoded.data(), g.vertices, 12, "EXPONENTIAL");
    meshopt_decodeFilterExp(e.plain.data(), g.vertices, 12);
    return e;
}

Encoded filteredNormals(const Grid& g) {
    std::vector<unsigned char> encoded(g.vertices * 4);
    meshopt_encodeFilterOct(encoded.data(), g.vertices, 4, 8, g.normals4.data());
    Encoded e = vertexStream(encoded.data(), g.vertices, 4, "OCTAHEDRAL");
    meshopt_decodeFilterOct(e.plain.data(), g.vertices, 4);
    return e;
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
TEST(MeshoptCompression, DamagedStreamsAreInputErrorsNamingTheView) {
    const Grid g = wavyGrid(9);
    struct Case {
        const char* what;
        std::function<void(nlohmann::json&)> damage;
        std::string expected;
    };
    const std::vector<Case> cases = {
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
    for (const Case& c : cases) {
        MeshoptFile file(g, true);
        c.damage(file.json());
        const fs::path path = file.writeGltf("meshopt-damaged");
        try {
            loadGltf(path, kQuiet);
            ADD_FAILURE() << c.what << ": loaded";
        } catch (const InputError& e) {
            const std::string message = e.what();
            EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << c.what << ": " << message;
            EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
        }
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

// gltfpack (Debian's, installed by .ci/install-deps) compresses sample models as exporters do:
// quantized attributes (KHR_mesh_quantization), meshopt streams with filters, reordered
// vertices and triangles. The compressed model renders like the original: 40 dB or more (the
// quantization moves vertices by up to 2^-14 of the model's size; measured 50-56 dB).
TEST(MeshoptCompression, GltfpackModelsRenderLikeTheirOriginals) {
    const fs::path data = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "gltf";
    if (!fs::exists(data)) GTEST_SKIP() << data << " is absent; real-data checks skipped";
    if (std::system("command -v gltfpack > /dev/null 2>&1") != 0)
        GTEST_SKIP() << "gltfpack is not installed (.ci/install-deps installs it)";
    for (const char* model : {"DamagedHelmet/DamagedHelmet.glb", "BrainStem/BrainStem.glb"}) {
        for (const char* flags : {"-c", "-cc"}) {
            const fs::path original = data / model;
            const fs::path packed = testing::uniqueTempPath(std::string("gltfpack") + flags + ".glb");
            const std::string command = "gltfpack -i '" + original.string() + "' -o '" + packed.string() + "' " + flags + " > /dev/null 2>&1";
            ASSERT_EQ(std::system(command.c_str()), 0) << command;
            auto render = [](const fs::path& file) {
                apps::RenderOptions o;
                o.scene = file.string();
                o.width = 160;
                o.height = 120;
                o.quiet = true;
                return apps::renderScene(o).image;
            };
            const apps::ImageError error = apps::compareImages(render(packed), render(original));
            EXPECT_GE(error.psnrDb, 40.0) << model << " " << flags;
            fs::remove(packed);
        }
    }
}

}  // namespace
}  // namespace cuberille::scene
