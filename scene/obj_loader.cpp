#include "scene/obj_loader.h"

#include <charconv>
#include <cmath>
#include <map>

#include "scene/input_error.h"
#include "scene/text_parsing.h"
#include "scene/ply_loader.h"

namespace cuberille::scene {
namespace {

[[noreturn]] void fail(const std::string& file, size_t line, const std::string& problem) {
    throw InputError(file + ":" + std::to_string(line) + ": " + problem);
}

float number(std::string_view w, const std::string& file, size_t line) {
    float v = 0;
    const char* first = w.data() + (!w.empty() && w[0] == '+');
    auto [end, ec] = std::from_chars(first, w.data() + w.size(), v);
    if (ec != std::errc() || end != w.data() + w.size() || !std::isfinite(v))
        fail(file, line, "'" + std::string(w) + "' is not a finite number");
    return v;
}

// A 1-based (or negative, from the end) OBJ index to a 0-based one.
uint32_t resolveIndex(std::string_view w, size_t count, const char* what, const std::string& file,
                      size_t line) {
    long long i = 0;
    auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), i);
    if (ec != std::errc() || end != w.data() + w.size() || i == 0)
        fail(file, line, std::string("'") + std::string(w) + "' is not a valid " + what + " index");
    const long long resolved = i > 0 ? i - 1 : static_cast<long long>(count) + i;
    if (resolved < 0 || resolved >= static_cast<long long>(count))
        fail(file, line, std::string(what) + " index " + std::to_string(i) + " is out of range (" +
                             std::to_string(count) + " defined so far)");
    return uint32_t(resolved);
}

std::map<std::string, glm::vec3> parseMtl(const std::filesystem::path& path, const WarningSink& warn) {
    std::map<std::string, glm::vec3> colors;
    std::string text;
    try {
        text = readFileBytes(path);
    } catch (const InputError& e) {
        warn(std::string(e.what()) + " (materials fall back to the default colour)");
        return colors;
    }
    std::string current;
    size_t lineNumber = 0, pos = 0;
    while (pos <= text.size()) {
        size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        ++lineNumber;
        auto w = splitWords(std::string_view(text).substr(pos, end - pos));
        pos = end + 1;
        if (w.size() >= 2 && w[0] == "newmtl") current = std::string(w[1]);
        if (w.size() >= 4 && w[0] == "Kd" && !current.empty()) {
            try {
                const std::string name = path.string();
                colors[current] = glm::vec3(srgbToLinear(number(w[1], name, lineNumber)),
                                            srgbToLinear(number(w[2], name, lineNumber)),
                                            srgbToLinear(number(w[3], name, lineNumber)));
            } catch (const InputError& e) {
                warn(std::string(e.what()) + " (material '" + current + "' keeps the default colour)");
            }
        }
        if (end == text.size()) break;
    }
    return colors;
}

/// One material's mesh, its vertices made as faces first use each (position, normal) pair.
struct MeshBuilder {
    Mesh mesh;
    bool needsComputedNormals = false;

    /// The mesh vertex of OBJ position p with normal n (UINT32_MAX: none), made on first use.
    /// A chain per position instead of a hash map of pairs: a position almost always has one
    /// normal, so the lookup is one array read (a hash map was a quarter of the bunny's parse).
    uint32_t vertexFor(uint32_t p, uint32_t n, const std::vector<glm::vec3>& positions,
                       const std::vector<glm::vec3>& positionColors, const std::vector<glm::vec3>& normals) {
        if (p >= firstVertexOf_.size()) firstVertexOf_.resize(positions.size(), kNone);
        for (uint32_t v = firstVertexOf_[p]; v != kNone; v = nextWithPosition_[v])
            if (normalOf_[v] == n) return v;
        const uint32_t v = uint32_t(mesh.positions.size());
        mesh.positions.push_back(positions[p]);
        mesh.normals.push_back(n == kNone ? glm::vec3(0.0f) : normals[n]);
        mesh.colors.push_back(positionColors[p]);
        normalOf_.push_back(n);
        nextWithPosition_.push_back(firstVertexOf_[p]);
        firstVertexOf_[p] = v;
        return v;
    }

private:
    static constexpr uint32_t kNone = UINT32_MAX;
    std::vector<uint32_t> firstVertexOf_;     // per OBJ position: its latest mesh vertex, or kNone
    std::vector<uint32_t> nextWithPosition_;  // per mesh vertex: the previous one of its position
    std::vector<uint32_t> normalOf_;          // per mesh vertex: its OBJ normal, or kNone
};

}  // namespace

