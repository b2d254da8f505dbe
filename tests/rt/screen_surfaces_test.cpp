// The visibility buffer's surfaces against a slow, sure reference: each covered pixel's camera
// ray met with its triangle's plane in double precision, for a perspective and an orthographic
// camera. surfaceAt takes one division per pixel (rt/screen_surfaces.h); this is what it must
// still agree with.

#include <cstring>

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/texture.h"
#include "rt/primary_rays.h"
#include "rt/screen_surfaces.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

struct Reference {
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0};  // unit, facing the camera
};

/// The pixel centre's camera ray, from clip depth 0 to 1, met with the triangle's plane, all in double.
bool referenceSurface(const TriangleMeshView& mesh, uint32_t t, const glm::mat4& clipFromWorld, int width, int height, int x, int y,
                      Reference& out) {
    const glm::dmat4 worldFromClip = glm::inverse(glm::dmat4(clipFromWorld));
    const double nx = (x + 0.5) / width * 2.0 - 1.0, ny = 1.0 - (y + 0.5) / height * 2.0;
    const glm::dvec4 n4 = worldFromClip * glm::dvec4(nx, ny, 0.0, 1.0), f4 = worldFromClip * glm::dvec4(nx, ny, 1.0, 1.0);
    const glm::dvec3 origin = glm::dvec3(n4) / n4.w, direction = glm::dvec3(f4) / f4.w - origin;
    const glm::dvec3 a(mesh.vertex(t, 0)), b(mesh.vertex(t, 1)), c(mesh.vertex(t, 2));
    const glm::dvec3 normal = glm::normalize(glm::cross(b - a, c - a));
    const double denominator = glm::dot(normal, direction);
    if (denominator == 0.0) return false;
    out.position = origin + direction * (glm::dot(normal, a - origin) / denominator);
    out.normal = denominator > 0.0 ? -normal : normal;
    return true;
}

void expectSurfacesMatchTheReference(const glm::mat4& clipFromWorld, const char* camera) {
    OwnedMesh scene = testing::uvSphere(16, 32, glm::vec3(0.0f, 0.5f, 0.0f), 1.0f);
    const TriangleMeshView mesh = scene.view();
    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::None, {}};
    constexpr int kWidth = 160, kHeight = 120;
    raster::Pipeline gpu;
    const ScreenSurfaces s = findScreenSurfaces(mesh, std::span(&all, 1), clipFromWorld, kWidth, kHeight, gpu);
    size_t covered = 0;
    double worst = 0.0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const size_t i = size_t(y) * kWidth + x;
            if (!s.covered(i)) continue;
            ++covered;
            Surface surface;
            Reference reference;
            const bool found = s.surfaceAt(x, y, surface);
            ASSERT_EQ(found, referenceSurface(mesh, s.triangle[i], clipFromWorld, kWidth, kHeight, x, y, reference))
                << camera << " pixel " << x << ", " << y;
            if (!found) continue;
            worst = std::max(worst, glm::length(glm::dvec3(surface.position) - reference.position));
            EXPECT_GT(glm::dot(glm::dvec3(surface.normal), reference.normal), 0.999) << camera << " pixel " << x << ", " << y;
        }
    EXPECT_GT(covered, size_t(kWidth * kHeight / 10)) << camera << ": the sphere should fill part of the frame";
    // Within 1e-3 of a unit sphere seen from 4.7 away. What float loses is mostly in worldFromClip,
    // the inverse of a projection 500 times deeper than near: the three-division form surfaceAt
    // had before was as far off (4.5e-4 perspective, 0.8e-4 orthographic; now 4.4e-4 and 1.1e-4).
    EXPECT_LT(worst, 1e-3) << camera;
}

