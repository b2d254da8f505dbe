// The shadow stage wired to an animated scene (render/scene_shadows.h): its hierarchy follows the
// casters from pose to pose by refitting, is rebuilt when Lauterbach's criterion says so, and
// the masks it gives are those of a stage built fresh on the same pose, pixel for pixel.

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "render/scene_shadows.h"

namespace cuberille {
namespace {

constexpr int kWidth = 96, kHeight = 72;

/// A ground quad under a sheet of small triangles (a 12 x 12 grid, two triangles a cell, each
/// with its own three vertices) held up over it, a sun from above and to the side, a camera
/// looking down at both. `pose` moves each sheet triangle's vertices, given the triangle's index.
template <class Pose>
scene::Scene sheetOverGround(Pose pose) {
    scene::Scene s;
    scene::Mesh ground;
    ground.positions = {{-4, 0, -4}, {4, 0, -4}, {4, 0, 4}, {-4, 0, 4}};
    ground.normals.assign(4, glm::vec3(0, 1, 0));
    ground.indices = {0, 2, 1, 0, 3, 2};
    ground.doubleSided = true;
    s.meshes.push_back(ground);
    scene::Mesh sheet;
    constexpr int n = 12;
    auto corner = [](int i, int j) { return glm::vec3(-1.5f + 3.0f * float(i) / n, 1.0f, -1.5f + 3.0f * float(j) / n); };
    auto triangle = [&](const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
        const uint32_t t = uint32_t(sheet.indices.size() / 3);
        for (const glm::vec3& p : {a, b, c}) {
            sheet.indices.push_back(uint32_t(sheet.positions.size()));
            sheet.positions.push_back(pose(p, t));
        }
    };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            triangle(corner(i, j), corner(i, j + 1), corner(i + 1, j));
            triangle(corner(i + 1, j), corner(i, j + 1), corner(i + 1, j + 1));
        }
    sheet.normals.assign(sheet.positions.size(), glm::vec3(0, 1, 0));
    sheet.doubleSided = true;
    s.meshes.push_back(sheet);
    s.camera.position = {0, 7, 5};
    s.camera.target = {0, 0, 0};
    s.lighting = raster::Lighting::directional(glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)), glm::vec3(1.0f), glm::vec3(0.1f));
    return s;
}

glm::vec3 still(const glm::vec3& p, uint32_t) { return p; }
glm::vec3 slid(const glm::vec3& p, uint32_t) { return p + glm::vec3(0.7f, 0.2f, -0.4f); }
/// Every triangle thrown its own way (a hash of its index), as in BvhRefit's exploding soup:
/// neighbours part, and boxes built around the first pose balloon.
glm::vec3 exploded(const glm::vec3& p, uint32_t t) {
    auto unit = [](uint32_t h) { return float((h * 2654435761u) >> 8) / float(1u << 24) * 2.0f - 1.0f; };
    return p + 2.0f * glm::vec3(unit(t * 3 + 1), 0.4f * (unit(t * 3 + 2) + 1.0f), unit(t * 3 + 3));
}

std::vector<float> mask(render::SceneShadows& stage, const scene::Scene& s, render::ShadowFrameStats& stats) {
    const raster::Lighting lit = stage.run(s, kWidth, kHeight, stats);
    return {lit.lights[0].visibility, lit.lights[0].visibility + size_t(kWidth) * kHeight};
}

size_t shadowedPixels(const std::vector<float>& m) {
    size_t n = 0;
    for (const float v : m) n += v < 1.0f;
    return n;
}

class AnimatedShadows : public ::testing::TestWithParam<rt::ShadowMode> {
protected:
    rt::ShadowOptions options() const {
        rt::ShadowOptions o;
        o.mode = GetParam();
        o.mapSizeTexels = 256;
        return o;
    }
};

