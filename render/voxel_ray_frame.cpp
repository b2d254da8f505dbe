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
#include "rt/ambient_occlusion.h"
#include "rt/primary_rays.h"
#include "rt/screen_surfaces.h"
#include "rt/shadows.h"
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
            boundsLo_ = coords_.size() == 1 ? glm::vec3(p) : glm::min(boundsLo_, glm::vec3(p));
            boundsHi_ = glm::max(boundsHi_, glm::vec3(p) + 1.0f);
        }
        normals_.insert(normals_.end(), b.normals.begin(), b.normals.end());
        colors_.insert(colors_.end(), b.colors.begin(), b.colors.end());
    }
    const double t1 = raster::nowMs();
    switch (structure) {
        case rt::VoxelStructure::Bvh: tree_.emplace<rt::VoxelBvh>(coords_); break;
        case rt::VoxelStructure::KdTree: tree_.emplace<rt::VoxelKdTree>(coords_); break;
        case rt::VoxelStructure::Octree: tree_.emplace<rt::VoxelOctree>(coords_); break;
        case rt::VoxelStructure::WideBvh: tree_.emplace<rt::WideVoxelBvh>(coords_); break;
    }
    gatherMs_ = t1 - t0;
    buildMs_ = raster::nowMs() - t1;
}

rt::VoxelHit VoxelRayScene::trace(const rt::VoxelRay& ray, const rt::VoxelTraversal& how, rt::VoxelTraversalCounters* counters) const {
    return std::visit(
        [&](const auto& tree) -> rt::VoxelHit {
            if constexpr (std::is_same_v<std::decay_t<decltype(tree)>, std::monostate>) return {};
            else return tree.trace(ray, how, counters);
        },
        tree_);
}

bool VoxelRayScene::occluded(rt::Ray ray, uint32_t voxel) const {
    const rt::VoxelRay leaving(ray);
    const glm::vec3 lo = glm::vec3(coords_[voxel].x, coords_[voxel].y, coords_[voxel].z) - float(kUnshadowingNeighbourhoodVoxels);
    float enter, exit;
    if (leaving.segment(lo, lo + float(2 * kUnshadowingNeighbourhoodVoxels + 1), ray.tMin, ray.tMax, &enter, &exit))
        ray.tMin = exit;  // past the voxel's neighbourhood
    return trace(rt::VoxelRay(ray), {.anyHit = true}, nullptr).hit();
}

void VoxelRayScene::lightFaces(const std::vector<uint64_t>& centre, const std::vector<glm::vec3>& centrePoint, int width,
                               int height, const VoxelRayEffects& effects, raster::Lighting& lighting, VoxelRayFrameStats& stats) {
    const bool shadows = effects.shadows && lighting.lightCount > 0, occlusion = effects.occlusionRays > 0;
    const glm::vec3 toLight = lighting.lightCount > 0 ? -lighting.lights[0].direction : glm::vec3(0.0f);
    const std::vector<glm::vec2> disk = rt::diskSamples(effects.soft ? std::max(1, effects.softSamplesPerSide) : 1);
    const std::vector<glm::vec3> directions = rt::occlusionDirections(effects.occlusionRays);
    const double diagonal = double(glm::length(boundsHi_ - boundsLo_)) * voxelSize_;
    stats.occlusionDistance = effects.occlusionDistance > 0.0f ? effects.occlusionDistance
                                                               : float(rt::kDefaultOcclusionDistanceOfBounds * diagonal);
    const float reachInVoxels = float(double(stats.occlusionDistance) / voxelSize_);
    shadowMask_.assign(size_t(width) * size_t(height), 1.0f);
    occlusionMask_.assign(size_t(width) * size_t(height), 1.0f);
    tbb::combinable<uint64_t> shadowRays, occlusionRays;
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < width; ++x) {
                const size_t p = size_t(y) * size_t(width) + size_t(x);
                if (centre[p] == kNoFace) continue;
                const uint32_t voxel = uint32_t(centre[p] / 6);
                const int bit = int(centre[p] % 6);
                glm::vec3 faceNormal(0.0f);
                faceNormal[bit / 2] = bit % 2 == 0 ? 1.0f : -1.0f;
                const glm::vec3 point = centrePoint[p];
                if (shadows && glm::dot(voxel::unpackNormal1010102(normals_[voxel]), toLight) > 0.0f) {
                    glm::vec3 u, v;
                    rt::tangentFrame(toLight, u, v);
                    int lit = 0;
                    for (const glm::vec2& s : disk) {
                        const glm::vec3 d = effects.soft ? glm::normalize(toLight + effects.lightRadius * (s.x * u + s.y * v)) : toLight;
                        lit += !occluded(rt::Ray{point, d, 0.0f, std::numeric_limits<float>::infinity()}, voxel);
                    }
                    shadowRays.local() += disk.size();
                    shadowMask_[p] = float(lit) / float(disk.size());
                }
                if (occlusion) {
                    occlusionMask_[p] = rt::openShare(rt::Surface{point, faceNormal}, directions, rt::occlusionTurnRadians(x, y),
                                                      reachInVoxels, 0.0f, [&](const rt::Ray& r) { return occluded(r, voxel); });
                    occlusionRays.local() += directions.size();
                }
            }
    });
    shadowRays.combine_each([&](uint64_t n) { stats.shadowRays += n; });
    occlusionRays.combine_each([&](uint64_t n) { stats.occlusionRays += n; });
    if (shadows) lighting.lights[0].visibility = shadowMask_.data();
    if (occlusion) lighting.ambientVisibility = occlusionMask_.data();
}

