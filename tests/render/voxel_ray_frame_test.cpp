// A voxel model's ray-traced frame (render/voxel_ray_frame.h): the same bits from every tree and
// thread count; the rasterizer's frame of the same level wherever the two see the same face,
// every other pixel explained (an inactive face, which the rasterizer does not draw, or an edge
// within 1/256 pixel); the tree kept between frames; the options it cannot honour refused.

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include "render/renderer.h"
#include "render/scene_state.h"
#include "rt/primary_rays.h"
#include "scene/input_error.h"
#include "tests/lod/lod_test_support.h"
#include "voxel/packing.h"
#include "voxel/voxel_model.h"

namespace cuberille {
namespace {

class VoxelRayFrame : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        model_ = new voxel::VoxelModel(testing::spherePyramid(128, 5));
        path_ = new std::filesystem::path(testing::writeTemp("_voxel_ray_frame.cvox", testing::cvoxBytes(*model_)));
    }
    static void TearDownTestSuite() {
        std::filesystem::remove(*path_);
        delete path_;
        delete model_;
    }
    static render::FrameSettings frame() {
        render::FrameSettings f;
        f.width = 160;
        f.height = 120;
        f.renderer = render::Renderer::Raytrace;
        f.azimuth = 40.0f;
        f.elevation = 25.0f;
        return f;
    }
    static voxel::VoxelModel* model_;
    static std::filesystem::path* path_;
};
voxel::VoxelModel* VoxelRayFrame::model_ = nullptr;
std::filesystem::path* VoxelRayFrame::path_ = nullptr;

TEST_F(VoxelRayFrame, EveryTreeGivesTheSameBitsAtEveryThreadCount) {
    const render::LoadedScene scene(path_->string());
    for (int msaa : {1, 4}) {
        render::FrameSettings f = frame();
        f.msaa = msaa;
        const render::RenderResult reference = render::render(scene, f);
        ASSERT_TRUE(reference.voxelRays);
        EXPECT_EQ(reference.voxelRays->rays, uint64_t(f.width) * uint64_t(f.height) * uint64_t(msaa));
        EXPECT_GT(reference.voxelRays->hits, reference.voxelRays->rays / 10);  // the sphere fills a sixth of the frame
        for (rt::VoxelStructure tree : {rt::VoxelStructure::Bvh, rt::VoxelStructure::KdTree, rt::VoxelStructure::Octree,
                                        rt::VoxelStructure::WideBvh})
            for (int threads : {1, 2, 7}) {
                SCOPED_TRACE(::testing::Message() << rt::voxelStructureName(tree) << ", " << threads << " threads, " << msaa << " samples");
                const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
                f.voxelAccel = tree;
                const render::RenderResult r = render::render(scene, f);
                EXPECT_EQ(r.image.rgba, reference.image.rgba);
                EXPECT_EQ(r.voxelRays->hits, reference.voxelRays->hits);
            }
    }
}

TEST_F(VoxelRayFrame, KeepsItsTreeWhileTheLevelAndTreeHold) {
    const render::LoadedScene scene(path_->string());
    render::FrameSettings f = frame();
    const render::RenderResult first = render::render(scene, f);
    EXPECT_GT(first.voxelRays->voxels, 0u);
    f.azimuth = 100.0f;  // another view: the same tree
    const render::RenderResult second = render::render(scene, f);
    EXPECT_EQ(second.voxelRays->buildMs, 0.0);
    EXPECT_EQ(second.voxelRays->voxels, first.voxelRays->voxels);
    f.voxelResolution = 64;  // a coarser level: a new tree over fewer voxels
    const render::RenderResult coarser = render::render(scene, f);
    EXPECT_EQ(coarser.voxelRays->level, 1u);
    EXPECT_EQ(coarser.voxelRays->resolution, 64u);
    EXPECT_LT(coarser.voxelRays->voxels, first.voxelRays->voxels);
}

/// The face a pixel-centre ray names: voxel x 6 + face bit (voxel/voxel_model.h), or ~0.
struct FaceTracer {
    std::vector<rt::VoxelCoord> coords;
    std::vector<uint8_t> activeFaces;
    std::optional<rt::VoxelBvh> bvh;
    glm::dvec3 origin;
    double voxelSize;