TEST_P(AnimatedShadows, RigidMotionIsRefittedAndShadowsAsAFreshStage) {
    const scene::Scene first = sheetOverGround(still), next = sheetOverGround(slid);
    render::SceneShadows stage(first, options());
    render::ShadowFrameStats stats;
    const std::vector<float> before = mask(stage, first, stats);
    EXPECT_FALSE(stats.bvhUpdated) << "the first frame builds";
    stage.update(next);
    const std::vector<float> after = mask(stage, next, stats);
    EXPECT_TRUE(stats.bvhUpdated);
    EXPECT_FALSE(stats.bvhRebuilt) << "a translation leaves every box's shape as it was";
    EXPECT_LT(stats.degradation, 0.05);
    render::SceneShadows fresh(next, options());
    render::ShadowFrameStats freshStats;
    EXPECT_EQ(after, mask(fresh, next, freshStats)) << "a refitted hierarchy finds the same occluders";
    EXPECT_NE(before, after) << "the sheet's shadow moved";
    EXPECT_GT(shadowedPixels(after), size_t(kWidth * kHeight / 50)) << "the sheet shadows the ground";
    EXPECT_FALSE(freshStats.bvhUpdated);
    stage.update(next);  // stats are per frame: a second update reports again, then nothing
    mask(stage, next, stats);
    EXPECT_TRUE(stats.bvhUpdated);
    mask(stage, next, stats);
    EXPECT_FALSE(stats.bvhUpdated);
}

TEST_P(AnimatedShadows, AnExplodingMeshRebuildsAndShadowsAsAFreshStage) {
    const scene::Scene first = sheetOverGround(still), next = sheetOverGround(exploded);
    render::SceneShadows stage(first, options());
    render::ShadowFrameStats stats;
    mask(stage, first, stats);
    stage.update(next);
    const std::vector<float> after = mask(stage, next, stats);
    EXPECT_TRUE(stats.bvhRebuilt) << "degradation " << stats.degradation;
    EXPECT_GT(stats.degradation, 0.4);
    render::SceneShadows fresh(next, options());
    render::ShadowFrameStats freshStats;
    EXPECT_EQ(after, mask(fresh, next, freshStats));
}

TEST_P(AnimatedShadows, AMovedCameraAndANewSizeGetTheMasksOfAFreshStage) {
    // The stage keeps its visibility buffer's per-pose data and its masks' storage between
    // frames; nothing of one frame may leak into the next.
    scene::Scene s = sheetOverGround(still);
    render::SceneShadows stage(s, options());
    render::ShadowFrameStats stats;
    mask(stage, s, stats);
    s.camera.position = {5, 3, -4};
    const raster::Lighting moved = stage.run(s, kWidth / 2, kHeight + 8, stats);
    render::SceneShadows fresh(s, options());
    render::ShadowFrameStats freshStats;
    const raster::Lighting reference = fresh.run(s, kWidth / 2, kHeight + 8, freshStats);
    const size_t pixels = size_t(kWidth / 2) * (kHeight + 8);
    EXPECT_EQ(std::vector<float>(moved.lights[0].visibility, moved.lights[0].visibility + pixels),
              std::vector<float>(reference.lights[0].visibility, reference.lights[0].visibility + pixels));
    EXPECT_EQ(stats.shadows.receiverPixels, freshStats.shadows.receiverPixels);
    EXPECT_EQ(stats.shadows.markedPixels, freshStats.shadows.markedPixels);
    EXPECT_EQ(stage.markedPixels(), fresh.markedPixels());
}

TEST_P(AnimatedShadows, ChangedTrianglesAreRefused) {
    scene::Scene first = sheetOverGround(still), next = sheetOverGround(slid);
    next.meshes[1].indices.resize(next.meshes[1].indices.size() - 3);
    render::SceneShadows stage(first, options());
    EXPECT_THROW(stage.update(next), std::runtime_error);
}

