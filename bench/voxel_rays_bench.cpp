// Voxel ray tracing through a BVH, a kD tree and an octree: Chajdas's chapter 5 comparison
// (Tables 10-13) on this CPU, with Embree tracing the same voxels' exposed faces in the same run.
//
//   voxel_rays_bench [--models dragon,bunny] [--resolutions 1024,2048] [--threads 2]
//                    [--width 1280 --height 720] [--samples 36] [--lanes 16]
//
// Per model and resolution: voxelize (six-separating, §5.3), build the three trees (Table 11's
// sizes), then trace his four ray types at 1280x720 — primary; shadow rays to a directional
// light; soft shadows, `samples` rays a pixel in a narrow cone toward it; ambient occlusion,
// `samples` cosine-distributed rays a pixel no longer than a third of the scene (§5.4) — and for
// each tree report rays a second, interior nodes and leaves visited a ray, and the share of lanes
// doing useful work when `lanes` rays (and 64, the paper's GPU wavefront) run the traversal loop
// in lockstep, simulated from each ray's steps (rt/voxel_rays.h). Table 10: the same rays with
// the paper's short stack (8 entries for the BVH, 4 for the others), without a stack (restart
// after every leaf) and with a full stack.
//
// Every tree's primary hits are checked against the others' (they must be the same voxel at
// every pixel) and Embree's against theirs (it may differ only where a ray grazes an edge).

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <numbers>

#include <tbb/combinable.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "bench/bench_support.h"
#include "raster/clock.h"
#include "rt/voxel_trees.h"
#include "rt/wide_voxel_bvh.h"
#include "voxel/mesh_view.h"
#include "voxel/octree_voxelizer.h"

#ifdef CUBERILLE_WITH_EMBREE
#include <embree3/rtcore.h>
#endif

namespace {

using namespace cuberille;
namespace fs = std::filesystem;

// ---- The scene: one level of voxels, a camera and a light in grid units ----------------------

struct VoxelScene {
    std::vector<rt::VoxelCoord> voxels;
    glm::vec3 lo{0.0f}, hi{0.0f};  // tight bounds, grid units
    double voxelizeMs = 0;
};

VoxelScene voxelizeScan(const fs::path& path, uint32_t resolution) {
    VoxelScene s;
    const auto view = voxel::openMeshView(path, nullptr);
    voxel::VoxelizeOptions o;
    o.resolution = resolution;
    o.separability = voxel::Separability::Six;
    o.keepSourceTriangles = false;
    const double start = raster::nowMs();
    const voxel::VoxelModel model = voxel::voxelizeMesh(*view, o);
    s.voxelizeMs = raster::nowMs() - start;
    s.voxels.reserve(model.voxelCount());
    glm::uvec3 lo(~0u), hi(0u);
    for (const voxel::VoxelBlock& b : model.blocks)
        for (size_t i = 0; i < b.voxels.size(); ++i) {
            const glm::uvec3 p = model.gridPosition(b, i);
            s.voxels.push_back({uint16_t(p.x), uint16_t(p.y), uint16_t(p.z)});
            lo = glm::min(lo, p);
            hi = glm::max(hi, p + 1u);
        }
    s.lo = glm::vec3(lo);
    s.hi = glm::vec3(hi);
    return s;
}

/// A pinhole camera framing the bounds from the front-right, above, as the renderer's default
/// framing does (40 degrees vertical).
struct Camera {
    glm::vec3 eye, forward, right, up;
    float tanHalf, aspect;
    rt::Ray ray(int x, int y, int width, int height) const {
        const float u = (2.0f * (float(x) + 0.5f) / float(width) - 1.0f) * tanHalf * aspect;
        const float v = (1.0f - 2.0f * (float(y) + 0.5f) / float(height)) * tanHalf;
        return rt::Ray{eye, forward + u * right + v * up, 0.0f, std::numeric_limits<float>::infinity()};
    }
};

Camera frame(const VoxelScene& s, int width, int height) {
    const glm::vec3 centre = (s.lo + s.hi) * 0.5f;
    const float radius = 0.5f * glm::length(s.hi - s.lo);
    const float fov = 40.0f * std::numbers::pi_v<float> / 180.0f;
    const glm::vec3 toEye = glm::normalize(glm::vec3(0.5f, 0.35f, 1.0f));
    Camera c;
    c.eye = centre + toEye * (radius / std::sin(fov * 0.5f));
    c.forward = -toEye;
    c.right = glm::normalize(glm::cross(c.forward, glm::vec3(0, 1, 0)));
    c.up = glm::cross(c.right, c.forward);
    c.tanHalf = std::tan(fov * 0.5f);
    c.aspect = float(width) / float(height);
    return c;
}

const glm::vec3 kToLight = glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f));

