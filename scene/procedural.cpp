#include "scene/procedural.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cuberille::scene {
namespace {

constexpr float kPi = 3.14159265358979f;

// Indices of a (rows x columns) vertex grid as two triangles per cell, counter-clockwise when
// the grid's u runs right and v runs up as seen from the front.
void gridIndices(int rows, int columns, bool wrapColumns, std::vector<uint32_t>& out) {
    const int cellsX = wrapColumns ? columns : columns - 1;
    for (int r = 0; r + 1 < rows; ++r)
        for (int c = 0; c < cellsX; ++c) {
            const uint32_t a = r * columns + c, b = r * columns + (c + 1) % columns;
            const uint32_t d = (r + 1) * columns + c, e = (r + 1) * columns + (c + 1) % columns;
            out.insert(out.end(), {a, b, d, b, e, d});
        }
}

Scene makeField(float detail) {
    Scene s;
    s.name = "field";
    const int rings = std::max(4, int(48 * std::sqrt(detail)));
    const int segments = std::max(6, int(72 * std::sqrt(detail)));
    const glm::vec3 palette[] = {{0.8f, 0.25f, 0.2f}, {0.25f, 0.55f, 0.85f}, {0.9f, 0.75f, 0.2f},
                                 {0.3f, 0.7f, 0.35f}, {0.7f, 0.4f, 0.8f}};
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) {
            const glm::vec3 centre((i - 5.5f) * 2.2f, 0.9f, (j - 5.5f) * 2.2f);
            Mesh m = (i + j) % 2 ? makeSphere(centre, 0.9f, rings, segments)
                                 : makeTorus(centre, 0.7f, 0.25f, segments, rings);
            m.color = palette[(i * 12 + j) % 5];
            s.meshes.push_back(std::move(m));
        }
    Mesh ground = makeGround(16.0f, 0.0f);
    ground.color = glm::vec3(0.6f);
    s.meshes.push_back(std::move(ground));
    s.camera.position = {14.0f, 11.0f, 19.0f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.verticalFovDegrees = 50.0f;
    s.camera.nearPlane = 0.5f;
    s.camera.farPlane = 100.0f;
    s.lighting = raster::Lighting::directional(glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f)), glm::vec3(0.9f),
                                               glm::vec3(0.12f, 0.13f, 0.16f));
    s.background = {0.05f, 0.06f, 0.08f, 1.0f};
    return s;
}

// A cut-out made in code: opaque discs on a transparent ground, for alpha MASK.
std::shared_ptr<const raster::Texture> discTexture(int size, int discs) {
    std::vector<glm::vec4> texels(size_t(size) * size);
    const float cell = float(size) / discs;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float dx = std::fmod(x + 0.5f, cell) - cell / 2, dy = std::fmod(y + 0.5f, cell) - cell / 2;
            const bool inside = dx * dx + dy * dy < 0.16f * cell * cell;
            texels[size_t(y) * size + x] = glm::vec4(0.95f, 0.85f, 0.3f, inside ? 1.0f : 0.0f);
        }
    return std::make_shared<raster::Texture>(size, size, std::move(texels));
}

