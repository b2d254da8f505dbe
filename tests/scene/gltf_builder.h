#pragma once
// Writes small glTF 2.0 files for tests: accessors over one base64-embedded buffer, the JSON
// built with nlohmann::json, so a test states its scene (nodes, meshes, materials, skins,
// morph targets, cameras, lights) and nothing else.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace cuberille::testing {

/// Standard base64 with padding, for `data:` URIs.
inline std::string base64(const std::string& in) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        uint32_t v = uint8_t(in[i]) << 16;
        if (i + 1 < in.size()) v |= uint8_t(in[i + 1]) << 8;
        if (i + 2 < in.size()) v |= uint8_t(in[i + 2]);
        out += k[v >> 18];
        out += k[(v >> 12) & 63];
        out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
        out += i + 2 < in.size() ? k[v & 63] : '=';
    }
    return out;
}

class GltfBuilder {
public:
    GltfBuilder() {
        json_["asset"] = {{"version", "2.0"}};
        for (const char* key : {"nodes", "meshes", "materials", "accessors", "bufferViews", "textures", "images",
                                "samplers", "cameras", "skins"})
            json_[key] = nlohmann::json::array();
    }

    nlohmann::json& json() { return json_; }

    /// A float accessor of VEC2/VEC3/VEC4 (or SCALAR) from tightly packed floats; POSITION
    /// accessors get the min and max the specification requires.
    int floats(const std::vector<float>& data, int components, bool withBounds = false) {
        static const char* types[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
        nlohmann::json a = {{"bufferView", view(data.data(), data.size() * 4)},
                            {"componentType", 5126},
                            {"count", data.size() / components},
                            {"type", types[components]}};
        if (withBounds) {
            std::vector<float> lo(components, 1e30f), hi(components, -1e30f);
            for (size_t i = 0; i < data.size(); ++i) {
                lo[i % components] = std::min(lo[i % components], data[i]);
                hi[i % components] = std::max(hi[i % components], data[i]);
            }
            a["min"] = lo;
            a["max"] = hi;
        }
        return push("accessors", a);
    }
    int positions(const std::vector<glm::vec3>& p) { return floats(flatten(p), 3, true); }
    int vec3s(const std::vector<glm::vec3>& v) { return floats(flatten(v), 3); }
    int vec2s(const std::vector<glm::vec2>& v) { return floats(flatten(v), 2); }
    int vec4s(const std::vector<glm::vec4>& v) { return floats(flatten(v), 4); }
    int mat4s(const std::vector<glm::mat4>& m) {
        std::vector<float> f;
        for (const glm::mat4& x : m)
            for (int c = 0; c < 4; ++c)
                for (int r = 0; r < 4; ++r) f.push_back(x[c][r]);  // column-major, as glTF
        nlohmann::json a = {{"bufferView", view(f.data(), f.size() * 4)}, {"componentType", 5126},
                            {"count", m.size()}, {"type", "MAT4"}};
        return push("accessors", a);
    }
    int indices(const std::vector<uint16_t>& i) {
        return push("accessors", {{"bufferView", view(i.data(), i.size() * 2)}, {"componentType", 5123},
                                  {"count", i.size()}, {"type", "SCALAR"}});
    }
    int joints(const std::vector<glm::u8vec4>& j) {
        return push("accessors", {{"bufferView", view(j.data(), j.size() * 4)}, {"componentType", 5121},
                                  {"count", j.size()}, {"type", "VEC4"}});
    }

    int push(const char* array, nlohmann::json value) {
        json_[array].push_back(std::move(value));
        return int(json_[array].size()) - 1;
    }

    void write(const std::filesystem::path& path) {
        json_["buffers"] = {{{"byteLength", bytes_.size()},
                             {"uri", "data:application/octet-stream;base64," + base64(bytes_)}}};
        std::ofstream(path) << json_.dump(1);
    }

    /// The buffer's bytes so far (what write() embeds), for files packed otherwise (GLB).
    const std::string& bytes() const { return bytes_; }

    /// Raw bytes as a buffer view (4-byte aligned), for accessors the helpers above do not make.
    int view(const void* data, size_t size) {
        while (bytes_.size() % 4) bytes_.push_back('\0');
        const size_t offset = bytes_.size();
        bytes_.append(static_cast<const char*>(data), size);
        return push("bufferViews", {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}});
    }

private:
    template <class T>
    static std::vector<float> flatten(const std::vector<T>& v) {
        std::vector<float> f(v.size() * T::length());
        std::memcpy(f.data(), v.data(), f.size() * 4);
        return f;
    }

    nlohmann::json json_;
    std::string bytes_;
};

// An animated glTF made in code: a floor, a cube sliding along x under the scene's light, and a
// row of cubes far to the side that the camera never sees.
inline void writeSlidingCubeGltf(const std::filesystem::path& path) {
    GltfBuilder b;
    std::vector<glm::vec3> cube;
    for (int c = 0; c < 8; ++c) cube.push_back({(c & 1) ? 0.5f : -0.5f, (c & 2) ? 0.5f : -0.5f, (c & 4) ? 0.5f : -0.5f});
    const std::vector<uint16_t> cubeIndices = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                               2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
    const int cubeMesh = b.push("meshes", {{"primitives", {{{"attributes", {{"POSITION", b.positions(cube)}}},
                                                            {"indices", b.indices(cubeIndices)}}}}});
    const int floorMesh = b.push(
        "meshes", {{"primitives", {{{"attributes", {{"POSITION", b.positions({{-6, 0, -6}, {6, 0, -6}, {6, 0, 6}, {-6, 0, 6}})}}},
                                    {"indices", b.indices({0, 2, 1, 0, 3, 2})}}}}});
    std::vector<int> roots = {b.push("nodes", {{"mesh", floorMesh}}), b.push("nodes", {{"mesh", cubeMesh}, {"translation", {-2, 1, 0}}})};
    for (int i = 0; i < 20; ++i) roots.push_back(b.push("nodes", {{"mesh", cubeMesh}, {"translation", {40 + 3 * i, 1, 0}}}));
    const int camera = b.push("cameras", {{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}, {"zfar", 100}}}});
    roots.push_back(b.push("nodes", {{"camera", camera}, {"translation", {0, 4, 10}}, {"rotation", {-0.1305262f, 0, 0, 0.9914449f}}}));
    const int times = b.floats({0.0f, 1.0f}, 1, true);
    const int moves = b.vec3s({{-2, 1, 0}, {2, 1, 0}});
    b.push("animations", {{"samplers", {{{"input", times}, {"output", moves}}}},
                          {"channels", {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}}}}});
    b.json()["scenes"] = {{{"nodes", roots}}};
    b.json()["scene"] = 0;
    b.write(path);
}

}  // namespace cuberille::testing
