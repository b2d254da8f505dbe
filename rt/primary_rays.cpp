#include "rt/primary_rays.h"

#include <algorithm>
#include <cmath>

#include "raster/clock.h"
#include "raster/limits.h"
#include "raster/parallel.h"
#include "raster/sample_pattern.h"
#include "raster/texture.h"
#include "rt/bvh_build.h"
#include "rt/wide_bvh.h"

namespace cuberille::rt {
namespace {

/// Gathers the traced draws' triangles in world space. With `dropCulledFor`, a culled draw's
/// triangles that face away from that camera are left out (the grid's mesh, built per frame);
/// without, every triangle is kept with its culled side (the kept BVH's mesh).
void gatherTracedMesh(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                      const PrimaryRayCamera* dropCulledFor, TracedMesh& mesh);
/// The view's HitFilter entries: the triangles a culled draw shows its culled side (none in a
/// mesh gathered without them), and the alpha-tested ones.
void filterForView(const TracedMesh& mesh, const PrimaryRayCamera& camera, std::vector<uint8_t>& entries);
/// What the alpha test of a camera ray's hit reads.
struct AlphaTestContext {
    const TracedMesh* mesh;
    std::span<const raster::DrawCall> draws;
    const PrimaryRayCamera* camera;
    glm::dmat4 clipFromWorld;
    int width, height;
};
bool passesAlphaTest(const void* context, uint32_t triangle, const Ray& ray, float u, float v);
/// Closest hits for a block's rays: the BVH's one at a time, or the grid's as packets.
struct PrimaryRayQuery {
    const DeformingBvh* bvh = nullptr;
    const HitFilter* filter = nullptr;
    const UniformGrid* grid = nullptr;
    TriangleMeshView mesh;
};
void traceBlock(const TracedMesh& mesh, const PrimaryRayQuery& query, const PrimaryRayCamera& camera, int blockX, int blockY,
                raster::VisibilityBuffer& out, uint64_t& hits);
/// Every block of the frame, in parallel; adds the rays and hits to `stats`.
void traceFrame(const TracedMesh& mesh, const PrimaryRayQuery& query, const PrimaryRayCamera& camera,
                raster::VisibilityBuffer& out, PrimaryRayStats& stats);

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
    TracedMesh mesh;
    gatherTracedMesh(draws, traced, accel == CasterAccel::Grid ? &camera : nullptr, mesh);
    stats.triangles = mesh.draw.size();
    double t1 = raster::nowMs();
    stats.gatherMs = t1 - t0;
    std::optional<DeformingBvh> bvh;
    UniformGrid grid;
    std::vector<uint8_t> entries;
    filterForView(mesh, camera, entries);
    const AlphaTestContext alpha{&mesh, draws, &camera, glm::inverse(camera.worldFromClip), out.width, out.height};
    const HitFilter filter{entries, passesAlphaTest, &alpha};
    PrimaryRayQuery query{.filter = &filter, .mesh = mesh.view()};
    if (accel == CasterAccel::Bvh) {
        bvh.emplace(mesh.view(), BvhUpdateMethod::Rebuild);
        query.bvh = &*bvh;
    } else {
        grid = buildUniformGrid(mesh.view());
        query.grid = &grid;
    }
    stats.buildMs = raster::nowMs() - t1;
    traceFrame(mesh, query, camera, out, stats);
    return stats;
}

PrimaryRayHierarchy::DrawKey PrimaryRayHierarchy::keyOf(uint32_t draw, const raster::DrawCall& c) {
    return {draw, c.positions.size(), c.indices.size(), c.worldFromObject, c.state.cull};
}

PrimaryRayHierarchy::PrimaryRayHierarchy(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                                         BvhUpdateMethod method) {
    for (size_t d = 0; d < draws.size(); ++d)
        if (traced[d]) {
            keys_.push_back(keyOf(uint32_t(d), draws[d]));
            sourceIndices_.insert(sourceIndices_.end(), draws[d].indices.begin(), draws[d].indices.end());
            vertexArrays_.push_back(draws[d].positions.data());
        }
    const double t0 = raster::nowMs();
    gatherTracedMesh(draws, traced, nullptr, mesh_);
    bvh_.emplace(mesh_.view(), method);
    pendingBuildMs_ = raster::nowMs() - t0;
}

bool PrimaryRayHierarchy::sameDraws(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced) const {
    size_t k = 0, index = 0;
    for (size_t d = 0; d < draws.size(); ++d) {
        if (!traced[d]) continue;
        if (k == keys_.size() || !(keys_[k] == keyOf(uint32_t(d), draws[d]))) return false;
        const std::span<const uint32_t> indices = draws[d].indices;
        if (!std::equal(indices.begin(), indices.end(), sourceIndices_.begin() + ptrdiff_t(index))) return false;
        index += indices.size();
        ++k;
    }
    return k == keys_.size();
}

bool PrimaryRayHierarchy::sameVertexArrays(std::span<const raster::DrawCall> draws) const {
    for (size_t k = 0; k < keys_.size(); ++k)
        if (draws[keys_[k].draw].positions.data() != vertexArrays_[k]) return false;
    return true;
}

BvhUpdateReport PrimaryRayHierarchy::update(std::span<const raster::DrawCall> draws) {
    const double t0 = raster::nowMs();
    // The same triangles in the same order: only the positions are gathered again, in place, so
    // the tree's view of the mesh stays valid.
    size_t at = 0;
    for (size_t k = 0; k < keys_.size(); ++k) {
        const raster::DrawCall& c = draws[keys_[k].draw];
        for (const glm::vec3& p : c.positions) mesh_.positions[at++] = glm::vec3(c.worldFromObject * glm::vec4(p, 1.0f));
        vertexArrays_[k] = c.positions.data();
    }
    BvhUpdateReport report = bvh_->update(mesh_.view());
    pendingBuildMs_ += raster::nowMs() - t0;
    return report;
}

PrimaryRayStats PrimaryRayHierarchy::trace(std::span<const raster::DrawCall> draws, const PrimaryRayCamera& camera,
                                           raster::VisibilityBuffer& out) {
    PrimaryRayStats stats;
    stats.accel = CasterAccel::Bvh;
    stats.triangles = mesh_.draw.size();
    stats.buildMs = pendingBuildMs_;
    pendingBuildMs_ = 0;
    const double t0 = raster::nowMs();
    filterForView(mesh_, camera, filter_);
    stats.gatherMs = raster::nowMs() - t0;
    const AlphaTestContext alpha{&mesh_, draws, &camera, glm::inverse(camera.worldFromClip), out.width, out.height};
    const HitFilter filter{filter_, passesAlphaTest, &alpha};
    traceFrame(mesh_, {.bvh = &*bvh_, .filter = &filter, .mesh = mesh_.view()}, camera, out, stats);
    return stats;
}

PrimaryRayStats PrimaryRayHierarchy::traceCentres(std::span<const raster::DrawCall> draws, const PrimaryRayCamera& camera,
                                                  std::span<const uint32_t> pixels, raster::VisibilityBuffer& out) {
    PrimaryRayStats stats;
    stats.accel = CasterAccel::Bvh;
    stats.triangles = mesh_.draw.size();
    const double t0 = raster::nowMs();
    const AlphaTestContext alpha{&mesh_, draws, &camera, glm::inverse(camera.worldFromClip), out.width, out.height};
    const HitFilter filter{filter_, passesAlphaTest, &alpha};
    // Packets of the listed pixels of each 8x8 block, as trace() takes a block's rays: listed
    // pixels lie along edges, and consecutive ones in the list (along a row) made incoherent
    // packets that open every upper node: the dragon's 100k open pixels took 59 ms so, 37 as
    // single rays, 30 as these.
    const uint32_t blocksX = uint32_t(out.width + kBlockPixels - 1) / kBlockPixels;
    const uint32_t blocksY = uint32_t(out.height + kBlockPixels - 1) / kBlockPixels;
    const auto blockOf = [&](uint32_t p) {
        return (p / uint32_t(out.width)) / kBlockPixels * blocksX + (p % uint32_t(out.width)) / kBlockPixels;
    };
    std::vector<uint32_t> firstOfBlock(size_t(blocksX) * blocksY + 1, 0), byBlock(pixels.size());
    for (const uint32_t p : pixels) ++firstOfBlock[blockOf(p) + 1];
    for (size_t b = 1; b < firstOfBlock.size(); ++b) firstOfBlock[b] += firstOfBlock[b - 1];
    std::vector<uint32_t> cursor(firstOfBlock.begin(), firstOfBlock.end() - 1);
    for (const uint32_t p : pixels) byBlock[cursor[blockOf(p)]++] = p;  // row order within a block
    constexpr size_t kMostRays = size_t(kBlockPixels) * kBlockPixels;
    std::vector<uint64_t> hits(size_t(blocksX) * blocksY, 0);
    raster::parallelFor(hits.size(), [&](size_t b) {
        const size_t first = firstOfBlock[b], n = firstOfBlock[b + 1] - first;
        if (n == 0) return;
        Ray rays[kMostRays];
        RayHit found[kMostRays];
        for (size_t k = 0; k < n; ++k) {
            const uint32_t p = byBlock[first + k];
            rays[k] = primaryRay(camera, p % uint32_t(out.width) + 0.5, p / uint32_t(out.width) + 0.5, out.width, out.height);
        }
        bvh_->closestHits(std::span<const Ray>(rays, n), std::span<RayHit>(found, n), filter);
        for (size_t k = 0; k < n; ++k) {
            if (!found[k].hit()) continue;
            out.draw[byBlock[first + k]] = mesh_.draw[found[k].triangle];
            out.triangle[byBlock[first + k]] = mesh_.triangle[found[k].triangle];
            ++hits[b];
        }
    });
    for (const uint64_t h : hits) stats.hits += h;
    stats.rays = pixels.size();
    stats.traceMs = raster::nowMs() - t0;
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

bool culledFor(raster::CullMode cull, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const PrimaryRayCamera& camera) {
    return cull != raster::CullMode::None && facesTheCamera(a, b, c, camera) == (cull == raster::CullMode::Front);
}

void filterForView(const TracedMesh& mesh, const PrimaryRayCamera& camera, std::vector<uint8_t>& entries) {
    constexpr size_t kTrianglesPerTask = 16384;
    const size_t triangles = mesh.cull.size();
    entries.resize(triangles);
    raster::parallelFor((triangles + kTrianglesPerTask - 1) / kTrianglesPerTask, [&](size_t task) {
        for (size_t t = task * kTrianglesPerTask; t < std::min(triangles, (task + 1) * kTrianglesPerTask); ++t) {
            const uint32_t* i = &mesh.indices[3 * t];
            entries[t] = culledFor(mesh.cull[t], mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]], camera)
                             ? HitFilter::kSkipped
                             : (mesh.alphaTested[t] ? HitFilter::kAlphaTested : HitFilter::kKept);
        }
    });
}

