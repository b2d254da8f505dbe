// Rendering voxel models: the LOD bound holds for every drawn voxel, mixed levels leave no crack,
// and frames do not depend on the thread count.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "lod/lod_pyramid.h"
#include "lod/voxel_scene.h"
#include "raster/parallel.h"
#include "raster/resolve.h"
#include "tests/voxel/voxel_test_support.h"
#include "tests/thread_counts.h"

namespace cuberille {
namespace {

constexpr double kRadius = 2.0;
const glm::dvec3 kCentre(0.3, 0.1, -0.2);

voxel::VoxelModel spherePyramid(uint32_t resolution, bool withTriangles = true,
                                voxel::Separability separability = voxel::Separability::Conservative,
                                lod::PyramidOptions pyramid = {}) {
    std::mt19937 rng(21);
    const auto tris = testing::icosphere(4, kCentre, kRadius, testing::randomRotation(rng));
    voxel::VoxelizeOptions o;
    o.resolution = resolution;
    o.keepSourceTriangles = withTriangles;
    o.separability = separability;
    voxel::VoxelModel m = voxel::voxelizeMesh(*testing::viewOf(tris, 1000), o);
    lod::buildLodPyramid(m, pyramid);
    return m;
}

scene::Camera cameraAt(const glm::dvec3& eye) {
    scene::Camera c;
    c.position = glm::vec3(eye);
    c.target = glm::vec3(kCentre) + glm::vec3(0.0f, 0.0f, 0.01f);  // never looking straight down an axis at itself
    c.verticalFovDegrees = glm::degrees(0.7f);
    c.nearPlane = 0.01f;
    c.farPlane = 100.0f;
    return c;
}

double distanceToBox(const glm::dvec3& p, const glm::dvec3& lo, const glm::dvec3& hi) {
    return glm::length(glm::max(glm::max(lo - p, p - hi), glm::dvec3(0.0)));
}

TEST(LodBound, NoDrawnVoxelProjectsBeyondThePixelError) {
    const voxel::VoxelModel m = spherePyramid(512);
    lod::SelectionOptions o;
    o.viewportHeightPixels = 720;
    o.verticalFovRadians = 0.7f;
    const double focal = 720 / (2.0 * std::tan(0.35));
    for (float pixelError : {1.0f, 4.0f})
        for (const glm::dvec3& eye : {glm::dvec3(0.3, 0.1, 12.0), glm::dvec3(5.0, 3.0, 2.0), glm::dvec3(0.3, 0.1, 2.5),
                                      glm::dvec3(40.0, -30.0, 25.0), glm::dvec3(0.3, 0.1, -0.2) /* inside */}) {
            o.pixelError = pixelError;
            const glm::mat4 clip = cameraAt(eye).clipFromWorld(16.0f / 9.0f);
            const lod::BlockSelection s = lod::selectBlocks(m, glm::dmat4(clip), eye, o);
            ASSERT_FALSE(s.voxelBlocks.empty() && s.triangleBlocks.empty());
            for (uint32_t i : s.voxelBlocks) {
                const voxel::VoxelBlock& b = m.blocks[i];
                const voxel::VoxelBoxes boxes(m, b);
                for (uint32_t packed : b.voxels) {  // each voxel, by itself
                    const glm::dvec3 lo = boxes.lowCorner(voxel::voxelPositionInBlock(packed));
                    const double d = distanceToBox(eye, lo, lo + boxes.voxelSize);
                    ASSERT_GT(d, 0.0) << "a voxel around the camera was drawn";
                    EXPECT_LE(boxes.voxelSize * focal / d, pixelError * (1.0 + 1e-9))
                        << "level " << b.level;
                }
            }
        }
}

// The other side of the bound: selection refines no further than it must. Every drawn block below
// the root was reached because its parent was too coarse by the same bound (the parent's voxels,
// at its nearest point, project beyond the pixel error asked for).
TEST(LodBound, NoBlockIsRefinedFurtherThanThePixelErrorAsks) {
    const voxel::VoxelModel m = spherePyramid(512);
    std::vector<int64_t> parentOf(m.blocks.size(), -1);
    for (size_t i = 0; i < m.blocks.size(); ++i)
        for (int k = 0; k < __builtin_popcount(m.blocks[i].childMask); ++k) parentOf[m.blocks[i].firstChild + size_t(k)] = int64_t(i);
    lod::SelectionOptions o;
    o.viewportHeightPixels = 720;
    o.verticalFovRadians = 0.7f;
    size_t refined = 0;
    for (float pixelError : {1.0f, 4.0f})
        for (const glm::dvec3& eye : {glm::dvec3(0.3, 0.1, 12.0), glm::dvec3(5.0, 3.0, 2.0), glm::dvec3(40.0, -30.0, 25.0)}) {
            o.pixelError = pixelError;
            const glm::mat4 clip = cameraAt(eye).clipFromWorld(16.0f / 9.0f);
            const lod::BlockSelection s = lod::selectBlocks(m, glm::dmat4(clip), eye, o);
            ASSERT_FALSE(s.voxelBlocks.empty());
            for (uint32_t i : s.voxelBlocks) {
                if (parentOf[i] < 0) continue;  // the root: nothing coarser to draw
                ++refined;
                EXPECT_GT(lod::projectedVoxelPixels(m, m.blocks[size_t(parentOf[i])], eye, o), pixelError)
                    << "block " << i << " at level " << m.blocks[i].level << " was refined into needlessly";
            }
        }
    EXPECT_GT(refined, 0u);
}

TEST(LodBound, HybridBlocksAreFinestLevelBlocksThatNeededRefining) {
    const voxel::VoxelModel m = spherePyramid(256);
    const glm::dvec3 eye(0.3, 0.1, 2.3);  // just outside the sphere: the nearest voxels are too coarse
    const glm::mat4 clip = cameraAt(eye).clipFromWorld(1.0f);
    lod::SelectionOptions o;
    const lod::BlockSelection with = lod::selectBlocks(m, glm::dmat4(clip), eye, o);
    EXPECT_GT(with.triangleBlocks.size(), 0u);
    for (uint32_t i : with.triangleBlocks) EXPECT_EQ(m.blocks[i].level, 0u);
    o.hybrid = false;
    const lod::BlockSelection without = lod::selectBlocks(m, glm::dmat4(clip), eye, o);
    EXPECT_EQ(without.triangleBlocks.size(), 0u);
    EXPECT_EQ(without.voxelBlocks.size(), with.voxelBlocks.size() + with.triangleBlocks.size());
}

TEST(LodBound, FinestLevelCapsRefinementAndDrawsVoxelsThere) {
    const voxel::VoxelModel m = spherePyramid(256);
    const glm::dvec3 eye(0.3, 0.1, 2.3);
    const glm::mat4 clip = cameraAt(eye).clipFromWorld(1.0f);
    lod::SelectionOptions o;
    o.pixelError = 0.0f;  // refine as far as allowed
    o.finestLevel = 1;    // the 128 voxel level
    const lod::BlockSelection s = lod::selectBlocks(m, glm::dmat4(clip), eye, o);
    EXPECT_EQ(s.triangleBlocks.size(), 0u);  // source triangles belong to level 0 alone
    ASSERT_GT(s.voxelBlocks.size(), 0u);
    for (uint32_t i : s.voxelBlocks) EXPECT_EQ(m.blocks[i].level, 1u);
}

/// Renders the scene's depth at 256x256 and returns it (1 where nothing was drawn).
raster::Image renderDepth(lod::VoxelScene& scene, const lod::VoxelRenderOptions& o, lod::VoxelFrameStats* stats = nullptr) {
    raster::Pipeline p;
    raster::FramebufferDesc d;
    d.widthPixels = d.heightPixels = 256;
    p.beginFrame(d);
    const lod::VoxelFrameStats s = scene.draw(p, 256, 256, o);
    p.endFrame();
    if (stats) *stats = s;
    raster::Image depth;
    raster::resolveDepth(p.framebuffer(), depth);
    return depth;
}

class NoCracks : public ::testing::TestWithParam<voxel::Separability> {};

TEST_P(NoCracks, MixedLevelsLeaveNoHoleInsideTheSilhouette) {
    lod::VoxelScene scene(spherePyramid(512, false, GetParam()), 0.0f, 0.0f);
    scene.camera.position = glm::vec3(kCentre) + glm::vec3(0.0f, 0.0f, 3.2f);  // close: levels vary across the sphere
    scene.camera.target = glm::vec3(kCentre);
    scene.camera.verticalFovDegrees = 80.0f;
    scene.camera.nearPlane = 0.01f;
    lod::VoxelRenderOptions o;
    o.selection.pixelError = 3.0f;
    lod::VoxelFrameStats stats;
    const raster::Image depth = renderDepth(scene, o, &stats);
    int levelsDrawn = 0;
    uint32_t coarsest = 0;
    for (uint32_t l = 0; l < stats.selection.drawnPerLevel.size(); ++l)
        if (stats.selection.drawnPerLevel[l]) ++levelsDrawn, coarsest = l;
    ASSERT_GE(levelsDrawn, 2) << "the test needs blocks of several levels side by side";
    // Every pixel whose ray meets the sphere shrunk by the coarsest drawn voxel's diagonal (and the
    // mesh's faceting) must be covered.
    const double shrink = scene.model().grid.voxelSize() * double(1u << coarsest) * std::sqrt(3.0) + 0.01 * kRadius;
    const glm::mat4 inverse = glm::inverse(scene.camera.clipFromWorld(1.0f));
    int inside = 0, holes = 0;
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 256; ++x) {
            const glm::vec4 ndc((x + 0.5f) / 128.0f - 1.0f, 1.0f - (y + 0.5f) / 128.0f, 1.0f, 1.0f);
            glm::vec4 far = inverse * ndc;
            const glm::dvec3 dir = glm::normalize(glm::dvec3(far / far.w) - glm::dvec3(scene.camera.position));
            const glm::dvec3 oc = glm::dvec3(scene.camera.position) - kCentre;
            const double b = glm::dot(oc, dir), c = glm::dot(oc, oc) - (kRadius - shrink) * (kRadius - shrink);
            if (b * b - c <= 0.0) continue;
            ++inside;
            holes += depth.rgba[(size_t(y) * 256 + x) * 4] >= 1.0f;
        }
    EXPECT_GT(inside, 5000);
    EXPECT_EQ(holes, 0);
}

INSTANTIATE_TEST_SUITE_P(Separability, NoCracks,
                         ::testing::Values(voxel::Separability::Conservative, voxel::Separability::Six));

/// A big sphere with a small one hidden behind it (seen from +z), as one model.
voxel::VoxelModel twoSpheres() {
    std::mt19937 rng(4);
    auto tris = testing::icosphere(4, kCentre, kRadius, testing::randomRotation(rng));
    const auto small = testing::icosphere(3, kCentre + glm::dvec3(0.2, 0.0, -3.5), 0.6, testing::randomRotation(rng));
    tris.insert(tris.end(), small.begin(), small.end());
    std::vector<glm::vec3> colors;
    for (size_t i = 0; i < tris.size(); ++i) colors.push_back(glm::vec3(float(i % 7) / 6.0f, 0.5f, float(i % 3) / 2.0f));
    voxel::VoxelizeOptions o;
    o.resolution = 512;
    voxel::VoxelModel m = voxel::voxelizeMesh(*testing::viewOf(tris, 1000, colors), o);
    lod::buildLodPyramid(m, {});
    return m;
}

/// The scene's frame at 240x160; `drawnFirst`, when given, is drawn into the frame before the voxels.
std::vector<float> renderColor(lod::VoxelScene& scene, const lod::VoxelRenderOptions& o, lod::VoxelFrameStats* stats,
                               int samples = 4, const raster::DrawCall* drawnFirst = nullptr) {
    raster::Pipeline p;
    raster::FramebufferDesc d;
    d.widthPixels = 240, d.heightPixels = 160, d.samples = samples;
    d.depthConvention = scene.camera.reversedDepth ? raster::DepthConvention::Reversed : raster::DepthConvention::Standard;
    p.beginFrame(d);
    if (drawnFirst) p.draw(*drawnFirst);
    const lod::VoxelFrameStats s = scene.draw(p, 240, 160, o);
    p.endFrame();
    if (!o.viewFrom) scene.readOcclusion(p.stats());
    if (stats) *stats = s;
    raster::Image image;
    raster::resolveColor(p.framebuffer(), image);
    return {image.rgba.begin(), image.rgba.end()};
}

TEST(Occlusion, ConvergedImageEqualsTheImageWithoutCulling) {
    const voxel::VoxelModel model = twoSpheres();
    struct View {
        const char* name;
        glm::vec3 eye, target;
    };
    const glm::vec3 c(kCentre);
    const View views[] = {
        {"front: the small sphere hidden", c + glm::vec3(0.3f, 0.2f, 9.0f), c},
        {"side: both visible", c + glm::vec3(9.0f, 1.0f, -1.5f), c + glm::vec3(0, 0, -1.5f)},
        {"grazing along the surface", c + glm::vec3(0.0f, 2.05f, 6.0f), c + glm::vec3(0.0f, 2.0f, -6.0f)},
        {"inside the big sphere", c + glm::vec3(0.5f, 0.1f, 0.3f), c + glm::vec3(0, 0, -3.5f)},
        {"far away", c + glm::vec3(-30.0f, 20.0f, 40.0f), c},
    };
    uint64_t culledSomewhere = 0;
    for (const View& v : views) {
        lod::VoxelScene culled(model, 0, 0), reference(model, 0, 0);
        for (lod::VoxelScene* s : {&culled, &reference}) {
            s->camera.position = v.eye;
            s->camera.target = v.target;
            s->camera.nearPlane = 0.01f;
            s->camera.farPlane = 200.0f;
        }
        lod::VoxelRenderOptions with, without;
        with.selection.pixelError = without.selection.pixelError = 2.0f;
        without.occlusion = false;
        const std::vector<float> want = renderColor(reference, without, nullptr);
        lod::VoxelFrameStats stats;
        std::vector<float> got;
        for (int frame = 0; frame < 4; ++frame) {
            got = renderColor(culled, with, &stats);
            EXPECT_EQ(got, want) << v.name << ", frame " << frame;  // never a visible difference, converged or not
        }
        culledSomewhere += stats.occlusionCulled;
        if (std::string(v.name).starts_with("front")) {
            EXPECT_GT(stats.occlusionCulled, 0u) << "the hidden sphere's blocks are culled";
            EXPECT_GT(stats.visibilityTests, 0u);
        }
    }
    EXPECT_GT(culledSomewhere, 0u);
}

// Clearing the faces with a voxel across them (lod/lod_pyramid.h) draws far fewer faces and
// changes almost no pixel. A pixel can change: a face cleared behind a neighbour whose own face
// toward the camera is not active (its surface normal turned away from that side) had shown
// through that gap, and now what lies behind shows instead.
TEST(HiddenFaces, ClearingThemDrawsFewerFacesAndLeavesTheImageAsItWas) {
    const voxel::VoxelModel cleared = spherePyramid(512, false), kept = spherePyramid(512, false, voxel::Separability::Conservative,
                                                                                         {.clearHiddenFaces = false});
    const glm::dvec3 eyes[] = {{0.4, 0.3, 7.0}, {6.0, 2.5, -1.0}, {-3.0, -4.0, 3.5}, {0.2, 2.3, 0.4}};
    size_t differing = 0, pixels = 0;
    uint64_t facesCleared = 0, facesKept = 0;
    for (const glm::dvec3& eye : eyes) {
        std::vector<float> images[2];
        for (int i = 0; i < 2; ++i) {
            lod::VoxelScene scene(i == 0 ? cleared : kept, 0.0f, 0.0f);
            scene.camera = cameraAt(eye);
            lod::VoxelRenderOptions o;
            o.occlusion = false;
            lod::VoxelFrameStats stats;
            images[i] = renderColor(scene, o, &stats);
            (i == 0 ? facesCleared : facesKept) += stats.facesEmitted;
        }
        for (size_t p = 0; p < images[0].size(); p += 4, ++pixels)
            differing += !std::equal(images[0].begin() + long(p), images[0].begin() + long(p) + 4, images[1].begin() + long(p));
    }
    // Measured: 1.16M faces against 3.15M (37%).
    EXPECT_LT(double(facesCleared), 0.45 * double(facesKept)) << facesCleared << " against " << facesKept;
    // Measured: 123 of 153,600 pixels (0.08%) over the four views; the bound is 2.5 times that, so
    // a clearing that opened holes would fail.
    EXPECT_LE(double(differing), 0.002 * double(pixels)) << differing << " of " << pixels << " pixels differ";
}

// Faces that cover no sample are left out before they become vertices (voxel::SampleFootprint);
// the rasterizer would have dropped each of them, so every pixel of every sample count stays the
// same bits: far (sub-pixel voxels, most faces left out), near, grazing, crossing the near plane
// (kept whole), and with the occlusion tests, whose answers the left-out faces could not change.
TEST(VoxelFootprint, LeavingOutFacesBetweenSamplesLeavesTheImageBitForBit) {
    const voxel::VoxelModel model = spherePyramid(512);
    const glm::dvec3 eyes[] = {{0.4, 0.3, 40.0}, {0.4, 0.3, 7.0}, {6.0, 2.5, -1.0}, {0.3, 2.35, 0.2}, {0.3, 0.1, 2.2}};
    uint64_t leftOut = 0, behind = 0, drawn = 0, drawnWithout = 0, farLeftOut = 0, farDrawn = 0;
    uint64_t leftOutAtSeveralSamples = 0;
    for (const glm::dvec3& eye : eyes)
        for (int samples : {1, 4, 16})
            for (bool occlusion : {false, true}) {
                SCOPED_TRACE(::testing::Message() << "eye " << eye.x << "," << eye.y << "," << eye.z << ", " << samples
                                                  << " samples, occlusion " << occlusion);
                std::vector<float> images[2];
                for (int i = 0; i < 2; ++i) {
                    lod::VoxelScene scene(model, 0.0f, 0.0f);
                    scene.camera = cameraAt(eye);
                    lod::VoxelRenderOptions o;
                    o.occlusion = occlusion;
                    o.leaveOutFacesBetweenSamples = i == 0;
                    lod::VoxelFrameStats stats;
                    for (int frame = 0; frame < (occlusion ? 2 : 1); ++frame) images[i] = renderColor(scene, o, &stats, samples);
                    (i == 0 ? drawn : drawnWithout) += stats.facesEmitted;
                    if (i == 0) leftOut += stats.facesBetweenSamples, behind += stats.facesBehindDepth;
                    if (i == 0 && samples > 1) leftOutAtSeveralSamples += stats.facesBetweenSamples;
                    if (i == 0 && eye == eyes[0] && samples == 1)
                        farLeftOut += stats.facesBetweenSamples, farDrawn += stats.facesEmitted;
                }
                EXPECT_EQ(images[0], images[1]);
            }
    EXPECT_EQ(drawn + leftOut + behind, drawnWithout);  // voxels behind the depth are tested only with a footprint
    EXPECT_GT(farLeftOut, 0u);
    EXPECT_GT(farLeftOut, farDrawn) << "far away, at one sample, most faces fall between samples";
    // Faces are searched at every sample count (only smaller ones at more samples: kSearchedFacePixels),
    // so the images above hold the multisample search to the same bits too.
    EXPECT_GT(leftOutAtSeveralSamples, 0u);
}

// A block straddling the viewport's edge holds voxels outside it, which expansion leaves out
// before looking at their faces; the image stays the same bits along every edge of the frame, at
// 1 and 4 samples (at 4, faces of a pixel are not searched, so the viewport test is most of what
// is left out).
TEST(VoxelFootprint, VoxelsOutsideTheViewportAreLeftOutBitForBit) {
    const voxel::VoxelModel model = spherePyramid(512, false);
    // The sphere pushed against each corner of the frame in turn: it crosses two edges each time.
    const glm::dvec3 offsets[] = {{1.9, 1.3, 0.0}, {-1.9, 1.3, 0.0}, {1.9, -1.3, 0.0}, {-1.9, -1.3, 0.0}};
    uint64_t leftOutAtFourSamples = 0;
    for (const glm::dvec3& offset : offsets)
        for (int samples : {1, 4}) {
            SCOPED_TRACE(::testing::Message() << "offset " << offset.x << "," << offset.y << ", " << samples << " samples");
            std::vector<float> images[2];
            for (int i = 0; i < 2; ++i) {
                lod::VoxelScene scene(model, 0.0f, 0.0f);
                scene.camera = cameraAt({0.4, 0.3, 6.0});
                scene.camera.target = glm::vec3(kCentre + offset);
                lod::VoxelRenderOptions o;
                o.occlusion = false;
                o.leaveOutFacesBetweenSamples = i == 0;
                lod::VoxelFrameStats stats;
                images[i] = renderColor(scene, o, &stats, samples);
                if (i == 0 && samples == 4) leftOutAtFourSamples += stats.facesBetweenSamples;
                if (i == 0) {
                    EXPECT_EQ(stats.triangleBlocksDrawn, 0u) << "the test is about voxel faces";
                }
            }
            EXPECT_EQ(images[0], images[1]);
        }
    EXPECT_GT(leftOutAtFourSamples, 0u);
}

/// A voxel frame drawn with voxels behind the depth drawn before left out ([0]) and without ([1]),
/// the last of `frames` (the occlusion tests learn from the frame before), and its statistics.
struct WithAndWithout {
    std::vector<float> image[2];
    lod::VoxelFrameStats stats[2];
};
WithAndWithout renderWithAndWithoutDepthTest(const voxel::VoxelModel& model, const scene::Camera& camera,
                                             lod::VoxelRenderOptions o, int samples, int frames = 1,
                                             const raster::DrawCall* drawnFirst = nullptr) {
    WithAndWithout r;
    for (int i = 0; i < 2; ++i) {
        lod::VoxelScene scene(model, 0.0f, 0.0f);
        scene.camera = camera;
        o.leaveOutVoxelsBehindDepth = i == 0;
        for (int frame = 0; frame < frames; ++frame)
            r.image[i] = renderColor(scene, o, &r.stats[i], samples, drawnFirst);
    }
    return r;
}

/// A model seen from an eye (looking at its centre, cameraAt).
struct ModelView {
    const voxel::VoxelModel* model;
    glm::dvec3 eye;
};

// Voxels behind what earlier chunks of the frame drew are left out before they become faces
// (voxel::DepthFootprint); no sample of theirs could pass the depth test, so every pixel of every
// sample count stays the same bits: the sphere seen through its own far side from afar, near,
// grazing, and crossing the near plane; the two spheres, one hidden behind the other; with the
// occlusion tests (whose sample counts the left-out voxels could not change) and without; chunks
// of a few hundred voxels, so many flushes fall inside each frame, and in standard and reversed
// depth.
TEST(VoxelHiddenDepth, LeavingOutVoxelsBehindDrawnDepthLeavesTheImageBitForBit) {
    const voxel::VoxelModel sphere = spherePyramid(512), spheres = twoSpheres();
    const ModelView views[] = {{&sphere, {0.4, 0.3, 40.0}}, {&sphere, {0.4, 0.3, 7.0}}, {&sphere, {6.0, 2.5, -1.0}},
                               {&sphere, {0.3, 2.35, 0.2}}, {&sphere, {0.3, 0.1, 2.2}}, {&spheres, {0.5, 0.3, 9.0}}};
    uint64_t behind = 0, drawn = 0, drawnWithout = 0, betweenWith = 0, betweenWithout = 0;
    for (const ModelView& view : views)
        for (int samples : {1, 4, 16})
            for (bool occlusion : {false, true})
                for (bool reversed : {false, true}) {
                    SCOPED_TRACE(::testing::Message() << "eye " << view.eye.x << "," << view.eye.y << "," << view.eye.z << ", "
                                                      << samples << " samples, occlusion " << occlusion << ", reversed " << reversed);
                    scene::Camera camera = cameraAt(view.eye);
                    camera.reversedDepth = reversed;
                    lod::VoxelRenderOptions o;
                    o.occlusion = occlusion;
                    o.voxelsPerExpansionChunk = 300;
                    const WithAndWithout r = renderWithAndWithoutDepthTest(*view.model, camera, o, samples, occlusion ? 2 : 1);
                    drawn += r.stats[0].facesEmitted, drawnWithout += r.stats[1].facesEmitted;
                    betweenWith += r.stats[0].facesBetweenSamples, betweenWithout += r.stats[1].facesBetweenSamples;
                    behind += r.stats[0].facesBehindDepth;
                    EXPECT_EQ(r.image[0], r.image[1]);
                }
    // Every camera-facing face is drawn, between samples or behind: the three add up.
    EXPECT_EQ(drawn + behind + betweenWith, drawnWithout + betweenWithout);
    // Measured: 363,154 faces left out behind, of 2,016,392 drawn without (18%); half that fails
    // a cull that no longer reaches the far side.
    EXPECT_GT(double(behind), 0.09 * double(drawnWithout)) << behind << " of " << drawnWithout;
}

// The same property over cameras drawn at random around both models: any direction, from
// grazing the surface to far away, looking anywhere near the centre, either depth convention.
TEST(VoxelHiddenDepth, RandomViewsGiveTheSameImageWithAndWithoutIt) {
    const voxel::VoxelModel sphere = spherePyramid(512), spheres = twoSpheres();
    std::mt19937 rng(2026);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), distance(2.05, 30.0);
    uint64_t behind = 0;
    for (int view = 0; view < 24; ++view) {
        glm::dvec3 direction;
        do direction = {unit(rng), unit(rng), unit(rng)};
        while (glm::length(direction) < 0.1 || glm::length(direction) > 1.0);
        const double d = distance(rng);
        const glm::dvec3 eye = kCentre + glm::normalize(direction) * d;
        const glm::dvec3 target = kCentre + 0.5 * glm::dvec3(unit(rng), unit(rng), unit(rng));
        const int samples = view % 3 == 0 ? 4 : 1;
        const bool reversed = view % 2 == 1;
        SCOPED_TRACE(::testing::Message() << "view " << view << ": eye " << eye.x << "," << eye.y << "," << eye.z);
        scene::Camera camera = cameraAt(eye);
        camera.target = glm::vec3(target);
        camera.reversedDepth = reversed;
        lod::VoxelRenderOptions o;
        o.occlusion = false;
        o.voxelsPerExpansionChunk = 200;
        const WithAndWithout r = renderWithAndWithoutDepthTest(view % 4 == 3 ? spheres : sphere, camera, o, samples);
        behind += r.stats[0].facesBehindDepth;
        EXPECT_EQ(r.image[0], r.image[1]);
    }
    EXPECT_GT(behind, 0u);
}