TEST_P(AnimatedShadows, EveryUpdateMethodGivesTheMasksOfAFreshStage) {
    // Larsson's lazy update leaves the lower boxes stale until a ray reaches them; the rays must
    // still meet exactly the occluders of a tree built on the pose, frame after frame.
    const scene::Scene first = sheetOverGround(still);
    for (const rt::BvhUpdateMethod method : {rt::BvhUpdateMethod::Refit, rt::BvhUpdateMethod::Lazy, rt::BvhUpdateMethod::Rebuild}) {
        render::SceneShadows stage(first, options(), method);
        render::ShadowFrameStats stats;
        mask(stage, first, stats);
        for (int frame = 1; frame <= 3; ++frame) {
            const float step = 0.3f * float(frame);
            const scene::Scene pose = sheetOverGround([&](const glm::vec3& p, uint32_t t) {
                return p + glm::vec3(step, 0.1f * step * float(t % 3), -0.5f * step);  // a drift and a ripple
            });
            stage.update(pose);
            const std::vector<float> moved = mask(stage, pose, stats);
            EXPECT_TRUE(stats.bvhUpdated);
            EXPECT_EQ(stats.bvhRebuilt, method == rt::BvhUpdateMethod::Rebuild) << int(method) << " frame " << frame;
            render::SceneShadows fresh(pose, options());
            render::ShadowFrameStats freshStats;
            EXPECT_EQ(moved, mask(fresh, pose, freshStats)) << int(method) << " frame " << frame;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Modes, AnimatedShadows,
                         ::testing::Values(rt::ShadowMode::Hybrid, rt::ShadowMode::RayTraced, rt::ShadowMode::Auto),
                         [](const ::testing::TestParamInfo<rt::ShadowMode>& p) {
                             return p.param == rt::ShadowMode::Hybrid      ? std::string("Hybrid")
                                    : p.param == rt::ShadowMode::RayTraced ? std::string("RayTraced")
                                                                           : std::string("Auto");
                         });


// Maps kept while nothing they depend on moves (issue 27): a point light's cube and a spot light's
// map do not depend on the camera, so a turntable draws them once; a sun's map focused on the
// receivers in view (MapFocus::View) is drawn again when the camera moves, one covering every
// caster (MapFocus::Scene, a turntable's) is kept. Every kept frame's masks are a fresh stage's,
// bit for bit, and a new pose draws every map again.
class KeptMaps : public ::testing::TestWithParam<rt::ShadowMode> {};

TEST_P(KeptMaps, AMapIsKeptWhileTheLightAndCastersStayAndTheMasksAreAFreshStages) {
    struct Case {
        const char* name;
        raster::LightType type;
        rt::MapFocus focus;
        bool keptAcrossCameras;
    };
    for (const Case c : {Case{"point", raster::LightType::Point, rt::MapFocus::View, true},
                         Case{"spot", raster::LightType::Spot, rt::MapFocus::View, true},
                         Case{"directional focused on the view", raster::LightType::Directional, rt::MapFocus::View, false},
                         Case{"directional over the scene", raster::LightType::Directional, rt::MapFocus::Scene, true}}) {
        SCOPED_TRACE(c.name);
        scene::Scene s = sheetOverGround(still);
        raster::Light& light = s.lighting.lights[0];
        light.type = c.type;
        light.position = {0.8f, 4.0f, 0.6f};
        light.direction = glm::normalize(glm::vec3(-0.2f, -1.0f, -0.15f));
        light.cosOuterCone = std::cos(0.9f), light.cosInnerCone = std::cos(0.7f);
        light.range = 0.0f;
        rt::ShadowOptions o;
        o.mode = GetParam();
        o.mapSizeTexels = 256;
        o.focus = c.focus;
        render::SceneShadows stage(s, o);
        render::ShadowFrameStats stats;
        mask(stage, s, stats);
        EXPECT_EQ(stats.shadows.mapsDrawn, 1);
        const std::vector<float> again = mask(stage, s, stats);
        EXPECT_EQ(stats.shadows.mapsKept, 1) << "nothing moved";
        render::SceneShadows fresh(s, o);
        render::ShadowFrameStats freshStats;
        EXPECT_EQ(again, mask(fresh, s, freshStats));
        EXPECT_GT(shadowedPixels(again), 0u);
        for (const glm::vec3 eye : {glm::vec3(5, 3, -4), glm::vec3(-6, 5, 1)}) {  // a turntable's frames
            s.camera.position = eye;
            const std::vector<float> turned = mask(stage, s, stats);
            EXPECT_EQ(stats.shadows.mapsKept, c.keptAcrossCameras ? 1 : 0);
            EXPECT_EQ(stats.shadows.mapsDrawn, c.keptAcrossCameras ? 0 : 1);
            render::SceneShadows reference(s, o);
            EXPECT_EQ(turned, mask(reference, s, freshStats)) << "camera " << eye.x;
        }
        scene::Scene slidScene = sheetOverGround(slid);
        slidScene.lighting = s.lighting, slidScene.camera = s.camera;
        stage.update(slidScene);  // the casters moved: drawn again
        const std::vector<float> moved = mask(stage, slidScene, stats);
        EXPECT_EQ(stats.shadows.mapsDrawn, 1);
        render::SceneShadows reference(slidScene, o);
        EXPECT_EQ(moved, mask(reference, slidScene, freshStats));
    }
}

INSTANTIATE_TEST_SUITE_P(Modes, KeptMaps, ::testing::Values(rt::ShadowMode::Map, rt::ShadowMode::Hybrid),
                         [](const ::testing::TestParamInfo<rt::ShadowMode>& p) {
                             return p.param == rt::ShadowMode::Hybrid ? std::string("Hybrid") : std::string("Map");
                         });

// --shadows auto (issue 27): over hard and soft shadows, every light type, one frame or a
// turntable's worth, small and large maps, auto gives each light hybrid or ray-traced shadows,
// never the inexact map, and its masks are then exactly the chosen mode's (a fresh stage of that
// mode, bit for bit), also after the casters move. The choice reads nothing an earlier frame
// left: the same frame again, on the same stage, chooses and draws the same. Both choices occur
// in the sweep.
TEST(AutoShadows, NeverChoosesAnInexactModeAndGivesTheChosenModesMasks) {
    int hybrid = 0, rayTraced = 0;
    for (const raster::LightType type : {raster::LightType::Directional, raster::LightType::Spot, raster::LightType::Point})
        for (const bool soft : {false, true})
            for (const int sequence : {1, 36})
                for (const int size : {256, 4096}) {
                    SCOPED_TRACE(::testing::Message() << "light " << int(type) << (soft ? ", soft" : ", hard") << ", " << sequence
                                                      << " frames, " << size << " texels");
                    scene::Scene s = sheetOverGround(still);
                    raster::Light& light = s.lighting.lights[0];
                    light.type = type;
                    light.position = {0.8f, 4.0f, 0.6f};
                    light.direction = glm::normalize(glm::vec3(-0.2f, -1.0f, -0.15f));
                    light.cosOuterCone = std::cos(0.9f), light.cosInnerCone = std::cos(0.7f);
                    light.range = 0.0f;
                    rt::ShadowOptions o;
                    o.mode = rt::ShadowMode::Auto;
                    o.soft = soft;
                    o.mapSizeTexels = size;
                    o.sequenceFrames = sequence;
                    render::SceneShadows stage(s, o);
                    render::ShadowFrameStats stats;
                    const std::vector<float> chosen = mask(stage, s, stats);
                    ASSERT_EQ(stats.shadows.autoHybrid + stats.shadows.autoRayTraced, 1);
                    const bool wasHybrid = stats.shadows.autoHybrid == 1;
                    (wasHybrid ? hybrid : rayTraced)++;
                    EXPECT_EQ(stats.shadows.mapsDrawn + stats.shadows.mapsKept, wasHybrid ? 1 : 0) << "a map only for hybrid";
                    rt::ShadowOptions exact = o;
                    exact.mode = wasHybrid ? rt::ShadowMode::Hybrid : rt::ShadowMode::RayTraced;
                    render::SceneShadows reference(s, exact);
                    render::ShadowFrameStats referenceStats;
                    EXPECT_EQ(chosen, mask(reference, s, referenceStats));
                    EXPECT_EQ(mask(stage, s, stats), chosen) << "the same frame again";
                    EXPECT_EQ(stats.shadows.autoHybrid, wasHybrid ? 1 : 0) << "the same choice again";
                    // A new pose: the edge adjacency hybrid needs is this pose's, found again.
                    scene::Scene moved = sheetOverGround(slid);
                    moved.lighting = s.lighting, moved.camera = s.camera;
                    stage.update(moved);
                    const std::vector<float> after = mask(stage, moved, stats);
                    exact.mode = stats.shadows.autoHybrid == 1 ? rt::ShadowMode::Hybrid : rt::ShadowMode::RayTraced;
                    render::SceneShadows movedReference(moved, exact);
                    EXPECT_EQ(after, mask(movedReference, moved, referenceStats)) << "after a new pose";
                }
    EXPECT_GT(hybrid, 0);
    EXPECT_GT(rayTraced, 0);
}

}  // namespace
}  // namespace cuberille
