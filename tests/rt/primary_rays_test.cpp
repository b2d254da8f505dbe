// Camera rays (rt/primary_rays.h): each sample sees what brute force over every triangle sees,
// through either structure and at any thread count; where they part from the rasterizer's depth
// test, it is only where snapping to 1/256 pixel can decide.

#include <gtest/gtest.h>

#include <cmath>

#include "rt/primary_rays.h"
#include "rt/ray_query.h"
#include "rt/screen_surfaces.h"
#include "tests/raster/random_draws.h"
#include "tests/thread_counts.h"

namespace cuberille::testing {
namespace {

rt::PrimaryRayCamera cameraOf(const RandomPerspectiveDraws& s) {
    rt::PrimaryRayCamera c;
    c.worldFromClip = glm::inverse(glm::dmat4(s.clipFromWorld));
    c.eye = s.eye;
    c.viewDirection = glm::normalize(s.target - s.eye);
    return c;
}

glm::dvec2 samplePosition(int x, int y, int s, int samples) {
    const raster::SamplePattern& sp = raster::standardSamplePattern(samples);
    return {x + 0.5 + sp.dx[s] / 16.0, y + 0.5 + sp.dy[s] / 16.0};
}

/// The draws' triangles as one mesh, and which of them a culled draw turns away from the eye (the
/// definition: counter-clockwise seen from the eye is the front, raster/draw.h).
struct ReferenceMesh {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices, drawOf, triangleOf;
    std::vector<uint8_t> culled;