// Where the decision is close: a wall drawn before the voxels (the first chunk is tested against
// what the frame drew before it) cuts through the sphere, so voxels lie just behind it (left out)
// and just in front of it (kept), at every depth along the cut; voxels of about a pixel and of
// several. The frame with the test is the frame without it, bit for bit; a margin of -1e-5 in
// place of hiddenDepthMargin's fails here (the views above never put a voxel that close).
TEST(VoxelHiddenDepth, VoxelsAroundAWallDrawnFirstAreLeftOutOnlyBehindIt) {
    const voxel::VoxelModel sphere = spherePyramid(512);
    std::mt19937 rng(77);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    uint64_t behind = 0, drawn = 0;
    for (int view = 0; view < 12; ++view) {
        const glm::dvec3 eye = kCentre + glm::dvec3(2.5 * unit(rng), 2.5 * unit(rng), 7.0 + 2.0 * unit(rng));
        glm::dvec3 normal(unit(rng), unit(rng), 1.5);  // the wall faces the camera, tilted
        normal = glm::normalize(normal);
        const glm::dvec3 u = glm::normalize(glm::cross(normal, glm::dvec3(0.3, 1.0, 0.1))), v = glm::cross(normal, u);
        const glm::dvec3 middle = kCentre + normal * (0.5 * unit(rng)) + u * (1.5 * unit(rng));
        // Half the view: the wall's edge runs through the sphere too.
        const std::vector<glm::vec3> wall = {glm::vec3(middle - 6.0 * v), glm::vec3(middle + 6.0 * u - 6.0 * v),
                                             glm::vec3(middle + 6.0 * u + 6.0 * v), glm::vec3(middle - 6.0 * v),
                                             glm::vec3(middle + 6.0 * u + 6.0 * v), glm::vec3(middle + 6.0 * v)};
        const std::vector<glm::vec4> wallColors(2, glm::vec4(0.2f, 0.6f, 0.3f, 1.0f));
        const int samples = view % 3 == 0 ? 4 : 1;
        const bool reversed = view % 2 == 1;
        SCOPED_TRACE(::testing::Message() << "view " << view);
        scene::Camera camera = cameraAt(eye);
        camera.reversedDepth = reversed;
        raster::DrawCall d;
        d.clipFromObject = camera.clipFromWorld(240.0f / 160.0f);
        d.positions = wall;
        d.triangleColors = wallColors;
        lod::VoxelRenderOptions o;
        o.occlusion = false;
        o.voxelsPerExpansionChunk = 2000;
        o.selection.pixelError = view % 2 ? 1.0f : 4.0f;  // voxels of a pixel, and of several: straddling 8x8 blocks
        const WithAndWithout r = renderWithAndWithoutDepthTest(sphere, camera, o, samples, 1, &d);
        behind += r.stats[0].facesBehindDepth, drawn += r.stats[0].facesEmitted;
        EXPECT_EQ(r.image[0], r.image[1]);
    }
    // Measured: about a fifth as many faces left out behind the wall as drawn.
    EXPECT_GT(behind, drawn / 10) << behind << " left out behind, " << drawn << " drawn";
}