// The weights of p in triangle (a, b, c) by areas, in double: those of b and c.
glm::dvec2 weightsInTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 n = glm::cross(b - a, c - a);
    const double area = glm::dot(n, n);
    if (!(area > 0.0)) return {0.0, 0.0};
    return {glm::dot(glm::cross(p - a, c - a), n) / area, glm::dot(glm::cross(b - a, p - a), n) / area};
}

// The weights (of the second and third vertex) where the camera's ray through window position
// (x, y) meets the triangle's plane.
glm::dvec2 weightsOnPlane(const AlphaTestContext& c, double x, double y, const glm::dvec3 (&v)[3]) {
    const Ray r = primaryRay(*c.camera, x, y, c.width, c.height);
    const glm::dvec3 o(r.origin), d(r.direction);
    const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
    const double along = glm::dot(n, d);
    const double t = along != 0.0 ? glm::dot(n, v[0] - o) / along : 0.0;
    return weightsInTriangle(o + t * d, v[0], v[1], v[2]);
}

// The rasterizer's alpha test (raster/shade.h, output merge), which a pixel takes once, at its
// centre, for all its samples: the base colour factor's alpha times the vertex alphas,
// interpolated, times the base colour texture's alpha at the level of detail of the centre's UV
// derivatives, against the draw's cutoff. The centre's weights are where the ray through it meets
// the triangle's plane (clamped onto the triangle where the centre lies outside it, as the shade
// stage clamps); the derivatives, the UV where the rays through the next pixel right and the next
// pixel down meet the plane, less the centre's: the rasterizer's own finite differences, on the
// unsnapped plane.
bool passesAlphaTest(const void* context, uint32_t triangle, const Ray& ray, float, float) {
    const AlphaTestContext& c = *static_cast<const AlphaTestContext*>(context);
    const raster::DrawCall& call = c.draws[c.mesh->draw[triangle]];
    const raster::DrawState& state = call.state;
    const size_t source = c.mesh->triangle[triangle];
    size_t corner[3];
    for (int k = 0; k < 3; ++k) corner[k] = call.indices.empty() ? 3 * source + k : call.indices[3 * source + k];
    glm::dvec3 world[3];
    for (int k = 0; k < 3; ++k) world[k] = glm::dvec3(c.mesh->positions[c.mesh->indices[3 * size_t(triangle) + k]]);
    // The pixel of the sample, from its ray's start on the near plane.
    const glm::dvec4 clip = c.clipFromWorld * glm::dvec4(glm::dvec3(ray.origin), 1.0);
    const double x = std::floor((clip.x / clip.w + 1.0) * c.width / 2.0) + 0.5;
    const double y = std::floor((1.0 - clip.y / clip.w) * c.height / 2.0) + 0.5;
    const glm::dvec2 onPlane = weightsOnPlane(c, x, y, world);
    glm::dvec2 centre = onPlane;
    if (centre.x < 0.0 || centre.y < 0.0 || centre.x + centre.y > 1.0) {
        const double w0 = std::max(0.0, 1.0 - centre.x - centre.y), w1 = std::max(0.0, centre.x), w2 = std::max(0.0, centre.y);
        const double sum = w0 + w1 + w2;
        centre = sum > 0.0 ? glm::dvec2(w1 / sum, w2 / sum) : glm::dvec2(0.0);
    }
    const float w[3] = {float(1.0 - centre.x - centre.y), float(centre.x), float(centre.y)};
    float alpha = state.constantColor.a;
    const size_t vertexCount = call.positions.size();
    if (call.vertexAlphas.size() == vertexCount && vertexCount > 0) {
        alpha = 0.0f;
        for (int k = 0; k < 3; ++k) alpha += w[k] * (state.constantColor.a * call.vertexAlphas[corner[k]]);
    }
    const raster::TextureBinding& base = state.textures.baseColor;
    if (base && call.texCoords.size() == vertexCount && vertexCount > 0) {
        const glm::vec2 uv0 = call.texCoords[corner[0]], uv1 = call.texCoords[corner[1]], uv2 = call.texCoords[corner[2]];
        const auto uvAt = [&](const glm::dvec2& wb) {
            return glm::vec2(float(1.0 - wb.x - wb.y) * uv0 + float(wb.x) * uv1 + float(wb.y) * uv2);
        };
        const glm::vec2 uv = w[0] * uv0 + w[1] * uv1 + w[2] * uv2;
        const glm::vec2 plane = uvAt(onPlane);  // unclamped, as the derivatives are
        const glm::vec2 right = uvAt(weightsOnPlane(c, x + 1.0, y, world)), down = uvAt(weightsOnPlane(c, x, y + 1.0, world));
        const glm::mat2& m = base.transform.linear;
        const raster::Texture& texture = *base.texture;
        const float lod = texture.levelOfDetail(m * (right - plane), m * (down - plane));
        alpha *= texture.sample(base.transform.apply(uv), lod).a;
    }
    return alpha >= state.alphaCutoff;
}

