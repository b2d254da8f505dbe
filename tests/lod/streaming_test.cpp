// Streaming under a memory budget, through the renderer: the budget holds, the first image needs
// only the root, missing blocks are stood in for (full) or left out (partial), a bad block is
// reported once and its parent shown, and once loading settles the image is the one a model
// wholly in memory gives.

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "lod/camera_path.h"
#include "lod/flight.h"
#include "raster/resolve.h"
#include "tests/lod/lod_test_support.h"

namespace cuberille {
namespace {

constexpr int kWidth = 200, kHeight = 150;

// The sphere the flights that settle below stream. ThreadSanitizer runs a flight tens of times
// slower, so there the model has half the side: the same loader threads, uploads, evictions and
// defragmentations racing the frames, on a quarter of the surface voxels, so CI can afford them
// under it (docs/robustness.md).
#if defined(__SANITIZE_THREAD__)
constexpr uint32_t kFlightResolution = 256;
#else
constexpr uint32_t kFlightResolution = 512;
#endif

voxel::VoxelModel spherePyramid(uint32_t resolution) { return testing::spherePyramid(resolution, 5); }

using testing::writeTemp;

raster::FramebufferDesc frameDesc() {
    raster::FramebufferDesc d;
    d.widthPixels = kWidth, d.heightPixels = kHeight, d.samples = 1;
    d.clearColor = glm::vec4(0.0f);
    return d;
}

std::vector<float> colorOf(const raster::Pipeline& p) {
    raster::Image image;
    raster::resolveColor(p.framebuffer(), image);
    return {image.rgba.begin(), image.rgba.end()};
}

std::vector<float> depthOf(const raster::Pipeline& p) {
    raster::Image image;
    raster::resolveDepth(p.framebuffer(), image);
    return {image.rgba.begin(), image.rgba.end()};
}

/// The image of a model wholly in memory (occlusion culling off: the reference image).
raster::Pipeline renderWhole(const voxel::VoxelModel& model, const scene::Camera& camera, lod::VoxelRenderOptions o) {
    lod::VoxelScene scene(model, 30.0f, 20.0f);  // the angles of Streamed's scene: the same light
    scene.camera = camera;
    o.occlusion = false;
    raster::Pipeline p;
    p.beginFrame(frameDesc());
    scene.draw(p, kWidth, kHeight, o);
    p.endFrame();
    return p;
}

/// Everything the flight below the test needs, opened on a .cvox.
struct Streamed {
    explicit Streamed(const std::filesystem::path& path, lod::StreamingOptions so = {}, lod::VoxelRenderOptions ro = {})
        : reader(path),
          blocks(reader, so, [this](const std::string& w) { warnings.push_back(w); }),
          scene(blocks, 30.0f, 20.0f),
          flight(scene, blocks, frameDesc(), ro) {}
    voxel::CvoxReader reader;
    std::vector<std::string> warnings;
    lod::StreamingBlocks blocks;
    lod::VoxelScene scene;
    lod::Flight flight;
};

uint64_t voxelBytes(const voxel::VoxelModel& m) { return m.voxelCount() * 12; }

TEST(Streaming, ResidentMemoryNeverExceedsTheBudget) {
    const voxel::VoxelModel model = spherePyramid(512);
    const auto path = writeTemp("budget.cvox", testing::cvoxBytes(model));
    lod::StreamingOptions so;
    so.budgetBytes = voxelBytes(model) / 4;  // an eighth of the voxels (half the budget is theirs)
    Streamed s(path, so);
    ASSERT_LE(s.blocks.capacityBytes(), so.budgetBytes);
    scene::Camera close = s.scene.camera;
    close.position = close.target + (close.position - close.target) * 0.3f;  // near: fine levels, part in view
    const lod::CameraPath path1 = lod::CameraPath::orbit(close);
    uint64_t revived = 0;
    for (int turn = 0; turn < 2; ++turn)
        for (int i = 0; i < 24; ++i) {
            const lod::FlightFrame f = s.flight.frame(path1.at(float(i) / 23.0f, close));
            uint64_t held = 0;
            for (int k = 0; k < lod::kPoolCount; ++k) {
                held += f.streaming.residentBytes[k] + f.streaming.freeListBytes[k];
                ASSERT_LE(f.streaming.residentBytes[k] + f.streaming.freeListBytes[k],
                          s.blocks.pool(lod::PoolKind(k)).capacityBytes());
            }
            ASSERT_LE(held, so.budgetBytes) << "frame " << f.index;
            revived += f.streaming.revivedBytes;
        }
    EXPECT_GT(s.blocks.pool(lod::kVoxelPool).stats().evictions, 0u) << "the budget was tight enough to evict";
    EXPECT_GT(revived, 0u) << "the second turn found blocks on the free list";
    EXPECT_TRUE(s.warnings.empty());
    std::filesystem::remove(path);
}

TEST(Streaming, DefragmentationKeepsEveryResidentBlockIntact) {
    const voxel::VoxelModel model = spherePyramid(kFlightResolution);
    const auto path = writeTemp("defrag.cvox", testing::cvoxBytes(model));
    lod::StreamingOptions so;
    so.budgetBytes = voxelBytes(model) / 2;
    so.highWaterMark = 0.5;  // defragment early and often
    Streamed s(path, so);
    scene::Camera close = s.scene.camera;
    close.position = close.target + (close.position - close.target) * 0.3f;
    const lod::CameraPath orbit = lod::CameraPath::orbit(close);
    for (int i = 0; i < 30; ++i) s.flight.frame(orbit.at(float(i) / 29.0f, close));
    s.flight.settle(orbit.at(1.0f, close), 200);
    uint64_t defragmentations = 0;
    for (int k = 0; k < lod::kPoolCount; ++k) defragmentations += s.blocks.pool(lod::PoolKind(k)).stats().defragmentations;
    ASSERT_GT(defragmentations, 0u);
    const std::vector<uint32_t> resident = s.blocks.pool(lod::kVoxelPool).residentBlocks();
    ASSERT_GE(resident.size(), 5u);
    for (uint32_t b : resident) {
        const voxel::VoxelBlock file = s.reader.load(b);
        const voxel::BlockVoxels held = s.blocks.voxels(b);
        ASSERT_TRUE(std::equal(held.voxels.begin(), held.voxels.end(), file.voxels.begin(), file.voxels.end())) << b;
        ASSERT_TRUE(std::equal(held.normals.begin(), held.normals.end(), file.normals.begin(), file.normals.end())) << b;
        ASSERT_TRUE(std::equal(held.colors.begin(), held.colors.end(), file.colors.begin(), file.colors.end())) << b;
    }
    std::filesystem::remove(path);
}

TEST(Streaming, SettledImageEqualsTheImageWithEverythingResident) {
    const voxel::VoxelModel model = spherePyramid(kFlightResolution);
    const auto path = writeTemp("settle.cvox", testing::cvoxBytes(model));
    for (lod::Refinement refine : {lod::Refinement::Full, lod::Refinement::Partial}) {
        lod::StreamingOptions so;
        // A few blocks a frame, so loading spans many frames, more than the path's eight take
        // whatever the I/O thread's speed; a sphere's voxels grow with its area.
        so.uploadLimitBytes = (uint64_t(1) << 18) * kFlightResolution / 512 * kFlightResolution / 512;
        lod::VoxelRenderOptions ro;
        ro.refine = refine;
        Streamed s(path, so, ro);
        const lod::CameraPath zoom = lod::CameraPath::zoom(s.scene.camera, 0.5f);
        for (int i = 0; i < 8; ++i) s.flight.frame(zoom.at(float(i) / 7.0f, s.scene.camera));
        const scene::Camera last = zoom.at(1.0f, s.scene.camera);
        const std::vector<lod::FlightFrame> settling = s.flight.settle(last, 500);
        ASSERT_TRUE(s.blocks.settled());
        ASSERT_GT(settling.size(), 1u) << "the upload limit spread loading over frames";
        const lod::FlightFrame final = s.flight.frame(last, true);
        EXPECT_EQ(final.voxel.missingBlocks, 0u);
        EXPECT_EQ(colorOf(s.flight.pipeline()), colorOf(renderWhole(model, last, ro)))
            << (refine == lod::Refinement::Full ? "full" : "partial");
    }
    std::filesystem::remove(path);
}

TEST(Streaming, FullRefinementNeverShowsAHoleAndPartialDoesWhileLoading) {
    const voxel::VoxelModel model = spherePyramid(kFlightResolution);
    const auto path = writeTemp("holes.cvox", testing::cvoxBytes(model));
    for (lod::Refinement refine : {lod::Refinement::Full, lod::Refinement::Partial}) {
        lod::StreamingOptions so;
        so.uploadLimitBytes = 32 << 10;
        lod::VoxelRenderOptions ro;
        ro.refine = refine;
        ro.occlusion = false;
        Streamed s(path, so, ro);
        const lod::CameraPath zoom = lod::CameraPath::zoom(s.scene.camera, 0.5f);
        uint64_t holes = 0, uncovered = 0;
        for (int i = 0; i < 10; ++i) {
            const scene::Camera c = zoom.at(float(i) / 9.0f, s.scene.camera);
            const lod::FlightFrame f = s.flight.frame(c);
            holes += f.voxel.holes;
            // Every pixel the whole model covers is covered (coarser conservative voxels contain
            // the finer ones, and stand-ins close their cells' sides).
            const std::vector<float> want = depthOf(renderWhole(model, c, ro)), got = depthOf(s.flight.pipeline());
            for (size_t p = 0; p < want.size(); p += 4) uncovered += want[p] < 1.0f && got[p] >= 1.0f;
        }
        if (refine == lod::Refinement::Full) {
            EXPECT_EQ(holes, 0u);
            EXPECT_EQ(uncovered, 0u);
        } else {
            EXPECT_GT(holes, 0u);
            EXPECT_GT(uncovered, 0u);
        }
    }
    std::filesystem::remove(path);
}

TEST(Streaming, TheFirstImageNeedsOnlyTheRootWhateverTheModelSize) {
    for (uint32_t resolution : {256u, 1024u}) {
        const voxel::VoxelModel model = spherePyramid(resolution);
        const auto path = writeTemp("first.cvox", testing::cvoxBytes(model));
        Streamed s(path);
        const uint64_t root = s.reader.partBytes(0, voxel::CvoxReader::kAllParts);
        EXPECT_EQ(s.blocks.bytesReadFromDisk(), root) << resolution;
        const lod::FlightFrame f = s.flight.frame(s.scene.camera);
        EXPECT_EQ(f.voxel.standIns, f.voxel.missingBlocks) << "the root stands in for every block the view wants";
        EXPECT_EQ(f.voxel.voxelBlocksDrawn, f.voxel.standIns + (f.voxel.missingBlocks == 0));
        EXPECT_EQ(f.streaming.loadedBytes, 0u) << "nothing read yet had to be waited for";
        const std::vector<float> depth = depthOf(s.flight.pipeline());
        size_t covered = 0;
        for (size_t p = 0; p < depth.size(); p += 4) covered += depth[p] < 1.0f;
        EXPECT_GT(covered, depth.size() / 4 / 20) << "a closed, coarse model at once";
        std::filesystem::remove(path);
    }
}

TEST(Streaming, ACorruptBlockIsReportedOnceAndItsParentShownThere) {
    const voxel::VoxelModel model = spherePyramid(512);
    std::string bytes = testing::cvoxBytes(model);
    const auto goodPath = writeTemp("good.cvox", bytes);
    scene::Camera last;
    uint32_t victim = 0;
    {
        // The level-0 block nearest the camera at the end of the zoom: certainly drawn there.
        Streamed probe(goodPath);
        last = lod::CameraPath::zoom(probe.scene.camera, 0.5f).at(1.0f, probe.scene.camera);
        lod::SelectionOptions o;
        o.viewportHeightPixels = kHeight;
        o.verticalFovRadians = glm::radians(last.verticalFovDegrees);
        const lod::BlockSelection sel = lod::selectBlocks(
            model, glm::dmat4(last.clipFromWorld(float(kWidth) / kHeight)), glm::dvec3(last.position), o);
        for (uint32_t b : sel.voxelBlocks)
            if (model.blocks[b].level == 0) {
                victim = b;
                break;
            }
        ASSERT_NE(victim, 0u);
    }
    // A voxel position no block may hold, in the victim's data.
    uint64_t offset = 0;
    std::memcpy(&offset, bytes.data() + 96 + size_t(victim) * 64 + 24, 8);
    bytes[offset + 3] = char(0xFF);
    const auto path = writeTemp("corrupt.cvox", bytes);
    lod::VoxelRenderOptions ro;
    Streamed s(path, {}, ro);
    const lod::CameraPath zoom = lod::CameraPath::zoom(s.scene.camera, 0.5f);
    for (int i = 0; i < 8; ++i) s.flight.frame(zoom.at(float(i) / 7.0f, s.scene.camera));
    s.flight.settle(last, 500);
    ASSERT_TRUE(s.blocks.settled());
    ASSERT_EQ(s.warnings.size(), 1u) << "reported once, though every frame wants the block";
    EXPECT_NE(s.warnings[0].find("block " + std::to_string(victim)), std::string::npos) << s.warnings[0];
    EXPECT_TRUE(s.blocks.failed(victim));
    const lod::FlightFrame f = s.flight.frame(last, true);
    EXPECT_EQ(f.voxel.standIns, 1u) << "the parent stands in for the failed block";
    EXPECT_EQ(f.voxel.holes, 0u);
    // The image differs from the whole model's only over the failed block's cell.
    const std::vector<float> want = colorOf(renderWhole(model, last, ro)), got = colorOf(s.flight.pipeline());
    glm::dvec3 lo, hi;
    lod::blockBounds(model, model.blocks[victim], lo, hi);
    const double cell = model.grid.voxelSize() * 2.0 * std::sqrt(3.0);  // a parent voxel reaches this far out
    lo -= cell, hi += cell;
    const glm::mat4 clip = last.clipFromWorld(float(kWidth) / kHeight);
    glm::vec2 pmin(1e9f), pmax(-1e9f);
    for (int c = 0; c < 8; ++c) {
        const glm::vec4 p = clip * glm::vec4(float(c & 1 ? hi.x : lo.x), float(c & 2 ? hi.y : lo.y), float(c & 4 ? hi.z : lo.z), 1.0f);
        ASSERT_GT(p.w, 0.0f);
        const glm::vec2 px((p.x / p.w * 0.5f + 0.5f) * kWidth, (0.5f - p.y / p.w * 0.5f) * kHeight);
        pmin = glm::min(pmin, px), pmax = glm::max(pmax, px);
    }
    size_t differing = 0, outside = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const size_t i = (size_t(y) * kWidth + x) * 4;
            if (std::equal(want.begin() + i, want.begin() + i + 4, got.begin() + i)) continue;
            ++differing;
            outside += x + 1 < pmin.x || x > pmax.x + 1 || y + 1 < pmin.y || y > pmax.y + 1;
        }
    EXPECT_GT(differing, 0u) << "the coarser parent shows";
    EXPECT_EQ(outside, 0u);
    std::filesystem::remove(path);
    std::filesystem::remove(goodPath);
}

}  // namespace
}  // namespace cuberille
