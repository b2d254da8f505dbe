// A voxel model's frame by camera rays (render/voxel_ray_frame.h).

#include "render/voxel_ray_frame.h"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "lod/voxel_scene.h"
#include "raster/clock.h"
#include "raster/sample_pattern.h"
#include "raster/visibility_shade.h"
#include "rt/primary_rays.h"
#include "scene/mesh.h"
#include "voxel/face_expansion.h"
#include "voxel/packing.h"

namespace cuberille::render {

namespace {

constexpr uint64_t kNoFace = ~0ull;

/// A face seen: voxel x 6 + the face's bit index in the active face mask (voxel/voxel_model.h:
/// 2 x axis, + 1 for the low side). A ray entering by the low plane of an axis (direction
/// positive along it) sees the low face.
uint64_t faceKey(uint32_t voxel, int axis, bool lowSide) { return uint64_t(voxel) * 6 + uint64_t(2 * axis + (lowSide ? 1 : 0)); }

}  // namespace

VoxelRayScene::VoxelRayScene(const voxel::VoxelModel& model, uint32_t level, rt::VoxelStructure structure)
    : level_(level), structure_(structure) {
    const double t0 = raster::nowMs();
    origin_ = model.grid.origin;
    voxelSize_ = model.grid.voxelSize() * double(1u << level);
    resolution_ = model.grid.resolution >> level;
    blockSize_ = model.blockSize;
    if (!model.hasColors) uncoloured_ = scene::Mesh{}.color;
    for (const voxel::VoxelBlock& b : model.blocks) {
        if (b.level != level) continue;
        for (size_t i = 0; i < b.voxels.size(); ++i) {
            const glm::uvec3 p = model.gridPosition(b, i);
            coords_.push_back({uint16_t(p.x), uint16_t(p.y), uint16_t(p.z)});
        }
        normals_.insert(normals_.end(), b.normals.begin(), b.normals.end());
        colors_.insert(colors_.end(), b.colors.begin(), b.colors.end());
    }
    const double t1 = raster::nowMs();
    switch (structure) {
        case rt::VoxelStructure::Bvh: tree_.emplace<rt::VoxelBvh>(coords_); break;
        case rt::VoxelStructure::KdTree: tree_.emplace<rt::VoxelKdTree>(coords_); break;
        case rt::VoxelStructure::Octree: tree_.emplace<rt::VoxelOctree>(coords_); break;
    }
    gatherMs_ = t1 - t0;
    buildMs_ = raster::nowMs() - t1;
}

rt::VoxelHit VoxelRayScene::trace(const rt::VoxelRay& ray, rt::VoxelTraversalCounters* counters) const {
    return std::visit(
        [&](const auto& tree) -> rt::VoxelHit {
            if constexpr (std::is_same_v<std::decay_t<decltype(tree)>, std::monostate>) return {};
            else return tree.trace(ray, {}, counters);
        },
        tree_);
}

VoxelRayFrameStats VoxelRayScene::drawFrame(raster::Pipeline& pipeline, const scene::Camera& camera,
                                            const raster::Lighting& lighting, int width, int height, int samples) {
    VoxelRayFrameStats stats;
    stats.structure = structure_;
    stats.level = level_;
    stats.resolution = resolution_;
    stats.voxels = coords_.size();
    if (!reported_) stats.gatherMs = gatherMs_, stats.buildMs = buildMs_, reported_ = true;

    // Trace: a ray per sample, near plane to far plane, moved into grid units (t is unchanged).
    const double t0 = raster::nowMs();
    const glm::mat4 clipFromWorld = camera.clipFromWorld(float(width) / float(height));
    rt::PrimaryRayCamera rays;
    rays.worldFromClip = glm::inverse(glm::dmat4(clipFromWorld));
    rays.reversedDepth = camera.reversedDepth;
    const raster::SamplePattern& pattern = raster::standardSamplePattern(samples);
    constexpr double kSampleOffsetUnitPixels = double(raster::kSampleOffsetUnitSubpixels) / raster::kSubpixelsPerPixel;
    const size_t sampleCount = size_t(width) * size_t(height) * size_t(samples);
    std::vector<uint64_t> faceOf(sampleCount, kNoFace);
    std::vector<uint8_t> secondTriangle(sampleCount, 0);
    tbb::combinable<rt::VoxelTraversalCounters> counters;
    tbb::combinable<uint64_t> inside;
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        rt::VoxelTraversalCounters& c = counters.local();
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < width; ++x)
                for (int s = 0; s < samples; ++s) {
                    const rt::Ray world = rt::primaryRay(rays, x + 0.5 + pattern.dx[s] * kSampleOffsetUnitPixels,
                                                         y + 0.5 + pattern.dy[s] * kSampleOffsetUnitPixels, width, height);
                    rt::Ray grid;
                    grid.origin = glm::vec3((glm::dvec3(world.origin) - origin_) / voxelSize_);
                    grid.direction = glm::vec3(glm::dvec3(world.direction) / voxelSize_);
                    grid.tMin = world.tMin;
                    grid.tMax = world.tMax;
                    const rt::VoxelRay ray(grid);
                    const rt::VoxelHit hit = trace(ray, &c);
                    if (!hit.hit()) continue;
                    if (hit.axis < 0) {
                        ++inside.local();
                        continue;
                    }
                    const size_t i = (size_t(y) * size_t(width) + size_t(x)) * size_t(samples) + size_t(s);
                    const int a = hit.axis, u = (a + 1) % 3, v = (a + 2) % 3;
                    const bool lowSide = !ray.farSide[a];
                    faceOf[i] = faceKey(hit.voxel, a, lowSide);
                    // Which triangle of the face's quad holds the hit: they meet on the diagonal
                    // from corner 0 to corner 2 (voxel::faceCorners' order for each side).
                    const glm::vec3 p = grid.origin + hit.t * grid.direction;
                    const rt::VoxelCoord& vc = coords_[hit.voxel];
                    const float cu = u == 0 ? vc.x : u == 1 ? vc.y : vc.z, cv = v == 0 ? vc.x : v == 1 ? vc.y : vc.z;
                    const float fu = p[u] - cu, fv = p[v] - cv;
                    secondTriangle[i] = lowSide ? fu > fv : fv > fu;
                }
    });
    counters.combine_each([&](const rt::VoxelTraversalCounters& c) { stats.counters.add(c); });
    inside.combine_each([&](uint64_t n) { stats.samplesInside += n; });
    stats.rays = stats.counters.rays;
    stats.hits = stats.counters.hits;
    stats.traceMs = raster::nowMs() - t0;

    // Shade: the faces seen as the rasterizer's quads, in key order (deterministic), one draw.
    const double t1 = raster::nowMs();
    std::vector<uint64_t> faces;
    for (uint64_t f : faceOf)
        if (f != kNoFace) faces.push_back(f);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    stats.facesSeen = faces.size();
    positions_.resize(4 * faces.size());
    normals3_.resize(4 * faces.size());
    colors3_.resize(4 * faces.size());
    indices_.resize(6 * faces.size());
    for (size_t k = 0; k < faces.size(); ++k) {
        const uint32_t voxel = uint32_t(faces[k] / 6);
        const int bit = int(faces[k] % 6), axis = bit / 2;
        const rt::VoxelCoord& vc = coords_[voxel];
        const glm::uvec3 g(vc.x, vc.y, vc.z);
        // The corner as face expansion computes it (voxel::VoxelBoxes): block origin, then the
        // voxel within the block, so the quad has the rasterized quad's bits.
        const glm::dvec3 blockOrigin = origin_ + glm::dvec3(g / blockSize_) * double(blockSize_) * voxelSize_;
        const glm::dvec3 lo = blockOrigin + glm::dvec3(g % blockSize_) * voxelSize_;
        glm::dvec3 corners[4];
        voxel::faceCorners(lo, lo + voxelSize_, axis, bit % 2 == 0, corners);
        const glm::vec3 n = voxel::unpackNormal1010102(normals_[voxel]);
        const glm::vec3 c = uncoloured_ ? *uncoloured_ : voxel::unpackSrgba8Rgb(colors_[voxel]);
        for (int j = 0; j < 4; ++j) positions_[4 * k + j] = glm::vec3(corners[j]), normals3_[4 * k + j] = n, colors3_[4 * k + j] = c;
        const uint32_t v0 = uint32_t(4 * k);
        const uint32_t quad[6] = {v0, v0 + 1, v0 + 2, v0, v0 + 2, v0 + 3};
        std::copy(quad, quad + 6, indices_.begin() + ptrdiff_t(6 * k));
    }
    pipeline.draw(lod::voxelFacesDraw(clipFromWorld, positions_, normals3_, colors3_, indices_, lighting, camera.position));
    raster::VisibilityBuffer seen;
    seen.reset(width, height, samples);
    for (size_t i = 0; i < sampleCount; ++i) {
        if (faceOf[i] == kNoFace) continue;
        const size_t k = size_t(std::lower_bound(faces.begin(), faces.end(), faceOf[i]) - faces.begin());
        seen.draw[i] = 0;
        seen.triangle[i] = uint32_t(2 * k + secondTriangle[i]);
    }
    pipeline.shadeVisible(seen);
    stats.shadeMs = raster::nowMs() - t1;
    return stats;
}

}  // namespace cuberille::render