VoxelRayFrameStats VoxelRayScene::drawFrame(raster::Pipeline& pipeline, const scene::Camera& camera,
                                            const raster::Lighting& lighting, int width, int height, int samples,
                                            const VoxelRayEffects& effects) {
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
    // The face at each pixel centre, where shadow and occlusion rays leave from (the one sample's
    // own ray at 1 sample, else a ray of its own).
    const bool lit = effects.shadows || effects.occlusionRays > 0;
    std::vector<uint64_t> centreFace(lit ? size_t(width) * size_t(height) : 0, kNoFace);
    std::vector<glm::vec3> centrePoint(centreFace.size());
    tbb::combinable<rt::VoxelTraversalCounters> counters;
    tbb::combinable<uint64_t> inside;
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        rt::VoxelTraversalCounters& c = counters.local();
        // The face a window position's ray enters, and where: the hit point put on the face's plane.
        auto faceAt = [&](double wx, double wy, glm::vec3* point, uint8_t* second) -> uint64_t {
            const rt::Ray world = rt::primaryRay(rays, wx, wy, width, height);
            rt::Ray grid;
            grid.origin = glm::vec3((glm::dvec3(world.origin) - origin_) / voxelSize_);
            grid.direction = glm::vec3(glm::dvec3(world.direction) / voxelSize_);
            grid.tMin = world.tMin;
            grid.tMax = world.tMax;
            const rt::VoxelRay ray(grid);
            const rt::VoxelHit hit = trace(ray, {}, &c);
            if (!hit.hit()) return kNoFace;
            if (hit.axis < 0) {
                ++inside.local();
                return kNoFace;
            }
            const int a = hit.axis, u = (a + 1) % 3, v = (a + 2) % 3;
            const bool lowSide = !ray.farSide[a];
            const rt::VoxelCoord& vc = coords_[hit.voxel];
            const glm::vec3 corner(vc.x, vc.y, vc.z);
            const glm::vec3 p = hit.entryPoint(ray, vc);
            *point = p;
            // Which triangle of the face's quad holds the hit: they meet on the diagonal from
            // corner 0 to corner 2 (voxel::faceCorners' order for each side).
            const float fu = p[u] - corner[u], fv = p[v] - corner[v];
            *second = lowSide ? fu > fv : fv > fu;
            return faceKey(hit.voxel, a, lowSide);
        };
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < width; ++x) {
                const size_t pixel = size_t(y) * size_t(width) + size_t(x);
                glm::vec3 point;
                for (int s = 0; s < samples; ++s) {
                    const size_t i = pixel * size_t(samples) + size_t(s);
                    faceOf[i] = faceAt(x + 0.5 + pattern.dx[s] * kSampleOffsetUnitPixels, y + 0.5 + pattern.dy[s] * kSampleOffsetUnitPixels,
                                       &point, &secondTriangle[i]);
                    if (lit && samples == 1) centreFace[pixel] = faceOf[i], centrePoint[pixel] = point;
                }
                uint8_t unused;
                if (lit && samples > 1) centreFace[pixel] = faceAt(x + 0.5, y + 0.5, &centrePoint[pixel], &unused);
            }
    });
    counters.combine_each([&](const rt::VoxelTraversalCounters& c) { stats.counters.add(c); });
    inside.combine_each([&](uint64_t n) { stats.samplesInside += n; });
    stats.rays = stats.counters.rays;
    stats.hits = stats.counters.hits;
    stats.traceMs = raster::nowMs() - t0;
    raster::Lighting lightingWithMasks = lighting;
    if (lit) {
        const double tl = raster::nowMs();
        lightFaces(centreFace, centrePoint, width, height, effects, lightingWithMasks, stats);
        stats.lightMs = raster::nowMs() - tl;
    }

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
    pipeline.draw(lod::voxelFacesDraw(clipFromWorld, positions_, normals3_, colors3_, indices_, lightingWithMasks, camera.position));
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
