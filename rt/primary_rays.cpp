#include "rt/primary_rays.h"

#include <algorithm>

#include "raster/clock.h"
#include "raster/limits.h"
#include "raster/parallel.h"
#include "raster/sample_pattern.h"
#include "rt/bvh_build.h"
#include "rt/wide_bvh.h"

namespace cuberille::rt {
namespace {

/// The traced draws as one world-space mesh, and where each of its triangles came from.
struct TracedMesh {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    std::vector<uint32_t> draw, triangle;  // per mesh triangle: its draw and its index there

    TriangleMeshView view() const { return {positions, indices}; }
};

TracedMesh gatherTracedMesh(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                            const PrimaryRayCamera& camera);
void traceBlock(const TracedMesh& mesh, const WideBvh* bvh, const UniformGrid* grid, const PrimaryRayCamera& camera,
                int blockX, int blockY, raster::VisibilityBuffer& out, uint64_t& hits);

/// The edge of the square blocks of pixels traced together: one grid packet of 8x8 rays at one
/// sample (Wald et al.'s best packet size below 250k triangles, §4.1).
constexpr int kBlockPixels = 8;

}  // namespace

Ray primaryRay(const PrimaryRayCamera& camera, double x, double y, int width, int height) {
    const double nx = 2.0 * x / width - 1.0, ny = 1.0 - 2.0 * y / height;
    const double nearDepth = camera.reversedDepth ? 1.0 : 0.0;
    const glm::dvec4 n = camera.worldFromClip * glm::dvec4(nx, ny, nearDepth, 1.0);
    const glm::dvec4 f = camera.worldFromClip * glm::dvec4(nx, ny, 1.0 - nearDepth, 1.0);
    const glm::dvec3 origin = glm::dvec3(n) / n.w, far = glm::dvec3(f) / f.w;
    Ray r;
    r.origin = glm::vec3(origin);
    r.direction = glm::vec3(far - origin);
    r.tMin = 0.0f;
    r.tMax = 1.0f;
    return r;
}

PrimaryRayStats tracePrimaryVisibility(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                                       const PrimaryRayCamera& camera, CasterAccel accel, raster::VisibilityBuffer& out) {
    PrimaryRayStats stats;
    stats.accel = accel;
    double t0 = raster::nowMs();
    const TracedMesh mesh = gatherTracedMesh(draws, traced, camera);
    stats.triangles = mesh.draw.size();
    double t1 = raster::nowMs();
    stats.gatherMs = t1 - t0;
    WideBvh wide;
    UniformGrid grid;
    if (accel == CasterAccel::Bvh) wide = collapseToWideBvh(buildBvh(mesh.view()));
    else grid = buildUniformGrid(mesh.view());
    double t2 = raster::nowMs();
    stats.buildMs = t2 - t1;
    const int blocksX = (out.width + kBlockPixels - 1) / kBlockPixels, blocksY = (out.height + kBlockPixels - 1) / kBlockPixels;
    std::vector<uint64_t> hits(size_t(blocksX) * size_t(blocksY), 0);
    if (!mesh.draw.empty())
        raster::parallelFor(hits.size(), [&](size_t b) {
            traceBlock(mesh, accel == CasterAccel::Bvh ? &wide : nullptr, accel == CasterAccel::Grid ? &grid : nullptr, camera,
                       int(b % blocksX), int(b / blocksX), out, hits[b]);
        });
    for (uint64_t h : hits) stats.hits += h;
    stats.rays = uint64_t(out.width) * uint64_t(out.height) * uint64_t(out.samples);
    stats.traceMs = raster::nowMs() - t2;
    return stats;
}

namespace {

// Which side of a triangle every ray of the camera sees: the front (counter-clockwise on screen,
// raster/draw.h) when its right-handed normal points toward the eye.
bool facesTheCamera(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const PrimaryRayCamera& camera) {
    const glm::vec3 n = glm::cross(b - a, c - a);
    const float toward = camera.orthographic ? -glm::dot(n, camera.viewDirection) : glm::dot(n, camera.eye - a);
    return toward > 0.0f;
}

TracedMesh gatherTracedMesh(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                            const PrimaryRayCamera& camera) {
    TracedMesh mesh;
    for (size_t d = 0; d < draws.size(); ++d) {
        if (!traced[d]) continue;
        const raster::DrawCall& call = draws[d];
        const uint32_t base = uint32_t(mesh.positions.size());
        for (const glm::vec3& p : call.positions) mesh.positions.push_back(glm::vec3(call.worldFromObject * glm::vec4(p, 1.0f)));
        const size_t vertexCount = call.positions.size();
        for (size_t t = 0; t < call.triangleCount(); ++t) {
            size_t corner[3];
            bool valid = true;
            for (int k = 0; k < 3; ++k) {
                corner[k] = call.indices.empty() ? 3 * t + k : call.indices[3 * t + k];
                valid = valid && corner[k] < vertexCount;
            }
            if (!valid) continue;  // as the front end drops it
            const glm::vec3& a = mesh.positions[base + corner[0]];
            const glm::vec3& b = mesh.positions[base + corner[1]];
            const glm::vec3& c = mesh.positions[base + corner[2]];
            if (call.state.cull != raster::CullMode::None &&
                facesTheCamera(a, b, c, camera) != (call.state.cull == raster::CullMode::Back))
                continue;
            for (int k = 0; k < 3; ++k) mesh.indices.push_back(base + uint32_t(corner[k]));
            mesh.draw.push_back(uint32_t(d));
            mesh.triangle.push_back(uint32_t(t));
        }
    }
    return mesh;
}

// One block's rays, pixel by pixel in row order and each pixel's samples in pattern order: the
// grid takes them as packets of up to 64, the BVH one by one.
void traceBlock(const TracedMesh& mesh, const WideBvh* bvh, const UniformGrid* grid, const PrimaryRayCamera& camera,
                int blockX, int blockY, raster::VisibilityBuffer& out, uint64_t& hits) {
    const int S = out.samples;
    const raster::SamplePattern& sp = raster::standardSamplePattern(S);
    const int x0 = blockX * kBlockPixels, y0 = blockY * kBlockPixels;
    const int x1 = std::min(x0 + kBlockPixels, out.width), y1 = std::min(y0 + kBlockPixels, out.height);
    Ray rays[kBlockPixels * kBlockPixels * raster::kMaxSamples];
    RayHit found[kBlockPixels * kBlockPixels * raster::kMaxSamples];
    size_t where[kBlockPixels * kBlockPixels * raster::kMaxSamples];
    int n = 0;
    constexpr double kSampleOffsetUnitPixels = double(raster::kSampleOffsetUnitSubpixels) / raster::kSubpixelsPerPixel;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int s = 0; s < S; ++s) {
                rays[n] = primaryRay(camera, x + 0.5 + sp.dx[s] * kSampleOffsetUnitPixels, y + 0.5 + sp.dy[s] * kSampleOffsetUnitPixels,
                                    out.width, out.height);
                where[n++] = (size_t(y) * size_t(out.width) + size_t(x)) * size_t(S) + size_t(s);
            }
    if (grid)
        closestHits(*grid, mesh.view(), std::span<const Ray>(rays, size_t(n)), std::span<RayHit>(found, size_t(n)));
    else
        for (int i = 0; i < n; ++i) found[i] = closestHit(*bvh, rays[i]);
    for (int i = 0; i < n; ++i) {
        if (!found[i].hit()) continue;
        ++hits;
        out.draw[where[i]] = mesh.draw[found[i].triangle];
        out.triangle[where[i]] = mesh.triangle[found[i].triangle];
    }
}

}  // namespace
}  // namespace cuberille::rt