    ReferenceMesh(const std::vector<raster::DrawCall>& draws, const glm::vec3& eye) {
        for (size_t d = 0; d < draws.size(); ++d) {
            const uint32_t base = uint32_t(positions.size());
            positions.insert(positions.end(), draws[d].positions.begin(), draws[d].positions.end());
            for (size_t t = 0; t < draws[d].triangleCount(); ++t) {
                uint32_t corner[3];
                for (int k = 0; k < 3; ++k)
                    corner[k] = base + (draws[d].indices.empty() ? uint32_t(3 * t + k) : draws[d].indices[3 * t + k]);
                indices.insert(indices.end(), corner, corner + 3);
                drawOf.push_back(uint32_t(d)), triangleOf.push_back(uint32_t(t));
                const glm::vec3 &a = positions[corner[0]], &b = positions[corner[1]], &c = positions[corner[2]];
                const bool front = glm::dot(glm::cross(b - a, c - a), eye - a) > 0.0f;
                const raster::CullMode cull = draws[d].state.cull;
                culled.push_back(cull != raster::CullMode::None && front == (cull == raster::CullMode::Front));
            }
        }
    }
    rt::TriangleMeshView view() const { return {positions, indices}; }
};

// Every triangle in one mesh, tested one by one, less those the draws' culling turns away: the
// reference (a draw culls back faces, one front faces, one neither). Both structures, 1 and 4
// samples, every thread count: the same (draw, triangle) at every sample.
TEST(PrimaryRays, EverySampleSeesWhatBruteForceSees) {
    constexpr int kWidth = 48, kHeight = 32;
    for (const uint32_t seed : {1u, 2u}) {
        const RandomPerspectiveDraws scene(seed);
        std::vector<raster::DrawCall> draws = scene.draws();
        draws[2].state.cull = raster::CullMode::Front;
        const ReferenceMesh reference(draws, scene.eye);
        const rt::TriangleMeshView all = reference.view();
        const std::vector<uint32_t>& drawOf = reference.drawOf;
        const std::vector<uint32_t>& triangleOf = reference.triangleOf;
        const rt::HitFilter culled{reference.culled};  // 1: skipped, as HitFilter::kSkipped
        const size_t kept = size_t(std::count(reference.culled.begin(), reference.culled.end(), 0));
        ASSERT_LT(kept, drawOf.size() * 5 / 6);
        const rt::PrimaryRayCamera camera = cameraOf(scene);
        const std::vector<uint8_t> traced(draws.size(), 1);
        for (const int samples : {1, 4}) {
            raster::VisibilityBuffer expected;
            expected.reset(kWidth, kHeight, samples);
            int hits = 0;
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int s = 0; s < samples; ++s) {
                        const glm::dvec2 p = samplePosition(x, y, s, samples);
                        const rt::RayHit h = rt::closestHitBruteForce(all, rt::primaryRay(camera, p.x, p.y, kWidth, kHeight), &culled);
                        if (!h.hit()) continue;
                        ++hits;
                        const size_t i = (size_t(y) * kWidth + x) * samples + s;
                        expected.draw[i] = drawOf[h.triangle], expected.triangle[i] = triangleOf[h.triangle];
                    }
            ASSERT_GT(hits, kWidth * kHeight * samples / 2);
            for (const rt::CasterAccel accel : {rt::CasterAccel::Bvh, rt::CasterAccel::Grid})
                for (const ThreadCount count : kThreadCounts) {
                    ThreadCountScope threads(count);
                    raster::VisibilityBuffer found;
                    found.reset(kWidth, kHeight, samples);
                    const rt::PrimaryRayStats stats = rt::tracePrimaryVisibility(draws, traced, camera, accel, found);
                    const std::string where = "seed " + std::to_string(seed) + ", " + std::to_string(samples) + " samples, " +
                                              (accel == rt::CasterAccel::Grid ? "grid, " : "bvh, ") +
                                              std::to_string(count.threads) + " threads";
                    EXPECT_EQ(stats.triangles, accel == rt::CasterAccel::Grid ? kept : drawOf.size()) << where;
                    EXPECT_EQ(stats.hits, uint64_t(hits)) << where;
                    EXPECT_EQ(found.draw, expected.draw) << where;
                    EXPECT_EQ(found.triangle, expected.triangle) << where;
                }
        }
    }
}

// The ray-traced frame's receivers at more than one sample (rt::centresWhereSamplesAgree, then
// PrimaryRayHierarchy::traceCentres): every pixel whose samples part gets brute force's centre
// ray, at any thread count; every pixel whose samples agree gets their triangle, which is the
// centre ray's unless that ray's triangle is one no sample of the pixel sees (lying between them:
// 3 and 6 of 1,536 pixels on these scenes of 1,500 small triangles, whose samples part at 40-44%
// of the pixels; 1% bounds it).
TEST(PrimaryRays, ReceiversAtPixelCentresAreTheSamplesTriangleOrTheCentreRays) {
    constexpr int kWidth = 48, kHeight = 32, kSamples = 4;
    for (const uint32_t seed : {1u, 2u}) {
        const RandomPerspectiveDraws scene(seed);
        std::vector<raster::DrawCall> draws = scene.draws();
        draws[2].state.cull = raster::CullMode::Front;
        const ReferenceMesh reference(draws, scene.eye);
        const rt::HitFilter culled{reference.culled};
        const rt::PrimaryRayCamera camera = cameraOf(scene);
        const std::vector<uint8_t> traced(draws.size(), 1);
        rt::PrimaryRayHierarchy kept(draws, traced, rt::BvhUpdateMethod::Refit);
        raster::VisibilityBuffer seen;
        seen.reset(kWidth, kHeight, kSamples);
        kept.trace(draws, camera, seen);
        for (const ThreadCount count : kThreadCounts) {
            ThreadCountScope threads(count);
            raster::VisibilityBuffer centres;
            std::vector<uint32_t> open;
            rt::centresWhereSamplesAgree(seen, centres, open);
            ASSERT_GT(open.size(), size_t(kWidth * kHeight / 20)) << "seed " << seed;
            ASSERT_LT(open.size(), size_t(kWidth * kHeight));
            kept.traceCentres(draws, camera, open, centres);
            size_t nextOpen = 0, betweenSamples = 0;
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x) {
                    const size_t p = size_t(y) * kWidth + x;
                    const rt::RayHit h = rt::closestHitBruteForce(reference.view(), rt::primaryRay(camera, x + 0.5, y + 0.5, kWidth, kHeight), &culled);
                    const uint32_t draw = h.hit() ? reference.drawOf[h.triangle] : raster::VisibilityBuffer::kNone;
                    const uint32_t triangle = h.hit() ? reference.triangleOf[h.triangle] : raster::VisibilityBuffer::kNone;
                    const bool isOpen = nextOpen < open.size() && open[nextOpen] == p;
                    nextOpen += isOpen;
                    const std::string where = "seed " + std::to_string(seed) + ", " + std::to_string(count.threads) + " threads, pixel " +
                                              std::to_string(x) + ", " + std::to_string(y);
                    if (isOpen || (centres.draw[p] == draw && (draw == raster::VisibilityBuffer::kNone || centres.triangle[p] == triangle))) {
                        EXPECT_EQ(centres.draw[p], draw) << where;
                        if (draw != raster::VisibilityBuffer::kNone) {
                            EXPECT_EQ(centres.triangle[p], triangle) << where;
                        }
                        continue;
                    }
                    ++betweenSamples;
                    for (int s = 0; s < kSamples; ++s)
                        EXPECT_FALSE(seen.draw[p * kSamples + s] == draw && seen.triangle[p * kSamples + s] == triangle) << where;
                }
            EXPECT_EQ(nextOpen, open.size());
            EXPECT_LT(betweenSamples, size_t(kWidth * kHeight / 100)) << "seed " << seed;
        }
    }
}