void gatherTracedMesh(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                      const PrimaryRayCamera* dropCulledFor, TracedMesh& mesh) {
    for (size_t d = 0; d < draws.size(); ++d) {
        if (!traced[d]) continue;
        const raster::DrawCall& call = draws[d];
        const uint32_t base = uint32_t(mesh.positions.size());
        for (const glm::vec3& p : call.positions) mesh.positions.push_back(glm::vec3(call.worldFromObject * glm::vec4(p, 1.0f)));
        const size_t vertexCount = call.positions.size();
        const raster::CullMode cull = call.state.cull;
        for (size_t t = 0; t < call.triangleCount(); ++t) {
            size_t corner[3];
            bool valid = true;
            for (int k = 0; k < 3; ++k) {
                corner[k] = call.indices.empty() ? 3 * t + k : call.indices[3 * t + k];
                valid = valid && corner[k] < vertexCount;
            }
            if (!valid) continue;  // as the front end drops it
            if (dropCulledFor && culledFor(cull, mesh.positions[base + corner[0]], mesh.positions[base + corner[1]],
                                           mesh.positions[base + corner[2]], *dropCulledFor))
                continue;
            for (int k = 0; k < 3; ++k) mesh.indices.push_back(base + uint32_t(corner[k]));
            mesh.draw.push_back(uint32_t(d));
            mesh.triangle.push_back(uint32_t(t));
            mesh.cull.push_back(dropCulledFor ? raster::CullMode::None : cull);
            mesh.alphaTested.push_back(call.state.alphaMode == raster::AlphaMode::Mask);
        }
    }
}