// The far side of a block lies behind its near side, and a block is drawn in one chunk: the
// frame's depth footprint, made from the chunks before, cannot see that; the block's own test
// (voxels front to back, each recording the farthest key it surely writes at the samples its
// faces cover) leaves the far side out. Every pixel of every sample count stays the same bits
// with and without it, in standard and reversed depth, from afar (coarse blocks holding both
// sides of the sphere), near, grazing, inside the sphere's bounds, and on the two spheres; and it
// leaves out faces the frame's depth alone does not.
TEST(VoxelHiddenDepth, FarSideOfABlockIsLeftOutBehindItsNearSideBitForBit) {
    const voxel::VoxelModel sphere = spherePyramid(512), spheres = twoSpheres();
    const ModelView views[] = {{&sphere, {0.4, 0.3, 40.0}}, {&sphere, {0.4, 0.3, 7.0}}, {&sphere, {6.0, 2.5, -1.0}},
                               {&sphere, {0.3, 2.35, 0.2}}, {&sphere, {0.3, 0.1, 1.2}}, {&spheres, {0.5, 0.3, 9.0}}};
    uint64_t behindFrameDepth = 0, behindBoth = 0, drawnWithout = 0;
    for (const ModelView& view : views)
        for (int samples : {1, 4, 16})
            for (bool reversed : {false, true}) {
                SCOPED_TRACE(::testing::Message() << "eye " << view.eye.x << "," << view.eye.y << "," << view.eye.z << ", "
                                                  << samples << " samples, reversed " << reversed);
                scene::Camera camera = cameraAt(view.eye);
                camera.reversedDepth = reversed;
                lod::VoxelRenderOptions o;
                o.occlusion = false;
                o.voxelsPerExpansionChunk = 2000;
                o.leaveOutVoxelsBehindTheirBlock = false;
                const WithAndWithout frameDepth = renderWithAndWithoutDepthTest(*view.model, camera, o, samples);
                o.leaveOutVoxelsBehindTheirBlock = true;
                const WithAndWithout both = renderWithAndWithoutDepthTest(*view.model, camera, o, samples);
                EXPECT_EQ(both.image[0], both.image[1]);
                EXPECT_EQ(frameDepth.image[0], both.image[1]);
                // Every camera-facing face is drawn, between samples or behind.
                EXPECT_EQ(both.stats[0].facesEmitted + both.stats[0].facesBehindDepth + both.stats[0].facesBetweenSamples,
                          both.stats[1].facesEmitted + both.stats[1].facesBetweenSamples);
                EXPECT_GE(both.stats[0].facesBehindDepth, frameDepth.stats[0].facesBehindDepth);
                behindFrameDepth += frameDepth.stats[0].facesBehindDepth, behindBoth += both.stats[0].facesBehindDepth;
                drawnWithout += both.stats[1].facesEmitted;
            }
    // Measured: 74,034 more faces left out (203,560 -> 277,594) of 1,040,666 drawn without either
    // test (7.1%); most of the sphere's far side lies in later chunks, which the frame's depth sees.
    EXPECT_GT(double(behindBoth - behindFrameDepth), 0.05 * double(drawnWithout))
        << behindFrameDepth << " and " << behindBoth << " left out behind, of " << drawnWithout;
}