    explicit FaceTracer(const voxel::VoxelModel& m) : origin(m.grid.origin), voxelSize(m.grid.voxelSize()) {
        for (const voxel::VoxelBlock& b : m.blocks) {
            if (b.level != 0) continue;
            for (size_t i = 0; i < b.voxels.size(); ++i) {
                const glm::uvec3 p = m.gridPosition(b, i);
                coords.push_back({uint16_t(p.x), uint16_t(p.y), uint16_t(p.z)});
                activeFaces.push_back(voxel::voxelFaceMask(b.voxels[i]));
            }
        }
        bvh.emplace(coords);
    }
    /// With `point`, where the ray meets the face, on its plane (grid units).
    uint64_t face(const rt::PrimaryRayCamera& camera, double x, double y, int width, int height,
                  glm::vec3* point = nullptr) const {
        const rt::Ray world = rt::primaryRay(camera, x, y, width, height);
        rt::Ray grid = world;
        grid.origin = glm::vec3((glm::dvec3(world.origin) - origin) / voxelSize);
        grid.direction = glm::vec3(glm::dvec3(world.direction) / voxelSize);
        const rt::VoxelRay ray(grid);
        const rt::VoxelHit h = bvh->trace(ray, {});
        if (!h.hit() || h.axis < 0) return ~0ull;
        if (point) *point = h.entryPoint(ray, coords[h.voxel]);
        return uint64_t(h.voxel) * 6 + uint64_t(2 * h.axis + (ray.farSide[h.axis] ? 0 : 1));
    }
    bool active(uint64_t face) const { return activeFaces[face / 6] & (1u << (face % 6)); }
};

/// Pixels where the ray-traced and rasterized frames of a model's finest level differ by more
/// than one 8-bit level, each explained: its ray meets a face that is not active (the rasterizer
/// draws only active faces), or a ray 1/256 pixel aside meets another face (snapping decides).
struct FrameDifferences {
    int differ = 0, inactive = 0, nearEdge = 0;
};

FrameDifferences compareWithRasterizer(const std::filesystem::path& cvox, const voxel::VoxelModel& model,
                                       std::initializer_list<std::pair<float, float>> azimuthsAndZooms) {
    constexpr double kSnapPixels = 1.0 / 256.0;
    const render::LoadedScene scene(cvox.string());
    const FaceTracer tracer(model);
    FrameDifferences d;
    for (auto [azimuth, zoom] : azimuthsAndZooms) {
        render::FrameSettings traced;
        traced.width = 160;
        traced.height = 120;
        traced.renderer = render::Renderer::Raytrace;
        traced.azimuth = azimuth;
        traced.elevation = 25.0f;
        traced.zoom = zoom;
        render::FrameSettings rasterized = traced;
        rasterized.renderer = render::Renderer::Raster;
        rasterized.pixelError = 0.0f;  // the finest level everywhere, as the ray tracer sees
        rasterized.noHybrid = true;
        const std::vector<uint8_t> a = render::displayPixels(scene, traced, render::render(scene, traced));
        const std::vector<uint8_t> b = render::displayPixels(scene, rasterized, render::render(scene, rasterized));
        const scene::Camera& camera = render::SceneAccess::state(scene).voxel->camera;
        rt::PrimaryRayCamera rays;
        rays.worldFromClip = glm::inverse(glm::dmat4(camera.clipFromWorld(float(traced.width) / float(traced.height))));
        for (int y = 0; y < traced.height; ++y)
            for (int x = 0; x < traced.width; ++x) {
                const size_t i = 4 * (size_t(y) * size_t(traced.width) + size_t(x));
                bool same = true;
                for (int c = 0; c < 3; ++c) same = same && std::abs(int(a[i + c]) - int(b[i + c])) <= 1;
                if (same) continue;
                ++d.differ;
                const double cx = x + 0.5, cy = y + 0.5;
                const uint64_t f = tracer.face(rays, cx, cy, traced.width, traced.height);
                if (f != ~0ull && !tracer.active(f)) {
                    ++d.inactive;
                    continue;
                }
                bool edge = false;
                for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
                    edge = edge || tracer.face(rays, cx + dx * kSnapPixels, cy + dy * kSnapPixels, traced.width, traced.height) != f;
                EXPECT_TRUE(edge) << "pixel " << x << ", " << y << " at azimuth " << azimuth << ", zoom " << zoom
                                  << ": the ray and the rasterizer disagree on an active face away from its edges";
                d.nearEdge += edge ? 1 : 0;
            }
    }
    return d;
}