// The default scene (`make demo`): everything the renderer does, and no file needed. A
// checkerboard ground (a texture generated here, mip-mapped and filtered), spheres sweeping
// metallic and roughness, tori, a glass-like sphere blended over them, a cut-out screen (alpha
// MASK, double-sided), a sun and a warm point light.
Scene makeDemo(float detail) {
    Scene s;
    s.name = "demo";
    const int rings = std::max(6, int(40 * std::sqrt(detail)));
    const int segments = std::max(8, int(64 * std::sqrt(detail)));
    Mesh ground = makeGround(12.0f, 0.0f);
    for (const glm::vec3& p : ground.positions) ground.texCoords.emplace_back(p.x / 4.0f, p.z / 4.0f);
    ground.textures.baseColor.texture = checkerTexture(256, 8, glm::vec3(0.6f), glm::vec3(0.15f, 0.18f, 0.22f));
    ground.metallicRoughness = true;
    ground.metallic = 0.0f;
    ground.roughness = 0.7f;
    ground.color = glm::vec3(1.0f);
    s.meshes.push_back(std::move(ground));
    const glm::vec3 gold(1.0f, 0.71f, 0.29f), red(0.8f, 0.15f, 0.1f);
    for (int i = 0; i < 5; ++i) {
        const float angle = 2.0f * kPi * i / 5.0f;
        Mesh ball = makeSphere(glm::vec3(5.0f * std::cos(angle), 1.0f, 5.0f * std::sin(angle)), 1.0f, rings, segments);
        ball.metallicRoughness = true;
        ball.color = i % 2 ? gold : red;
        ball.metallic = i % 2 ? 1.0f : 0.0f;
        ball.roughness = 0.15f + 0.2f * i;
        s.meshes.push_back(std::move(ball));
        Mesh ring = makeTorus(glm::vec3(5.0f * std::cos(angle + 0.63f), 0.35f, 5.0f * std::sin(angle + 0.63f)), 0.6f,
                              0.3f, segments, rings);
        ring.color = glm::vec3(0.2f, 0.5f + 0.1f * i, 0.8f);  // Lambert
        s.meshes.push_back(std::move(ring));
    }
    Mesh glass = makeSphere(glm::vec3(0.0f, 2.0f, 0.0f), 2.0f, rings, segments);
    glass.metallicRoughness = true;
    glass.color = glm::vec3(0.25f, 0.55f, 1.0f);
    glass.metallic = 0.0f;
    glass.roughness = 0.05f;
    glass.alpha = 0.45f;
    glass.alphaMode = raster::AlphaMode::Blend;
    s.meshes.push_back(std::move(glass));
    Mesh screen;
    screen.positions = {{-3.0f, 0.0f, -7.0f}, {3.0f, 0.0f, -7.0f}, {3.0f, 4.0f, -7.0f}, {-3.0f, 4.0f, -7.0f}};
    screen.normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
    screen.texCoords = {{0.0f, 1.0f}, {1.5f, 1.0f}, {1.5f, 0.0f}, {0.0f, 0.0f}};
    screen.indices = {0, 1, 2, 0, 2, 3};
    screen.textures.baseColor.texture = discTexture(128, 4);
    screen.color = glm::vec3(1.0f);
    screen.alphaMode = raster::AlphaMode::Mask;
    screen.doubleSided = true;
    s.meshes.push_back(std::move(screen));
    s.camera.position = {9.0f, 6.5f, 11.0f};
    s.camera.target = {0.0f, 1.2f, 0.0f};
    s.camera.verticalFovDegrees = 50.0f;
    s.camera.nearPlane = 0.5f;
    s.camera.farPlane = 100.0f;
    s.lighting = raster::Lighting::directional(glm::normalize(glm::vec3(0.5f, 1.0f, 0.2f)), glm::vec3(1.4f),
                                               glm::vec3(0.1f, 0.11f, 0.14f));
    raster::Light& lamp = s.lighting.lights[s.lighting.lightCount++];
    lamp.type = raster::LightType::Point;
    lamp.position = {-4.0f, 3.0f, 4.0f};
    lamp.intensity = glm::vec3(12.0f, 7.0f, 3.0f);
    lamp.range = 20.0f;
    s.background = {0.05f, 0.06f, 0.08f, 1.0f};
    return s;
}

// A rolling terrain of about 10M triangles: a (n x n) height field seen from above at an angle.
Scene makeSubpixel(float detail) {
    Scene s;
    s.name = "subpixel";
    const int n = std::max(8, int(2237 * std::sqrt(detail)));  // 2 (n-1)^2 ≈ 10M triangles
    Mesh m;
    m.positions.reserve(size_t(n) * n);
    m.normals.reserve(size_t(n) * n);
    auto height = [](float x, float z) {
        return 0.35f * std::sin(1.7f * x) * std::cos(1.3f * z) + 0.15f * std::sin(4.1f * x + 2.3f * z);
    };
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            const float x = -5.0f + 10.0f * c / (n - 1), z = 5.0f - 10.0f * r / (n - 1);
            const float e = 1e-3f;
            const float dx = (height(x + e, z) - height(x - e, z)) / (2 * e);
            const float dz = (height(x, z + e) - height(x, z - e)) / (2 * e);
            m.positions.emplace_back(x, height(x, z), z);
            m.normals.push_back(glm::normalize(glm::vec3(-dx, 1.0f, -dz)));
        }
    gridIndices(n, n, false, m.indices);
    m.color = glm::vec3(0.55f, 0.7f, 0.45f);
    s.meshes.push_back(std::move(m));
    s.camera.position = {0.0f, 6.5f, 6.0f};
    s.camera.target = {0.0f, 0.0f, 0.3f};
    s.camera.verticalFovDegrees = 60.0f;
    s.camera.nearPlane = 0.5f;
    s.camera.farPlane = 50.0f;
    s.lighting = raster::Lighting::directional(glm::normalize(glm::vec3(-0.5f, 1.0f, 0.2f)), glm::vec3(0.95f),
                                               glm::vec3(0.1f));
    return s;
}