// One tree kept across views and poses — refitted, lazily updated or rebuilt — answers each view
// of each pose as the grid built for that frame does (and so as brute force does), with the
// draws' culling decided afresh for each view; a change of culling or of the traced draws is not
// taken for the same draws.
TEST(PrimaryRays, AKeptHierarchyAnswersEveryViewAndPoseAsAFreshGrid) {
    constexpr int kWidth = 64, kHeight = 40, kSamples = 2;
    for (const rt::BvhUpdateMethod method : {rt::BvhUpdateMethod::Refit, rt::BvhUpdateMethod::Lazy, rt::BvhUpdateMethod::Rebuild}) {
        RandomPerspectiveDraws scene(5);
        const std::vector<raster::DrawCall> draws = scene.draws();
        const std::vector<uint8_t> traced(draws.size(), 1);
        rt::PrimaryRayHierarchy kept(draws, traced, method);
        ASSERT_TRUE(kept.sameDraws(draws, traced));
        std::mt19937 rng(9);
        std::uniform_real_distribution<float> jitter(-0.05f, 0.05f);
        for (int pose = 0; pose < 3; ++pose) {
            if (pose > 0) {  // every vertex moved in place: the same draws, a new pose
                for (std::vector<glm::vec3>& p : scene.positions)
                    for (glm::vec3& v : p) v += glm::vec3(jitter(rng), jitter(rng), jitter(rng)) + glm::vec3(0.02f * pose, 0.0f, 0.0f);
                kept.update(draws);
            }
            for (const glm::vec3 eye : {glm::vec3(0.3f, 0.2f, 0.6f), glm::vec3(-1.5f, 0.5f, -1.0f), glm::vec3(1.0f, -0.4f, -6.0f)}) {
                RandomPerspectiveDraws view(5);
                view.eye = eye;
                view.clipFromWorld = glm::perspective(glm::radians(60.0f), 1.5f, 0.1f, 20.0f) *
                                     glm::lookAt(eye, glm::vec3(0.0f, 0.0f, -3.0f), glm::vec3(0, 1, 0));
                const rt::PrimaryRayCamera camera = cameraOf(view);
                raster::VisibilityBuffer fromKept, fromGrid;
                fromKept.reset(kWidth, kHeight, kSamples);
                fromGrid.reset(kWidth, kHeight, kSamples);
                const rt::PrimaryRayStats stats = kept.trace(draws, camera, fromKept);
                rt::tracePrimaryVisibility(draws, traced, camera, rt::CasterAccel::Grid, fromGrid);
                EXPECT_GT(stats.hits, uint64_t(kWidth * kHeight)) << "pose " << pose;
                EXPECT_EQ(fromKept.draw, fromGrid.draw) << "pose " << pose;
                EXPECT_EQ(fromKept.triangle, fromGrid.triangle) << "pose " << pose;
            }
        }
        std::vector<raster::DrawCall> changed = draws;
        changed[1].state.cull = raster::CullMode::Front;
        EXPECT_FALSE(kept.sameDraws(changed, traced));
        std::vector<uint8_t> fewer = traced;
        fewer[2] = 0;
        EXPECT_FALSE(kept.sameDraws(draws, fewer));
    }
}