// A block's source triangles are indexed for drawing the first time a frame draws them, not when
// the model is loaded (lod::ModelBlocks): a far view indexes none; a near view indexes the blocks
// it draws as triangles, and draws the same image as a scene that indexed them in an earlier frame.
TEST(SourceTriangles, AreIndexedOnlyForTheBlocksAFrameDraws) {
    const voxel::VoxelModel model = spherePyramid(256);
    auto blocksStillRaw = [](const lod::VoxelScene& s) {
        size_t raw = 0;
        for (const voxel::VoxelBlock& b : s.model().blocks) raw += !b.triangles.empty();
        return raw;
    };
    size_t withTriangles = 0;
    for (const voxel::VoxelBlock& b : model.blocks) withTriangles += !b.triangles.empty();
    ASSERT_GT(withTriangles, 0u);
    const glm::dvec3 far(0.4, 0.3, 40.0), near(0.3, 0.1, 2.05);  // the surface is 0.25 from `near`
    lod::VoxelRenderOptions o;
    o.occlusion = false;
    lod::VoxelFrameStats stats;

    lod::VoxelScene farFirst(model, 0.0f, 0.0f);
    farFirst.camera = cameraAt(far);
    renderColor(farFirst, o, &stats);
    EXPECT_EQ(stats.triangleBlocksDrawn, 0u);
    EXPECT_EQ(blocksStillRaw(farFirst), withTriangles);

    farFirst.camera = cameraAt(near);
    const std::vector<float> nearAfterFar = renderColor(farFirst, o, &stats);
    ASSERT_GT(stats.triangleBlocksDrawn, 0u);
    EXPECT_EQ(blocksStillRaw(farFirst), withTriangles - stats.triangleBlocksDrawn);
    const std::vector<float> nearAgain = renderColor(farFirst, o, &stats);  // drawn from what was indexed

    lod::VoxelScene nearFirst(model, 0.0f, 0.0f);
    nearFirst.camera = cameraAt(near);
    EXPECT_EQ(renderColor(nearFirst, o, nullptr), nearAfterFar);
    EXPECT_EQ(nearAgain, nearAfterFar);
}