/// A primary hit, where the secondary rays leave from: on the entered face's plane exactly, so
/// the hit rule needs no offset (rt/voxel_rays.h).
struct SurfacePoint {
    bool valid = false;
    glm::vec3 position{0.0f}, normal{0.0f};
};

SurfacePoint surfaceOf(const rt::Ray& primary, const rt::VoxelHit& h, const rt::VoxelCoord& v) {
    SurfacePoint p;
    if (!h.hit() || h.axis < 0) return p;
    const rt::VoxelRay ray(primary);
    p.position = h.entryPoint(ray, v);
    p.normal = h.faceNormal(ray);
    p.valid = true;
    return p;
}

/// Stratified sample k of n = m x m in the unit square, rotated per pixel (Cranley-Patterson) by a
/// hash of the pixel so neighbouring pixels do not repeat one pattern.
glm::vec2 stratified(int k, int m, uint32_t pixel) {
    uint32_t h = pixel * 0x9E3779B1u;
    h ^= h >> 15;
    h *= 0x85EBCA77u;
    h ^= h >> 13;
    const float jx = float(h & 0xFFFF) / 65536.0f, jy = float(h >> 16) / 65536.0f;
    const float u = std::fmod((float(k % m) + 0.5f) / float(m) + jx, 1.0f);
    const float v = std::fmod((float(k / m) + 0.5f) / float(m) + jy, 1.0f);
    return {u, v};
}

void basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
    t = glm::normalize(std::abs(n.x) > 0.5f ? glm::cross(n, glm::vec3(0, 1, 0)) : glm::cross(n, glm::vec3(1, 0, 0)));
    b = glm::cross(n, t);
}

enum class RayType { Primary, Shadow, Soft, Ao };
const char* rayTypeName(RayType t) {
    switch (t) {
        case RayType::Primary: return "primary";
        case RayType::Shadow: return "shadow";
        case RayType::Soft: return "soft";
        case RayType::Ao: return "ao";
    }
    return "?";
}

/// The rays of one pixel of a ray type (none where the pixel's primary ray missed).
struct RayMaker {
    const Camera& camera;
    int width, height, samples;
    float aoLength;
    float softConeRadians = 5.0f * std::numbers::pi_v<float> / 180.0f;

    void raysOf(RayType type, int x, int y, const SurfacePoint& p, std::vector<rt::Ray>& out) const {
        out.clear();
        if (type == RayType::Primary) {
            out.push_back(camera.ray(x, y, width, height));
            return;
        }
        if (!p.valid) return;
        const uint32_t pixel = uint32_t(y * width + x);
        if (type == RayType::Shadow) {
            out.push_back(rt::Ray{p.position, kToLight, 0.0f, std::numeric_limits<float>::infinity()});
            return;
        }
        const int m = int(std::lround(std::sqrt(double(samples))));
        glm::vec3 t, b;
        if (type == RayType::Soft) {
            basis(kToLight, t, b);
            const float spread = std::tan(softConeRadians);
            for (int k = 0; k < m * m; ++k) {
                const glm::vec2 s = stratified(k, m, pixel);
                const float r = spread * std::sqrt(s.x), phi = 2.0f * std::numbers::pi_v<float> * s.y;
                out.push_back(rt::Ray{p.position, kToLight + r * (std::cos(phi) * t + std::sin(phi) * b), 0.0f,
                                      std::numeric_limits<float>::infinity()});
            }
            return;
        }
        basis(p.normal, t, b);
        for (int k = 0; k < m * m; ++k) {  // cosine-distributed about the face normal
            const glm::vec2 s = stratified(k, m, pixel);
            const float r = std::sqrt(s.x), phi = 2.0f * std::numbers::pi_v<float> * s.y;
            const glm::vec3 d = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0f, 1.0f - s.x)) * p.normal;
            out.push_back(rt::Ray{p.position, d, 0.0f, aoLength});
        }
    }
};