/// An alpha-tested screen (a quad whose base colour texture's alpha is a checker, cut at 0.5)
/// before an opaque wall, seen straight on at `distance`: near, the checker is magnified; far, it
/// is minified, and only the level of detail the rasterizer takes decides what survives.
struct MaskedScreen {
    std::vector<glm::vec3> screen, wall;
    std::vector<glm::vec2> uvs;
    std::vector<uint32_t> quad{0, 1, 2, 0, 2, 3};
    raster::Texture checker;
    glm::mat4 clipFromWorld;
    glm::vec3 eye{0.0f, 0.0f, 0.0f};

    MaskedScreen(float distance, float tiles) : checker(makeChecker()) {
        const float h = 1.0f;
        screen = {{-h, -h, -distance}, {h, -h, -distance}, {h, h, -distance}, {-h, h, -distance}};
        wall = {{-9, -9, -distance - 1}, {9, -9, -distance - 1}, {9, 9, -distance - 1}, {-9, 9, -distance - 1}};
        uvs = {{0, 0}, {tiles, 0}, {tiles, tiles}, {0, tiles}};
        clipFromWorld = glm::perspective(glm::radians(50.0f), 1.5f, 0.1f, 100.0f) *
                        glm::lookAt(eye, glm::vec3(0.1f, 0.05f, -1.0f), glm::vec3(0, 1, 0));
    }
    static raster::Texture makeChecker() {
        std::vector<glm::vec4> texels(8 * 8);
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) texels[y * 8 + x] = {1.0f, 1.0f, 1.0f, (x + y) % 2 ? 1.0f : 0.0f};
        return raster::Texture(8, 8, std::move(texels));
    }
    std::vector<raster::DrawCall> draws() const {
        std::vector<raster::DrawCall> out(2);
        for (raster::DrawCall& d : out) {
            d.clipFromObject = clipFromWorld;
            d.indices = quad;
            d.state.shading = raster::ShadingModel::Unlit;
        }
        out[0].positions = screen;
        out[0].texCoords = uvs;
        out[0].state.textures.baseColor.texture = &checker;
        out[0].state.constantColor = glm::vec4(1.0f, 0.0f, 0.0f, 1.0f);
        out[0].state.alphaMode = raster::AlphaMode::Mask;
        out[0].state.alphaCutoff = 0.5f;
        out[1].positions = wall;
        out[1].state.constantColor = glm::vec4(0.0f, 0.0f, 1.0f, 1.0f);
        return out;
    }
};