TEST(Occlusion, VisibilityViewShowsNoCulledBlockFromTheMainCamera) {
    // The culled blocks are drawn in red after everything else: none may show.
    const voxel::VoxelModel model = twoSpheres();
    lod::VoxelScene culled(model, 0, 0), reference(model, 0, 0);
    for (lod::VoxelScene* s : {&culled, &reference}) {
        s->camera.position = glm::vec3(kCentre) + glm::vec3(0.3f, 0.2f, 9.0f);
        s->camera.target = glm::vec3(kCentre);
    }
    lod::VoxelRenderOptions with, without;
    with.coloring = without.coloring = lod::BlockColoring::Visibility;
    without.occlusion = false;
    const std::vector<float> want = renderColor(reference, without, nullptr);
    lod::VoxelFrameStats stats;
    for (int frame = 0; frame < 3; ++frame) EXPECT_EQ(renderColor(culled, with, &stats), want) << "frame " << frame;
    EXPECT_GT(stats.occlusionCulled, 0u);
    // Seen from the debug camera, the culled blocks do show.
    const scene::Camera debug = lod::debugCameraFor(culled.camera);
    with.viewFrom = &debug;
    without.viewFrom = &debug;
    EXPECT_NE(renderColor(culled, with, nullptr), renderColor(reference, without, nullptr));
}

TEST(VoxelDeterminism, SameFrameForAnyThreadCount) {
    lod::VoxelScene scene(spherePyramid(256), 30.0f, 20.0f);
    lod::VoxelRenderOptions o;
    o.selection.pixelError = 2.0f;
    auto render = [&](testing::ThreadCount count) {
        const testing::ThreadCountScope scope(count);
        raster::Pipeline p;
        raster::FramebufferDesc d;
        d.widthPixels = 200, d.heightPixels = 150, d.samples = 4;
        p.beginFrame(d);
        scene.draw(p, 200, 150, o);
        p.endFrame();
        raster::Image image;
        raster::resolveColor(p.framebuffer(), image);
        if (count.exact) { EXPECT_EQ(scope.ran(), count.threads) << "threads that ran"; }
        return image.rgba;
    };
    const auto one = render(testing::kThreadCounts[0]);
    EXPECT_EQ(one, render(testing::kThreadCounts[1]));
    EXPECT_EQ(one, render(testing::kThreadCounts[2]));
}

}  // namespace
}  // namespace cuberille