// A few hundred large, overlapping, depth-tested triangles: a fill-rate test.
Scene makeFill(float detail) {
    Scene s;
    s.name = "fill";
    const int count = std::max(4, int(300 * detail));
    uint32_t state = 12345u;  // LCG: deterministic everywhere, no library dependency
    auto next = [&]() {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    Mesh m;
    for (int i = 0; i < count; ++i) {
        const glm::vec3 c(next() * 8.0f - 4.0f, next() * 5.0f - 2.5f, -next() * 6.0f);
        const float size = 3.0f + next() * 4.0f;
        glm::vec3 p[3];
        for (int k = 0; k < 3; ++k) {
            const float a = 2.0f * kPi * (k / 3.0f + next() * 0.2f);
            p[k] = c + size * glm::vec3(std::cos(a), std::sin(a), 0.3f * (next() - 0.5f));
        }
        const glm::vec3 normal = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
        for (int k = 0; k < 3; ++k) {
            m.indices.push_back(uint32_t(m.positions.size()));
            m.positions.push_back(p[k]);
            m.normals.push_back(normal);
        }
    }
    m.color = glm::vec3(0.8f, 0.6f, 0.4f);
    s.meshes.push_back(std::move(m));
    s.camera.position = {0.0f, 0.0f, 6.0f};
    s.camera.target = {0.0f, 0.0f, -2.0f};
    s.camera.verticalFovDegrees = 60.0f;
    s.lighting = raster::Lighting::directional(glm::normalize(glm::vec3(0.2f, 0.3f, 1.0f)), glm::vec3(1.0f),
                                               glm::vec3(0.15f));
    return s;
}

}  // namespace

std::shared_ptr<const raster::Texture> checkerTexture(int size, int cells, glm::vec3 a, glm::vec3 b) {
    std::vector<glm::vec4> texels(size_t(size) * size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            texels[size_t(y) * size + x] = glm::vec4(((x * cells / size) + (y * cells / size)) % 2 ? a : b, 1.0f);
    return std::make_shared<raster::Texture>(size, size, std::move(texels));
}

Mesh makeSphere(glm::vec3 centre, float radius, int rings, int segments) {
    Mesh m;
    for (int r = 0; r <= rings; ++r) {
        const float theta = kPi * r / rings;  // from the south pole (v up)
        for (int c = 0; c < segments; ++c) {
            const float phi = 2.0f * kPi * c / segments;
            const glm::vec3 n(-std::sin(theta) * std::cos(phi), -std::cos(theta),
                              std::sin(theta) * std::sin(phi));
            m.normals.push_back(n);
            m.positions.push_back(centre + radius * n);
        }
    }
    gridIndices(rings + 1, segments, true, m.indices);
    return m;
}

Mesh makeTorus(glm::vec3 centre, float majorRadius, float minorRadius, int rings, int segments) {
    Mesh m;
    for (int r = 0; r <= rings; ++r) {
        const float u = 2.0f * kPi * r / rings;
        for (int c = 0; c < segments; ++c) {
            const float v = -2.0f * kPi * c / segments;  // keeps the grid counter-clockwise from outside
            const glm::vec3 ring(std::cos(u), 0.0f, -std::sin(u));
            const glm::vec3 n = std::cos(v) * ring + glm::vec3(0.0f, std::sin(v), 0.0f);
            m.normals.push_back(n);
            m.positions.push_back(centre + majorRadius * ring + minorRadius * n);
        }
    }
    gridIndices(rings + 1, segments, true, m.indices);
    return m;
}

Mesh makeGround(float halfExtent, float height) {
    Mesh m;
    m.positions = {{-halfExtent, height, halfExtent}, {halfExtent, height, halfExtent},
                   {halfExtent, height, -halfExtent}, {-halfExtent, height, -halfExtent}};
    m.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

const std::vector<std::string>& proceduralSceneNames() {
    static const std::vector<std::string> names = {"demo", "field", "subpixel", "fill"};
    return names;
}

bool isProceduralScene(const std::string& name) {
    const auto& n = proceduralSceneNames();
    return std::find(n.begin(), n.end(), name) != n.end();
}

Scene makeProceduralScene(const std::string& name, float detail) {
    if (name == "demo") return makeDemo(detail);
    if (name == "field") return makeField(detail);
    if (name == "subpixel") return makeSubpixel(detail);
    if (name == "fill") return makeFill(detail);
    throw std::invalid_argument("unknown built-in scene '" + name + "'");
}

}  // namespace cuberille::scene