// The alpha test on camera rays is the rasterizer's: at one sample (the pixel centre, where the
// rasterizer tests a pixel's alpha) the screen is seen at the samples where the forward frame
// kept it — magnified (4 texels across the quad) and minified (512 texels across a quad of some
// 20 pixels, so a coarse level decides) — but for the few whose alpha lies within rounding of
// the cutoff; and the BVH and the grid, at one and two threads, name the same hits.
TEST(PrimaryRays, AlphaTestedHitsPassWhereTheRasterizersPixelsDo) {
    constexpr int kWidth = 96, kHeight = 64;
    for (const auto& [distance, tiles] : {std::pair{2.5f, 4.0f}, std::pair{12.0f, 512.0f}}) {
        const MaskedScreen scene(distance, tiles);
        const std::vector<raster::DrawCall> draws = scene.draws();
        raster::Pipeline forward;
        forward.beginFrame(frame(kWidth, kHeight, 1));
        for (const raster::DrawCall& d : draws) forward.draw(d);
        forward.endFrame();
        rt::PrimaryRayCamera camera;
        camera.worldFromClip = glm::inverse(glm::dmat4(scene.clipFromWorld));
        camera.eye = scene.eye;
        const std::vector<uint8_t> traced(draws.size(), 1);
        raster::VisibilityBuffer bvh;
        bvh.reset(kWidth, kHeight, 1);
        rt::tracePrimaryVisibility(draws, traced, camera, rt::CasterAccel::Bvh, bvh);
        int screen = 0, wall = 0, differing = 0;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                const bool rasterScreen = sampleColor(forward.framebuffer(), x, y, 0).r > 0.5f;
                const uint32_t seen = bvh.draw[size_t(y) * kWidth + x];
                screen += seen == 0, wall += seen == 1;
                differing += rasterScreen != (seen == 0);
            }
        const std::string where = "distance " + std::to_string(distance);
        EXPECT_GT(screen, 20) << where;
        EXPECT_GT(wall, 20) << where;
        EXPECT_LE(differing, (screen + 99) / 100) << where << ": over 1% of the screen's samples";
        for (const ThreadCount count : {kThreadCounts[0], kThreadCounts[1]}) {
            ThreadCountScope threads(count);
            raster::VisibilityBuffer grid;
            grid.reset(kWidth, kHeight, 1);
            rt::tracePrimaryVisibility(draws, traced, camera, rt::CasterAccel::Grid, grid);
            EXPECT_EQ(grid.draw, bvh.draw) << where;
            EXPECT_EQ(grid.triangle, bvh.triangle) << where;
        }
    }
}

/// A triangle of a draw as the rasterizer would place it before snapping, in double: window
/// positions (pixels) and depths; `inFront` false where a vertex lies behind the eye's plane
/// (clipping then makes the window triangle something else).
struct WindowTriangle {
    glm::dvec3 v[3];  // x, y in pixels, z in [0, 1]
    bool inFront = true;
};

WindowTriangle windowTriangle(const RandomPerspectiveDraws& scene, const raster::DrawCall& draw, uint32_t triangle, int width,
                              int height) {
    WindowTriangle w;
    for (int k = 0; k < 3; ++k) {
        const size_t i = draw.indices.empty() ? 3 * size_t(triangle) + k : draw.indices[3 * size_t(triangle) + k];
        const glm::dvec4 c = glm::dmat4(scene.clipFromWorld) * glm::dvec4(glm::dvec3(draw.positions[i]), 1.0);
        if (!(c.w > 1e-6)) w.inFront = false;
        w.v[k] = {(c.x / c.w + 1.0) * width / 2.0, (1.0 - c.y / c.w) * height / 2.0, c.z / c.w};
    }
    return w;
}

double distanceToEdges(const WindowTriangle& w, const glm::dvec2& p) {
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        const glm::dvec2 a(w.v[k]), b(w.v[(k + 1) % 3]);
        const glm::dvec2 e = b - a;
        const double length = glm::length(e);
        if (length == 0.0) return 0.0;
        nearest = std::min(nearest, std::abs(e.x * (p.y - a.y) - e.y * (p.x - a.x)) / length);
    }
    return nearest;
}