// seenByRange names each pixel's caster triangle as the frame that draws one draw per range would:
// (its range, its index within the range), over ranges of every kind a scene gives — empty ones
// (a mesh with no triangles) before, between and after the others, and many triangles each.
TEST(ScreenSurfaces, SeenByRangeNamesEachPixelsTriangleByItsRangeAndPlaceInIt) {
    OwnedMesh scene = testing::uvSphere(16, 32, glm::vec3(0.0f, 0.5f, 0.0f), 1.0f);
    const TriangleMeshView mesh = scene.view();
    const uint32_t triangles = uint32_t(mesh.triangleCount()), vertices = uint32_t(mesh.positions.size());
    // Ranges over the one vertex array (the sphere's indices are not rebased, so every range
    // starts at vertex 0 and uses them all): empty, a third, empty, the rest, empty.
    const uint32_t third = triangles / 3;
    const std::vector<CasterRange> ranges = {{0, 0, 0, vertices, raster::CullMode::None, {}},
                                             {0, third, 0, vertices, raster::CullMode::None, {}},
                                             {third, 0, 0, vertices, raster::CullMode::None, {}},
                                             {third, triangles - third, 0, vertices, raster::CullMode::None, {}},
                                             {triangles, 0, 0, vertices, raster::CullMode::None, {}}};
    constexpr int kWidth = 96, kHeight = 72;
    const glm::mat4 clipFromWorld = glm::perspective(glm::radians(45.0f), 4.0f / 3.0f, 0.1f, 50.0f) *
                                    glm::lookAt(glm::vec3(0.0f, 1.0f, 4.0f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
    raster::Pipeline gpu;
    VisibilityBuffer buffer;
    buffer.setCasters(mesh, ranges);
    const ScreenSurfaces& s = buffer.draw(clipFromWorld, kWidth, kHeight, gpu);
    raster::VisibilityBuffer named;
    buffer.seenByRange(named);
    ASSERT_EQ(named.width, kWidth);
    ASSERT_EQ(named.height, kHeight);
    ASSERT_EQ(named.samples, 1);
    size_t inFirst = 0, inSecond = 0;
    for (size_t i = 0; i < s.triangle.size(); ++i) {
        if (!s.covered(i)) {
            EXPECT_EQ(named.draw[i], raster::VisibilityBuffer::kNone) << "pixel " << i;
            continue;
        }
        ASSERT_TRUE(named.draw[i] == 1 || named.draw[i] == 3) << "pixel " << i << ": an empty range named, " << named.draw[i] << " for triangle " << s.triangle[i] << " of " << triangles;
        const CasterRange& r = ranges[named.draw[i]];
        EXPECT_LT(named.triangle[i], r.triangleCount) << "pixel " << i;
        EXPECT_EQ(r.firstTriangle + named.triangle[i], s.triangle[i]) << "pixel " << i;
        (named.draw[i] == 1 ? inFirst : inSecond) += 1;
    }
    EXPECT_GT(inFirst, 100u);
    EXPECT_GT(inSecond, 50u);
}

TEST(ScreenSurfaces, EachSurfaceIsWherePixelsRayMeetsItsTriangleForAPerspectiveCamera) {
    const glm::mat4 view = glm::lookAtRH(glm::vec3(2.0f, 2.5f, 3.5f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0));
    expectSurfacesMatchTheReference(glm::perspectiveRH_ZO(glm::radians(50.0f), 160.0f / 120.0f, 0.1f, 50.0f) * view, "perspective");
}

TEST(ScreenSurfaces, EachSurfaceIsWherePixelsRayMeetsItsTriangleForAnOrthographicCamera) {
    const glm::mat4 view = glm::lookAtRH(glm::vec3(-3.0f, 1.0f, 2.0f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0));
    expectSurfacesMatchTheReference(glm::orthoRH_ZO(-1.6f, 1.6f, -1.2f, 1.2f, 0.1f, 20.0f) * view, "orthographic");
}

// The ray-tracing renderer's receivers (surfacesFromVisibility): the pixels its camera rays hit
// are the covered ones; each gets the plane of the triangle its ray hit with the bits the casters'
// visibility buffer gives that triangle (so shadows match wherever both name one triangle), the
// surface where the pixel's ray meets it (the double reference, within the bound above), and the
// hull reaches exactly as deep as the deepest surface.
TEST(ScreenSurfaces, FromCameraRaysEachPixelGetsThePlaneOfTheTriangleItsRayHit) {
    const OwnedMesh scene = testing::uvSphere(16, 32, glm::vec3(0.0f, 0.5f, 0.0f), 1.0f);
    const TriangleMeshView mesh = scene.view();
    constexpr int kWidth = 160, kHeight = 120;
    const glm::vec3 eye(2.0f, 2.5f, 3.5f), target(0.0f, 0.5f, 0.0f);
    const glm::mat4 clipFromWorld = glm::perspectiveRH_ZO(glm::radians(50.0f), 160.0f / 120.0f, 0.1f, 50.0f) *
                                    glm::lookAtRH(eye, target, glm::vec3(0, 1, 0));
    raster::DrawCall draw;
    draw.clipFromObject = clipFromWorld;
    draw.positions = mesh.positions;
    draw.indices = mesh.indices;
    draw.state.cull = raster::CullMode::Back;
    PrimaryRayCamera camera;
    camera.worldFromClip = glm::inverse(glm::dmat4(clipFromWorld));
    camera.eye = eye;
    camera.viewDirection = glm::normalize(target - eye);
    raster::VisibilityBuffer seen;
    seen.reset(kWidth, kHeight, 1);
    const std::vector<uint8_t> traced{1};
    tracePrimaryVisibility(std::span(&draw, 1), traced, camera, CasterAccel::Bvh, seen);
    ScreenSurfaces s;
    surfacesFromVisibility(seen, std::span(&draw, 1), clipFromWorld, s);

    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::Back, {}};
    raster::Pipeline gpu;
    const ScreenSurfaces drawn = findScreenSurfaces(mesh, std::span(&all, 1), clipFromWorld, kWidth, kHeight, gpu);
    size_t covered = 0;
    double worst = 0.0;
    float deepest = -1.0f;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const size_t i = size_t(y) * kWidth + x;
            ASSERT_EQ(s.covered(i), seen.draw[i] != raster::VisibilityBuffer::kNone) << "pixel " << x << ", " << y;
            if (!s.covered(i)) continue;
            ++covered;
            const uint32_t t = seen.triangle[i];
            const TrianglePlane& plane = s.planes[s.triangle[i]];
            ASSERT_EQ(std::memcmp(&plane, &drawn.planes[t], sizeof(TrianglePlane)), 0) << "pixel " << x << ", " << y;
            Surface surface;
            Reference reference;
            ASSERT_EQ(s.surfaceAt(x, y, surface), referenceSurface(mesh, t, clipFromWorld, kWidth, kHeight, x, y, reference));
            worst = std::max(worst, glm::length(glm::dvec3(surface.position) - reference.position));
            EXPECT_GT(glm::dot(glm::dvec3(surface.normal), reference.normal), 0.999) << "pixel " << x << ", " << y;
            const glm::vec4 clip = clipFromWorld * glm::vec4(surface.position, 1.0f);
            deepest = std::max(deepest, clip.z / clip.w);
        }
    EXPECT_GT(covered, size_t(kWidth * kHeight / 10));
    EXPECT_LT(worst, 1e-3);
    ASSERT_EQ(s.seenHull.size(), 8u);
    const glm::vec4 far = clipFromWorld * glm::vec4(s.seenHull[4], 1.0f);
    EXPECT_NEAR(far.z / far.w, deepest, 1e-6f);  // the far corners come back through the inverse
}