std::vector<Mesh> parseObj(const std::string& text, const std::string& file,
                           const std::filesystem::path& directory, const WarningSink& warn) {
    std::vector<glm::vec3> positions, positionColors, normals;
    std::map<std::string, glm::vec3> materials;
    std::vector<MeshBuilder> builders(1);
    std::map<std::string, size_t> builderOf;  // material → builder, in order of first use
    size_t current = 0;
    bool anyColors = false;

    size_t lineNumber = 0, pos = 0;
    std::vector<uint32_t> polygon;
    std::vector<std::string_view> w;
    while (pos <= text.size()) {
        size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        ++lineNumber;
        std::string_view line = std::string_view(text).substr(pos, end - pos);
        pos = end + 1;
        if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
        splitWords(line, w);
        if (w.empty()) {
            if (end == text.size()) break;
            continue;
        }
        if (w[0] == "v") {
            if (w.size() != 4 && w.size() != 7) fail(file, lineNumber, "a vertex needs x y z (and optionally r g b)");
            positions.emplace_back(number(w[1], file, lineNumber), number(w[2], file, lineNumber),
                                   number(w[3], file, lineNumber));
            positionColors.push_back(w.size() == 7 ? glm::vec3(number(w[4], file, lineNumber),
                                                               number(w[5], file, lineNumber),
                                                               number(w[6], file, lineNumber))
                                                   : glm::vec3(1.0f));
            anyColors = anyColors || w.size() == 7;
        } else if (w[0] == "vn") {
            if (w.size() != 4) fail(file, lineNumber, "a normal needs x y z");
            normals.emplace_back(number(w[1], file, lineNumber), number(w[2], file, lineNumber),
                                 number(w[3], file, lineNumber));
        } else if (w[0] == "f") {
            if (w.size() < 4) fail(file, lineNumber, "a face needs at least three vertices");
            MeshBuilder& b = builders[current];
            polygon.clear();
            for (size_t k = 1; k < w.size(); ++k) {
                const std::string_view spec = w[k];
                const size_t slash1 = spec.find('/');
                const uint32_t p = resolveIndex(spec.substr(0, slash1), positions.size(), "vertex", file, lineNumber);
                uint32_t n = UINT32_MAX;
                if (slash1 != std::string_view::npos) {
                    const size_t slash2 = spec.find('/', slash1 + 1);
                    if (slash2 != std::string_view::npos && slash2 + 1 < spec.size())
                        n = resolveIndex(spec.substr(slash2 + 1), normals.size(), "normal", file, lineNumber);
                }
                if (n == UINT32_MAX) b.needsComputedNormals = true;
                polygon.push_back(b.vertexFor(p, n, positions, positionColors, normals));
            }
            for (size_t k = 2; k < polygon.size(); ++k)
                b.mesh.indices.insert(b.mesh.indices.end(), {polygon[0], polygon[k - 1], polygon[k]});
        } else if (w[0] == "usemtl") {
            const std::string name = w.size() > 1 ? std::string(w[1]) : "";
            auto [it, inserted] = builderOf.try_emplace(name, builders.size());
            if (inserted) {
                builders.emplace_back();
                const auto m = materials.find(name);
                builders.back().mesh.color = m != materials.end() ? m->second : glm::vec3(0.8f);
            }
            current = it->second;
        } else if (w[0] == "mtllib") {
            for (size_t k = 1; k < w.size(); ++k) {
                auto loaded = parseMtl(directory / std::string(w[k]), warn);
                materials.insert(loaded.begin(), loaded.end());
            }
        }
        if (end == text.size()) break;
    }

    std::vector<Mesh> meshes;
    for (MeshBuilder& b : builders) {
        if (b.mesh.indices.empty()) continue;
        if (b.needsComputedNormals) computeVertexNormals(b.mesh);
        if (!anyColors) b.mesh.colors.clear();
        meshes.push_back(std::move(b.mesh));
    }
    if (meshes.empty()) throw InputError(file + ": no triangles (no face lines)");
    return meshes;
}

std::vector<Mesh> loadObj(const std::filesystem::path& path, const WarningSink& warn) {
    return parseObj(readFileBytes(path), path.string(), path.parent_path(), warn);
}

}  // namespace cuberille::scene