/// The triangle's window depth at p and the length of its depth gradient (per pixel).
glm::dvec2 depthAndGradient(const WindowTriangle& w, const glm::dvec2& p) {
    const glm::dvec3 n = glm::cross(w.v[1] - w.v[0], w.v[2] - w.v[0]);
    if (n.z == 0.0) return {0.0, std::numeric_limits<double>::infinity()};
    const glm::dvec2 gradient(-n.x / n.z, -n.y / n.z);
    return {w.v[0].z + gradient.x * (p.x - w.v[0].x) + gradient.y * (p.y - w.v[0].y), glm::length(gradient)};
}

// The bound on where snapping can decide: each vertex moves by at most 1/512 pixel in x and in y,
// so an edge by at most sqrt(2)/512 = 0.0028 pixel, and a depth plane's value at a sample by its
// gradient times that much; 1/256 pixel covers both with the float rounding of the vertex stage
// (some 1e-5 pixel over a frame this size) to spare.
constexpr double kSnapPixels = 1.0 / 256.0;

// Random scenes with culling, clipping and intersecting triangles, at 1 and 4 samples: every
// sample where the rays and the depth test name different triangles (or one names none) lies
// within kSnapPixels of an edge of either triangle, or where their depths are within what
// snapping can move them; and few do. Culling the wrong side, a ray through the wrong position or
// the wrong depth range would part from the rasterizer far from any edge.
TEST(PrimaryRays, PartFromTheDepthTestOnlyWhereSnappingDecides) {
    constexpr int kWidth = 150, kHeight = 100;
    for (const uint32_t seed : {1u, 2u, 3u}) {
        const RandomPerspectiveDraws scene(seed);
        const std::vector<raster::DrawCall> draws = scene.draws();
        const std::vector<uint8_t> traced(draws.size(), 1);
        for (const int samples : {1, 4}) {
            const std::string where = "seed " + std::to_string(seed) + ", " + std::to_string(samples) + " samples";
            const raster::VisibilityBuffer raster = visibilityOfForwardFrame(draws, kWidth, kHeight, samples);
            raster::VisibilityBuffer rays;
            rays.reset(kWidth, kHeight, samples);
            rt::tracePrimaryVisibility(draws, traced, cameraOf(scene), rt::CasterAccel::Bvh, rays);
            int differing = 0, unexplained = 0;
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int s = 0; s < samples; ++s) {
                        const size_t i = (size_t(y) * kWidth + x) * samples + s;
                        if (raster.draw[i] == rays.draw[i] && raster.triangle[i] == rays.triangle[i]) continue;
                        ++differing;
                        const glm::dvec2 p = samplePosition(x, y, s, samples);
                        std::vector<WindowTriangle> named;
                        for (const raster::VisibilityBuffer* b : {&raster, static_cast<const raster::VisibilityBuffer*>(&rays)})
                            if (b->draw[i] != raster::VisibilityBuffer::kNone)
                                named.push_back(windowTriangle(scene, draws[b->draw[i]], b->triangle[i], kWidth, kHeight));
                        bool explained = false;
                        for (const WindowTriangle& w : named)
                            explained = explained || !w.inFront || distanceToEdges(w, p) <= kSnapPixels;
                        if (!explained && named.size() == 2) {
                            const glm::dvec2 a = depthAndGradient(named[0], p), b = depthAndGradient(named[1], p);
                            explained = std::abs(a.x - b.x) <= (a.y + b.y) * kSnapPixels + 1e-6;
                        }
                        if (!explained && unexplained++ < 3)
                            ADD_FAILURE() << where << ": sample " << s << " of (" << x << ", " << y
                                          << ") parts from the depth test away from any edge or depth tie";
                    }
            EXPECT_EQ(unexplained, 0) << where;
            EXPECT_LT(differing, kWidth * kHeight * samples / 200) << where << ": more than 0.5% of the samples differ";
        }
    }
}

}  // namespace
}  // namespace cuberille::testing