// ---- Tracing a frame's rays of one type through one tree -------------------------------------

struct PassResult {
    double ms = 0;
    rt::VoxelTraversalCounters counters;
    rt::LaneOccupancy lanes, wavefront;  // `lanes` wide and 64 wide
};

constexpr int kTile = 8;

using TraceFn = std::function<rt::VoxelHit(const rt::VoxelRay&, const rt::VoxelTraversal&, rt::VoxelTraversalCounters*,
                                           rt::VoxelStepTrace*)>;

/// Every pixel's rays of `type`, 8x8 tiles spread over the threads. With `occupancy`, untimed:
/// each tile's rays keep their step traces for the lockstep simulation.
PassResult tracePass(const TraceFn& trace, const RayMaker& maker, RayType type, const std::vector<SurfacePoint>& surface,
                     const rt::VoxelTraversal& how, bool occupancy, int lanes, std::vector<rt::VoxelHit>* primaryHits) {
    const int tilesX = (maker.width + kTile - 1) / kTile, tilesY = (maker.height + kTile - 1) / kTile;
    tbb::combinable<rt::VoxelTraversalCounters> counters;
    tbb::combinable<rt::LaneOccupancy> laneShare, waveShare;
    const double start = raster::nowMs();
    tbb::parallel_for(0, tilesX * tilesY, [&](int tile) {
        std::vector<rt::Ray> rays;
        std::vector<rt::VoxelStepTrace> traces;
        rt::VoxelTraversalCounters& c = counters.local();
        const int x0 = (tile % tilesX) * kTile, y0 = (tile / tilesX) * kTile;
        for (int y = y0; y < std::min(y0 + kTile, maker.height); ++y)
            for (int x = x0; x < std::min(x0 + kTile, maker.width); ++x) {
                const size_t pixel = size_t(y) * size_t(maker.width) + size_t(x);
                maker.raysOf(type, x, y, surface.empty() ? SurfacePoint{} : surface[pixel], rays);
                for (const rt::Ray& r : rays) {
                    rt::VoxelStepTrace* steps = nullptr;
                    if (occupancy) steps = &traces.emplace_back();
                    const rt::VoxelHit h = trace(rt::VoxelRay(r), how, &c, steps);
                    if (primaryHits) (*primaryHits)[pixel] = h;
                }
            }
        if (occupancy) {
            laneShare.local().add(rt::voxelLaneOccupancy(traces, lanes));
            waveShare.local().add(rt::voxelLaneOccupancy(traces, 64));
        }
    });
    PassResult r;
    r.ms = raster::nowMs() - start;
    counters.combine_each([&](const rt::VoxelTraversalCounters& c) { r.counters.add(c); });
    laneShare.combine_each([&](const rt::LaneOccupancy& o) { r.lanes.add(o); });
    waveShare.combine_each([&](const rt::LaneOccupancy& o) { r.wavefront.add(o); });
    return r;
}

// ---- Embree over the exposed faces -----------------------------------------------------------