TEST_F(VoxelRayFrame, ShowsTheRasterizersFacesButWhereAFaceIsInactiveOrAnEdgeIsWithinSnapping) {
    // A closed surface: its exposed faces are active, so only edges differ — measured 15 pixels
    // of 4 x 19,200, from afar and zoomed until voxels are pixels wide.
    const FrameDifferences sphere = compareWithRasterizer(*path_, *model_, {{40.0f, 1.0f}, {200.0f, 1.0f}, {40.0f, 6.0f}, {130.0f, 12.0f}});
    EXPECT_LT(sphere.differ, 4 * 160 * 120 / 1000) << sphere.differ << " pixels differ";
    EXPECT_GT(sphere.nearEdge, 0);
    // A one-sided sheet seen from behind: its voxels' back faces are not active, so the
    // rasterizer shows the background through what the rays see.
    std::vector<testing::Triangle> sheet{{glm::vec3(-2, -2, -1), glm::vec3(2, -2, 1), glm::vec3(2, 2, 1)},
                                         {glm::vec3(-2, -2, -1), glm::vec3(2, 2, 1), glm::vec3(-2, 2, -1)}};
    voxel::VoxelizeOptions o;
    o.resolution = 64;
    voxel::VoxelModel sheetModel = voxel::voxelizeMesh(*testing::viewOf(sheet, 1000), o);
    lod::buildLodPyramid(sheetModel, {});
    const auto sheetPath = testing::writeTemp("_voxel_ray_sheet.cvox", testing::cvoxBytes(sheetModel));
    const FrameDifferences behind = compareWithRasterizer(sheetPath, sheetModel, {{200.0f, 1.0f}});
    std::filesystem::remove(sheetPath);
    EXPECT_GT(behind.inactive, 1000) << behind.differ << " pixels differ, " << behind.inactive << " on inactive faces";
}

TEST_F(VoxelRayFrame, ShadowsAndOcclusionAreTheSameBitsFromEveryTreeAndThreadCount) {
    const render::LoadedScene scene(path_->string());
    render::FrameSettings f = frame();
    f.shadows.mode = rt::ShadowMode::RayTraced;
    f.shadows.soft = true;
    f.shadows.lightRadius = 0.2f;
    f.ambientOcclusion.raysPerPixel = 8;
    const render::RenderResult reference = render::render(scene, f);
    EXPECT_GT(reference.voxelRays->shadowRays, 0u);
    EXPECT_GT(reference.voxelRays->occlusionRays, 0u);
    f.shadows.mode = rt::ShadowMode::None;
    f.ambientOcclusion.raysPerPixel = 0;
    EXPECT_NE(render::render(scene, f).image.rgba, reference.image.rgba);  // the effects show
    f = frame();
    f.shadows = {.mode = rt::ShadowMode::RayTraced, .soft = true, .lightRadius = 0.2f};
    f.ambientOcclusion.raysPerPixel = 8;
    for (rt::VoxelStructure tree : {rt::VoxelStructure::KdTree, rt::VoxelStructure::Octree, rt::VoxelStructure::WideBvh})
        for (int threads : {1, 7}) {
            const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
            f.voxelAccel = tree;
            EXPECT_EQ(render::render(scene, f).image.rgba, reference.image.rgba) << rt::voxelStructureName(tree) << ", " << threads;
        }
}

