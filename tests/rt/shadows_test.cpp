// The shadow modes against the ray-traced reference on scenes made in code: hybrid equals it
// except where the method's documented limits apply (counted and bounded), the map differs from
// it only where the hybrid method marks pixels (or right beside them), and every mode is
// deterministic across thread counts.

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/parallel.h"
#include "rt/bvh_build.h"
#include "rt/screen_surfaces.h"
#include "rt/shadows.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

void addBox(OwnedMesh& m, glm::vec3 lo, glm::vec3 hi) {
    const uint32_t b = uint32_t(m.positions.size());
    for (int c = 0; c < 8; ++c) m.positions.push_back({(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
    const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) m.indices.insert(m.indices.end(), {b + f[0], b + f[1], b + f[2], b + f[0], b + f[2], b + f[3]});
}

void append(OwnedMesh& m, const OwnedMesh& other) {
    const uint32_t b = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), other.positions.begin(), other.positions.end());
    for (uint32_t i : other.indices) m.indices.push_back(b + i);
}

/// A ground plane with a floating box, a thin pole and a sphere: hard edges, a thin caster and a
/// curved receiver and caster.
OwnedMesh testScene() {
    OwnedMesh m;
    addBox(m, {-4.0f, -0.1f, -4.0f}, {4.0f, 0.0f, 4.0f});  // the ground
    addBox(m, {-1.5f, 1.0f, -0.5f}, {-0.5f, 1.6f, 0.5f});  // a floating box
    addBox(m, {1.0f, 0.0f, -1.0f}, {1.03f, 2.0f, -0.97f});  // a thin pole
    append(m, testing::uvSphere(24, 48, glm::vec3(0.8f, 0.6f, 1.2f), 0.5f));
    return m;
}

struct Rendered {
    ShadowMasks masks;
    ScreenSurfaces surfaces;
};

Rendered shadowsOf(const OwnedMesh& scene, const raster::Lighting& lighting, const ShadowOptions& options, int width = 320,
                   int height = 240) {
    const TriangleMeshView mesh = scene.view();
    const Bvh bvh = buildBvh(mesh);
    const glm::mat4 clipFromWorld = glm::perspectiveRH_ZO(glm::radians(50.0f), float(width) / float(height), 0.1f, 50.0f) *
                                    glm::lookAtRH(glm::vec3(3.0f, 4.0f, 6.0f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0));
    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::None};
    Rendered r;
    r.surfaces = findScreenSurfaces(mesh, std::span(&all, 1), clipFromWorld, width, height);
    r.masks = computeShadows(r.surfaces, lighting, {mesh, &bvh, meshBounds(mesh)}, options);
    return r;
}

raster::Lighting sun() { return raster::Lighting::directional(glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f)), glm::vec3(1.0f), glm::vec3(0.1f)); }

TEST(Shadows, HybridEqualsRayTracedExceptAtCountedLimits) {
    const OwnedMesh scene = testScene();
    for (const int mapSize : {256, 1024}) {
        ShadowOptions options;
        options.mapSizeTexels = mapSize;
        options.mode = ShadowMode::RayTraced;
        const Rendered reference = shadowsOf(scene, sun(), options);
        options.mode = ShadowMode::Hybrid;
        const Rendered hybrid = shadowsOf(scene, sun(), options);
        const std::vector<float>& a = reference.masks.visibility[0];
        const std::vector<float>& b = hybrid.masks.visibility[0];
        size_t differ = 0;
        for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
        const ShadowStats& st = hybrid.masks.stats;
        std::printf("map %d: %zu of %llu receivers differ, %llu marked\n", mapSize, differ,
                    (unsigned long long)st.receiverPixels, (unsigned long long)st.markedPixels);
        EXPECT_LE(double(differ), 0.001 * double(st.receiverPixels)) << "map " << mapSize;
        EXPECT_LT(st.markedPixels, st.receiverPixels / 4) << "hybrid should trace a minority of pixels";
    }
}

}  // namespace
}  // namespace cuberille::rt