// An alpha-tested caster's holes are seen through, as the frame's alpha test sees through them: a
// quad in front of a back plane, its base colour texture opaque on the right half only (two
// texels, magnified nearest: each pixel's alpha is known exactly), so every pixel whose centre
// lies left of the middle names the back plane and every other names the quad; with a vertex
// alpha ramp, a pixel is a hole where the factor times the ramp is under the cutoff too; with a
// factor under the cutoff the quad is all hole. The id colours pass through the shade stage
// unchanged (the texture is made white, the ids rounded back). Without the alpha test the quad
// hides the back plane everywhere.
TEST(ScreenSurfaces, AlphaTestedCastersAreSeenThroughTheirHoles) {
    constexpr int kWidth = 64, kHeight = 32;
    // Orthographic, looking down -z at [0, 1] x [0, 1]: pixel (x, y)'s centre is u = (x + 1/2) / 64.
    const glm::mat4 clipFromWorld = glm::orthoRH_ZO(0.0f, 1.0f, 0.0f, 1.0f, 0.1f, 10.0f) *
                                    glm::lookAtRH(glm::vec3(0, 0, 5), glm::vec3(0, 0, 0), glm::vec3(0, 1, 0));
    // Ids past 16 bits, so both id channels go through interpolation: 70,000 triangles of no
    // area first (drawn, never seen), then the quad, then the back plane.
    constexpr uint32_t kFirstQuad = 70000, kFirstBack = kFirstQuad + 2;
    OwnedMesh scene;
    scene.positions.push_back(glm::vec3(0.5f, 0.5f, 2.0f));
    scene.indices.assign(3 * size_t(kFirstQuad), 0u);
    for (const float z : {1.0f, 0.0f}) {
        const uint32_t base = uint32_t(scene.positions.size());
        for (const glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(2, -1), glm::vec2(2, 2), glm::vec2(-1, 2)})
            scene.positions.push_back(z == 1.0f ? glm::vec3(glm::clamp(c, 0.0f, 1.0f), z) : glm::vec3(c, z));
        for (const uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) scene.indices.push_back(base + i);
    }
    const std::vector<glm::vec2> uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};  // u along x; v down the image
    const std::vector<float> ramp = {0.0f, 1.0f, 1.0f, 0.0f};            // alpha rising with x
    const raster::Texture halfOpaque(2, 1, std::vector<uint8_t>{200, 10, 10, 0, 10, 200, 10, 255}, raster::TexelFormat::Srgb8,
                                     raster::WrapMode::ClampToEdge, raster::WrapMode::ClampToEdge,
                                     {.magnifyNearest = true, .minify = raster::MinFilter::Nearest});
    const std::shared_ptr<const raster::Texture> white = alphaTestTexture(halfOpaque);
    ASSERT_EQ(white->texel(0, 0, 0), glm::vec4(1, 1, 1, 0));
    ASSERT_EQ(white->texel(0, 1, 0), glm::vec4(1, 1, 1, 1));
    struct Case {
        const char* name;
        std::optional<CasterAlphaTest> test;
        float holesLeftOf;  // u below which a pixel sees the back plane
    };
    CasterAlphaTest textured{.cutoff = 0.5f, .factor = 1.0f, .vertexAlphas = {}, .texCoords = uvs, .alphaOnly = {white.get(), {}}};
    CasterAlphaTest ramped{.cutoff = 0.75f, .factor = 1.0f, .vertexAlphas = ramp, .texCoords = {}, .alphaOnly = {}};
    CasterAlphaTest faint{.cutoff = 0.5f, .factor = 0.4f, .vertexAlphas = {}, .texCoords = {}, .alphaOnly = {}};
    for (const Case& c : {Case{"opaque", std::nullopt, 0.0f}, Case{"texture", textured, 0.5f}, Case{"vertex alphas", ramped, 0.75f},
                          Case{"factor", faint, 2.0f}}) {
        const CasterRange ranges[3] = {{0, kFirstQuad, 0, 1, raster::CullMode::None, {}},
                                       {kFirstQuad, 2, 1, 4, raster::CullMode::None, c.test},
                                       {kFirstBack, 2, 5, 4, raster::CullMode::None, {}}};
        raster::Pipeline gpu;
        const ScreenSurfaces s = findScreenSurfaces(scene.view(), ranges, clipFromWorld, kWidth, kHeight, gpu);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                const size_t i = size_t(y) * kWidth + x;
                ASSERT_TRUE(s.covered(i));
                const bool hole = (x + 0.5f) / kWidth < c.holesLeftOf;
                const uint32_t first = hole ? kFirstBack : kFirstQuad;
                EXPECT_TRUE(s.triangle[i] == first || s.triangle[i] == first + 1)
                    << c.name << ", pixel " << x << ", " << y << ": triangle " << s.triangle[i];
            }
    }
}

}  // namespace
}  // namespace cuberille::rt