// A plate of voxels over a floor of voxels: every floor pixel is darker with --shadows raytraced
// exactly where a brute-force ray from its face toward the light meets a voxel past the
// neighbourhood the rule leaves out (decided where the light's cosine makes the difference plain).
TEST(VoxelRayShadows, AFacesShadowIsWhereBruteForceRaysToTheLightAreBlocked) {
    std::vector<testing::Triangle> scene{{glm::vec3(-2, 0, -2), glm::vec3(2, 0, 2), glm::vec3(2, 0, -2)},
                                         {glm::vec3(-2, 0, -2), glm::vec3(-2, 0, 2), glm::vec3(2, 0, 2)},
                                         {glm::vec3(-0.8, 0.9, -0.8), glm::vec3(0.8, 0.9, 0.8), glm::vec3(0.8, 0.9, -0.8)},
                                         {glm::vec3(-0.8, 0.9, -0.8), glm::vec3(-0.8, 0.9, 0.8), glm::vec3(0.8, 0.9, 0.8)}};
    voxel::VoxelizeOptions o;
    o.resolution = 64;
    voxel::VoxelModel model = voxel::voxelizeMesh(*testing::viewOf(scene, 1000), o);
    lod::buildLodPyramid(model, {});
    const auto path = testing::writeTemp("_voxel_ray_shadows.cvox", testing::cvoxBytes(model));
    const render::LoadedScene loaded(path.string());
    render::FrameSettings f;
    f.width = 160;
    f.height = 120;
    f.renderer = render::Renderer::Raytrace;
    f.elevation = 50.0f;  // from above, so the floor under the plate shows
    const std::vector<uint8_t> unshadowed = render::displayPixels(loaded, f, render::render(loaded, f));
    f.shadows.mode = rt::ShadowMode::RayTraced;
    const std::vector<uint8_t> shadowed = render::displayPixels(loaded, f, render::render(loaded, f));
    std::filesystem::remove(path);

    const lod::VoxelScene& voxels = *render::SceneAccess::state(loaded).voxel;
    const glm::vec3 toLight = -voxels.lighting.lights[0].direction;
    rt::PrimaryRayCamera rays;
    rays.worldFromClip = glm::inverse(glm::dmat4(voxels.camera.clipFromWorld(float(f.width) / float(f.height))));
    const FaceTracer tracer(model);
    std::vector<uint32_t> normals;
    for (const voxel::VoxelBlock& b : model.blocks)
        if (b.level == 0) normals.insert(normals.end(), b.normals.begin(), b.normals.end());
    int blocked = 0, open = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            glm::vec3 point;
            const uint64_t face = tracer.face(rays, x + 0.5, y + 0.5, f.width, f.height, &point);
            if (face == ~0ull) continue;
            const uint32_t voxel = uint32_t(face / 6);
            if (glm::dot(voxel::unpackNormal1010102(normals[voxel]), toLight) < 0.3f) continue;  // the shadow barely shows
            rt::Ray ray{point, toLight, 0.0f, std::numeric_limits<float>::infinity()};
            const rt::VoxelCoord& v = tracer.coords[voxel];
            const glm::vec3 lo = glm::vec3(v.x, v.y, v.z) - float(render::kUnshadowingNeighbourhoodVoxels);
            float enter, exit;
            if (rt::VoxelRay(ray).segment(lo, lo + float(2 * render::kUnshadowingNeighbourhoodVoxels + 1), 0.0f, ray.tMax, &enter, &exit))
                ray.tMin = exit;
            const bool expectShadow = rt::closestVoxelBruteForce(tracer.coords, rt::VoxelRay(ray)).hit();
            const size_t i = 4 * (size_t(y) * size_t(f.width) + size_t(x));
            const int darker = int(unshadowed[i]) + unshadowed[i + 1] + unshadowed[i + 2] - shadowed[i] - shadowed[i + 1] - shadowed[i + 2];
            EXPECT_EQ(darker > 30, expectShadow) << "pixel " << x << ", " << y << " darker by " << darker;
            (expectShadow ? blocked : open) += 1;
        }
    EXPECT_GT(blocked, 100);
    EXPECT_GT(open, 1000);
}

TEST_F(VoxelRayFrame, RefusesWhatOneTracedLevelCannotHonour) {
    const render::LoadedScene scene(path_->string());
    render::FrameSettings f = frame();
    f.accel = rt::CasterAccel::Grid;
    EXPECT_THROW(render::render(scene, f), scene::InputError);
    f = frame();
    f.pixelError = 2.0f;
    EXPECT_THROW(render::render(scene, f), scene::InputError);
    f = frame();
    f.debugCamera = true;
    EXPECT_THROW(render::render(scene, f), scene::InputError);
    f = frame();
    f.shadows.mode = rt::ShadowMode::Hybrid;  // no shadow map of voxels: rays only
    EXPECT_THROW(render::render(scene, f), scene::InputError);
    f.renderer = render::Renderer::Raster;
    f.shadows.mode = rt::ShadowMode::RayTraced;  // the rasterized voxel frame casts no rays
    EXPECT_THROW(render::render(scene, f), scene::InputError);
    f = frame();
    f.renderer = render::Renderer::Raster;
    f.voxelAccel = rt::VoxelStructure::Octree;  // a voxel tree answers only camera rays
    EXPECT_THROW(render::render(scene, f), scene::InputError);
}

}  // namespace
}  // namespace cuberille