#ifdef CUBERILLE_WITH_EMBREE
/// The voxels' faces that no neighbour covers, as Embree quads: the surface a ray from outside
/// meets, so its hits name the same voxels as ours but where a ray grazes an edge.
class EmbreeVoxelFaces {
public:
    EmbreeVoxelFaces(RTCDevice device, const std::vector<rt::VoxelCoord>& voxels) {
        std::vector<uint64_t> keys(voxels.size());
        for (size_t i = 0; i < voxels.size(); ++i) keys[i] = rt::voxelKey(voxels[i]);
        std::sort(keys.begin(), keys.end());
        auto occupied = [&](int x, int y, int z) {
            if (x < 0 || y < 0 || z < 0 || x > 0xFFFF || y > 0xFFFF || z > 0xFFFF) return false;
            return std::binary_search(keys.begin(), keys.end(), rt::voxelKey({uint16_t(x), uint16_t(y), uint16_t(z)}));
        };
        for (uint32_t i = 0; i < voxels.size(); ++i) {
            const glm::ivec3 p(voxels[i].x, voxels[i].y, voxels[i].z);
            for (int a = 0; a < 3; ++a)
                for (int side = 0; side < 2; ++side) {
                    glm::ivec3 n = p;
                    n[a] += side ? 1 : -1;
                    if (occupied(n.x, n.y, n.z)) continue;
                    const int b = (a + 1) % 3, c = (a + 2) % 3;
                    glm::vec3 corner = glm::vec3(p);
                    corner[a] += float(side);
                    const uint32_t base = uint32_t(vertices_.size());
                    for (int k = 0; k < 4; ++k) {
                        glm::vec3 q = corner;
                        q[b] += float(k == 1 || k == 2);
                        q[c] += float(k >= 2);
                        vertices_.push_back(q);
                    }
                    quads_.insert(quads_.end(), {base, base + 1, base + 2, base + 3});
                    faceVoxel_.push_back(i);
                }
        }
        vertices_.emplace_back(0.0f);  // Embree reads 16 bytes at the last vertex
        scene_ = rtcNewScene(device);
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_.data(), 0, sizeof(glm::vec3),
                                   vertices_.size() - 1);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, quads_.data(), 0, 4 * sizeof(uint32_t),
                                   faceVoxel_.size());
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene_, g);
        rtcReleaseGeometry(g);
        const double start = raster::nowMs();
        rtcCommitScene(scene_);
        buildMs = raster::nowMs() - start;
    }
    ~EmbreeVoxelFaces() { rtcReleaseScene(scene_); }
    size_t faces() const { return faceVoxel_.size(); }

    /// Closest (the voxel whose face is hit) or any hit, as our traces report them.
    rt::VoxelHit trace(const rt::VoxelRay& r, const rt::VoxelTraversal& how) const {
        rt::VoxelHit h;
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        if (how.anyHit) {
            RTCRay ray{};
            ray.org_x = r.origin.x, ray.org_y = r.origin.y, ray.org_z = r.origin.z;
            ray.dir_x = r.direction.x, ray.dir_y = r.direction.y, ray.dir_z = r.direction.z;
            // Rays leave from a face: Embree needs tnear past it not to hit that face again.
            ray.tnear = r.tMin + kEmbreeNear, ray.tfar = r.tMax, ray.mask = ~0u;
            rtcOccluded1(scene_, &context, &ray);
            if (ray.tfar < 0.0f) h.voxel = 0;
            return h;
        }
        RTCRayHit rh{};
        rh.ray.org_x = r.origin.x, rh.ray.org_y = r.origin.y, rh.ray.org_z = r.origin.z;
        rh.ray.dir_x = r.direction.x, rh.ray.dir_y = r.direction.y, rh.ray.dir_z = r.direction.z;
        rh.ray.tnear = r.tMin, rh.ray.tfar = r.tMax, rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &context, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
            h.voxel = faceVoxel_[rh.hit.primID];
            h.t = rh.ray.tfar;
        }
        return h;
    }
    double buildMs = 0;

private:
    /// Embree's self-intersection guard for rays leaving a face, in voxel units (ours needs none).
    static constexpr float kEmbreeNear = 1e-3f;
    std::vector<glm::vec3> vertices_;
    std::vector<uint32_t> quads_;
    std::vector<uint32_t> faceVoxel_;
    RTCScene scene_;
};
#endif

// ---- One model at one resolution ---------------------------------------------------------------

struct Tree {
    std::string name;
    int paperStack;  // §5.4.4, Table 10: 8 entries for the BVH, 4 for the kD tree and octree
    TraceFn trace;
    rt::VoxelTreeSize size;
    double buildMs;
};