void traceFrame(const TracedMesh& mesh, const PrimaryRayQuery& query, const PrimaryRayCamera& camera,
                raster::VisibilityBuffer& out, PrimaryRayStats& stats) {
    const double t0 = raster::nowMs();
    const int blocksX = (out.width + kBlockPixels - 1) / kBlockPixels, blocksY = (out.height + kBlockPixels - 1) / kBlockPixels;
    std::vector<uint64_t> hits(size_t(blocksX) * size_t(blocksY), 0);
    if (!mesh.draw.empty())
        raster::parallelFor(hits.size(), [&](size_t b) {
            traceBlock(mesh, query, camera, int(b % blocksX), int(b / blocksX), out, hits[b]);
        });
    for (uint64_t h : hits) stats.hits += h;
    stats.rays = uint64_t(out.width) * uint64_t(out.height) * uint64_t(out.samples);
    stats.traceMs = raster::nowMs() - t0;
}

// One block's rays, pixel by pixel in row order and each pixel's samples in pattern order: the grid
// and the BVH take them as packets of up to 64.
void traceBlock(const TracedMesh& mesh, const PrimaryRayQuery& query, const PrimaryRayCamera& camera, int blockX, int blockY,
                raster::VisibilityBuffer& out, uint64_t& hits) {
    const int S = out.samples;
    const raster::SamplePattern& sp = raster::standardSamplePattern(S);
    const int x0 = blockX * kBlockPixels, y0 = blockY * kBlockPixels;
    const int x1 = std::min(x0 + kBlockPixels, out.width), y1 = std::min(y0 + kBlockPixels, out.height);
    // A thread's scratch, grown once: arrays for sixteen samples on the stack were as many
    // constructor runs per block as rays (48 KB written) whatever the sample count.
    thread_local std::vector<Ray> rayScratch;
    thread_local std::vector<RayHit> hitScratch;
    thread_local std::vector<size_t> whereScratch;
    const size_t most = size_t(kBlockPixels) * kBlockPixels * size_t(S);
    if (rayScratch.size() < most) rayScratch.resize(most), hitScratch.resize(most), whereScratch.resize(most);
    Ray* rays = rayScratch.data();
    RayHit* found = hitScratch.data();
    size_t* where = whereScratch.data();
    int n = 0;
    constexpr double kSampleOffsetUnitPixels = double(raster::kSampleOffsetUnitSubpixels) / raster::kSubpixelsPerPixel;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int s = 0; s < S; ++s) {
                rays[n] = primaryRay(camera, x + 0.5 + sp.dx[s] * kSampleOffsetUnitPixels, y + 0.5 + sp.dy[s] * kSampleOffsetUnitPixels,
                                    out.width, out.height);
                where[n++] = (size_t(y) * size_t(out.width) + size_t(x)) * size_t(S) + size_t(s);
            }
    if (query.grid)
        closestHits(*query.grid, query.mesh, std::span<const Ray>(rays, size_t(n)), std::span<RayHit>(found, size_t(n)), nullptr,
                    query.filter);
    else
        query.bvh->closestHits(std::span<const Ray>(rays, size_t(n)), std::span<RayHit>(found, size_t(n)), *query.filter);
    for (int i = 0; i < n; ++i) {
        if (!found[i].hit()) continue;
        ++hits;
        out.draw[where[i]] = mesh.draw[found[i].triangle];
        out.triangle[where[i]] = mesh.triangle[found[i].triangle];
    }
}

}  // namespace
}  // namespace cuberille::rt