double mib(uint64_t bytes) { return double(bytes) / double(1 << 20); }

/// The most voxels Embree is given: the dragon at 4096³ (24.5 M voxels, 25 M exposed faces) ran
/// in 24 GiB; the bunny at 4096³ (33.8 M) ran out of it while Embree built.
constexpr size_t kEmbreeMaxVoxels = 25'000'000;

void benchModel(const std::string& name, uint32_t resolution, int width, int height, int samples, int lanes,
                void* embreeDevice) {
    const fs::path path = bench::scanPath(name, CUBERILLE_SOURCE_DIR);
    if (!fs::exists(path)) {
        std::printf("%s: %s not found, skipped\n", name.c_str(), path.string().c_str());
        return;
    }
    const VoxelScene scene = voxelizeScan(path, resolution);
    std::printf("\n## %s at %u^3: %zu voxels (six-separating), voxelized in %.0f ms\n\n", name.c_str(), resolution,
                scene.voxels.size(), scene.voxelizeMs);

    std::vector<Tree> trees;
    {
        double start = raster::nowMs();
        auto bvh = std::make_shared<rt::VoxelBvh>(scene.voxels);
        trees.push_back({"bvh", 8, [bvh](auto&&... a) { return bvh->trace(a...); }, bvh->size(), raster::nowMs() - start});
        start = raster::nowMs();
        auto kd = std::make_shared<rt::VoxelKdTree>(scene.voxels);
        trees.push_back({"kdtree", 4, [kd](auto&&... a) { return kd->trace(a...); }, kd->size(), raster::nowMs() - start});
        start = raster::nowMs();
        auto octree = std::make_shared<rt::VoxelOctree>(scene.voxels);
        trees.push_back({"octree", 4, [octree](auto&&... a) { return octree->trace(a...); }, octree->size(), raster::nowMs() - start});
        // The BVH again with eight children a node in vector lanes (rt/wide_voxel_bvh.h): its build
        // time is the binary build's and the collapse; it keeps a full stack (no short-stack runs).
        start = raster::nowMs();
        auto wide = std::make_shared<rt::WideVoxelBvh>(scene.voxels);
        trees.push_back({"bvh8", rt::VoxelTraversal::kFullStack, [wide](auto&&... a) { return wide->trace(a...); }, wide->size(),
                         raster::nowMs() - start});
    }
    std::printf("| tree | build ms | interior nodes | MiB | leaves | null | MiB | deepest | mean leaf depth |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const Tree& t : trees)
        std::printf("| %s | %.0f | %llu | %.1f | %llu | %llu | %.1f | %d | %.1f |\n", t.name.c_str(), t.buildMs,
                    (unsigned long long)t.size.interiorNodes, mib(t.size.interiorBytes), (unsigned long long)t.size.leaves,
                    (unsigned long long)t.size.nullLeaves, mib(t.size.leafBytes), t.size.depth, t.size.meanLeafDepth);

    const Camera camera = frame(scene, width, height);
    const glm::vec3 extent = scene.hi - scene.lo;
    const RayMaker maker{camera, width, height, samples, std::max({extent.x, extent.y, extent.z}) / 3.0f};

    // Primary hits from the first tree; every other tree must agree at every pixel.
    const size_t pixels = size_t(width) * size_t(height);
    std::vector<rt::VoxelHit> reference(pixels), other(pixels);
    tracePass(trees[0].trace, maker, RayType::Primary, {}, {}, false, lanes, &reference);
    for (size_t k = 1; k < trees.size(); ++k) {
        tracePass(trees[k].trace, maker, RayType::Primary, {}, {}, false, lanes, &other);
        size_t differ = 0;
        for (size_t i = 0; i < pixels; ++i) differ += other[i].voxel != reference[i].voxel || other[i].t != reference[i].t;
        if (differ) std::printf("\n**%s and %s disagree at %zu pixels**\n", trees[0].name.c_str(), trees[k].name.c_str(), differ);
    }
    std::vector<SurfacePoint> surface(pixels);
    size_t covered = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            if (reference[i].hit())
                surface[i] = surfaceOf(camera.ray(x, y, width, height), reference[i], scene.voxels[reference[i].voxel]);
            covered += surface[i].valid ? 1 : 0;
        }
    std::printf("\n%zu of %zu pixels cover the model; %d secondary rays a pixel for soft shadows and AO (AO at most %.0f voxels)\n",
                covered, pixels, samples, maker.aoLength);

    const RayType types[] = {RayType::Primary, RayType::Shadow, RayType::Soft, RayType::Ao};
    std::printf("\nRays through each tree with the paper's short stack: million rays a second, ms for the frame's rays, interior nodes and leaves a ray, "
                "lanes busy in %d-wide and 64-wide lockstep (simulated)\n\n", lanes);
    std::printf("| tree | rays | Mrays/s | ms | interior/ray | leaves/ray | voxels/ray | %d lanes | 64 lanes |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n", lanes);
    std::vector<std::array<double, 3>> stackMs(trees.size() * 4);
    for (size_t k = 0; k < trees.size(); ++k)
        for (int ti = 0; ti < 4; ++ti) {
            const RayType type = types[ti];
            const bool anyHit = type != RayType::Primary;
            const int stacks[3] = {trees[k].paperStack, 0, rt::VoxelTraversal::kFullStack};
            PassResult timed;
            // A tree that always keeps a full stack (bvh8) has nothing to compare across stacks.
            const int stackRuns = trees[k].paperStack == rt::VoxelTraversal::kFullStack ? 1 : 3;
            stackMs[k * 4 + size_t(ti)] = {NAN, NAN, NAN};
            for (int s = 0; s < stackRuns; ++s) {
                std::vector<double> ms;
                PassResult r;
                for (int rep = 0; rep < 3; ++rep) {
                    r = tracePass(trees[k].trace, maker, type, surface, {.stackEntries = stacks[s], .anyHit = anyHit}, false, lanes, nullptr);
                    ms.push_back(r.ms);
                }
                r.ms = bench::median(ms);
                stackMs[k * 4 + size_t(ti)][size_t(s)] = r.ms;
                if (s == 0) timed = r;
            }
            const PassResult occ = tracePass(trees[k].trace, maker, type, surface, {.stackEntries = stacks[0], .anyHit = anyHit}, true, lanes, nullptr);
            const double rays = double(timed.counters.rays);
            std::printf("| %s | %s | %.2f | %.1f | %.1f | %.2f | %.1f | %.1f%% | %.1f%% |\n", trees[k].name.c_str(), rayTypeName(type),
                        rays / timed.ms / 1e3, timed.ms, double(timed.counters.interiorSteps) / rays,
                        double(timed.counters.leafSteps) / rays, double(timed.counters.voxelTests) / rays,
                        100.0 * occ.lanes.share(), 100.0 * occ.wavefront.share());
        }
    std::printf("\nTable 10 on this CPU: ms for the frame's rays with the short stack, without a stack (restart after every leaf) and with a full stack\n\n");
    std::printf("| tree | rays | short stack | no stack | full stack |\n|---|---|---:|---:|---:|\n");
    for (size_t k = 0; k < trees.size(); ++k)
        for (int ti = 0; ti < 4; ++ti) {
            const auto& m = stackMs[k * 4 + size_t(ti)];
            if (std::isnan(m[1]))
                std::printf("| %s (full) | %s | %.1f | — | — |\n", trees[k].name.c_str(), rayTypeName(types[ti]), m[0]);
            else
                std::printf("| %s (%d) | %s | %.1f | %.1f | %.1f |\n", trees[k].name.c_str(), trees[k].paperStack, rayTypeName(types[ti]), m[0], m[1], m[2]);
        }

#ifdef CUBERILLE_WITH_EMBREE
    std::vector<std::string> treeNames;
    for (const Tree& t : trees) treeNames.push_back(t.name);
    trees.clear();  // their memory, for Embree's
    if (embreeDevice && scene.voxels.size() > kEmbreeMaxVoxels) {
        std::printf("\nEmbree left out: %zu voxels is over %zu, past which its faces and tree outgrow this machine's memory\n",
                    scene.voxels.size(), kEmbreeMaxVoxels);
    } else if (embreeDevice) {
        const EmbreeVoxelFaces embree(static_cast<RTCDevice>(embreeDevice), scene.voxels);
        std::printf("\nEmbree %s over the %zu exposed faces as quads (built in %.0f ms), the same rays; ratio: the fastest tree's rays a second over Embree's\n\n",
                    RTC_VERSION_STRING, embree.faces(), embree.buildMs);
        std::printf("| rays | Embree Mrays/s | fastest tree | ratio | primary hits on another voxel |\n|---|---:|---|---:|---:|\n");
        const TraceFn embreeTrace = [&](const rt::VoxelRay& r, const rt::VoxelTraversal& how, rt::VoxelTraversalCounters* c,
                                        rt::VoxelStepTrace*) {
            const rt::VoxelHit h = embree.trace(r, how);
            if (c) ++c->rays;
            return h;
        };
        for (int ti = 0; ti < 4; ++ti) {
            const RayType type = types[ti];
            std::vector<double> ms;
            PassResult r;
            for (int rep = 0; rep < 3; ++rep) {
                r = tracePass(embreeTrace, maker, type, surface, {.anyHit = type != RayType::Primary}, false, lanes,
                              type == RayType::Primary ? &other : nullptr);
                ms.push_back(r.ms);
            }
            const double embreeRate = double(r.counters.rays) / bench::median(ms) / 1e3;
            size_t best = 0;
            for (size_t k = 1; k < treeNames.size(); ++k)
                if (stackMs[k * 4 + size_t(ti)][0] < stackMs[best * 4 + size_t(ti)][0]) best = k;
            const double oursRate = double(r.counters.rays) / stackMs[best * 4 + size_t(ti)][0] / 1e3;
            size_t differ = 0;
            if (type == RayType::Primary)
                for (size_t i = 0; i < pixels; ++i) differ += other[i].voxel != reference[i].voxel;
            std::printf("| %s | %.2f | %s | %.2f | %s |\n", rayTypeName(type), embreeRate, treeNames[best].c_str(),
                        oursRate / embreeRate, type == RayType::Primary ? std::to_string(differ).c_str() : "");
        }
    }
#endif
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Voxel ray tracing through a BVH, a kD tree and an octree (Chajdas 2015, chapter 5), Embree beside"};
    std::string models = "dragon,bunny", resolutions = "1024,2048";
    int threads = 0, width = 1280, height = 720, samples = 36, lanes = 16;
    app.add_option("--models", models, "bunny, dragon, horse, or mesh paths")->capture_default_str();
    app.add_option("--resolutions", resolutions, "Voxelization resolutions (powers of two up to 65536)")->capture_default_str();
    app.add_option("--threads", threads, "0: every core")->capture_default_str();
    app.add_option("--width", width)->capture_default_str();
    app.add_option("--height", height)->capture_default_str();
    app.add_option("--samples", samples, "Soft-shadow and AO rays a pixel (a square: 36 as the paper)")->capture_default_str();
    app.add_option("--lanes", lanes, "Lanes of the simulated lockstep traversal (16: AVX-512 floats)")->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
    void* device = nullptr;
#ifdef CUBERILLE_WITH_EMBREE
    const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : "";
    RTCDevice embree = rtcNewDevice(config.c_str());
    device = embree;
#endif
    std::printf("# voxel_rays_bench --models %s --resolutions %s --threads %d, %dx%d\n", models.c_str(), resolutions.c_str(),
                threads, width, height);
    for (const std::string& m : bench::splitList(models))
        for (const std::string& r : bench::splitList(resolutions))
            benchModel(m, uint32_t(std::stoul(r)), width, height, samples, lanes, device);
#ifdef CUBERILLE_WITH_EMBREE
    rtcReleaseDevice(embree);
#endif
    return 0;
}
