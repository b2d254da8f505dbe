// BVHs and shadows, side by side with Embree in the same run (docs/performance.md).
//
//   bvh_bench [--models dragon,horse,1m] [--animation brainstem] [--shadow-scenes vc,dragon,brainstem]
//             [--frame-scenes vc,helmet,brainstem,dragon]
//
// Part 1, per model: build (binned SAH against Embree's default quality, spatial median against
// Embree's low quality), refit after a deformation (ours, full and lazy, against Embree's refit
// quality), and ray throughput (closest hit for random rays, any hit for shadow rays from the
// surface) against Embree's rtcIntersect1 / rtcOccluded1, one ray at a time on every core.
// Part 2: a skinned animation, every frame refitted, lazily updated and rebuilt, with
// Lauterbach's degradation. Part 3: each shadow mode and map size, its time and the share of
// pixels that differ from the ray-traced reference. Part 4: the renderer's camera-ray stage on each
// frame scene beside Embree's rays.

#include <embree3/rtcore.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "render/scene_shadows.h"
#include "bench/bench_support.h"
#include "bench/procedural_meshes.h"
#include "raster/clock.h"
#include "raster/parallel.h"
#include "rt/ambient_occlusion.h"
#include "rt/bvh_build.h"
#include "rt/bvh_refit.h"
#include "rt/lazy_refit.h"
#include "rt/primary_rays.h"
#include "rt/ray_query.h"
#include "rt/uniform_grid.h"
#include "rt/wide_bvh.h"
#include "scene/model_scene.h"

namespace {

using namespace cuberille;
namespace fs = std::filesystem;

struct Geometry {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    rt::TriangleMeshView view() const { return {positions, indices}; }
    size_t triangles() const { return indices.size() / 3; }
};

fs::path dataPath(const std::string& name) {
    const fs::path data = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data";
    if (name == "vc") return data / "gltf" / "VC" / "VC.glb";
    if (name == "brainstem") return data / "gltf" / "BrainStem" / "BrainStem.glb";
    if (name == "cesiumman") return data / "gltf" / "CesiumMan" / "CesiumMan.glb";
    if (name == "helmet") return data / "gltf" / "DamagedHelmet" / "DamagedHelmet.glb";
    return bench::scanPath(name, CUBERILLE_SOURCE_DIR);
}

std::optional<scene::Scene> loadScene(const std::string& name, float time = 0.0f) {
    const fs::path path = dataPath(name);
    if (!fs::exists(path)) return std::nullopt;
    scene::ModelSceneOptions options;  // the default framing
    options.timeSeconds = time;
    return scene::loadModelScene(path, options, [](const std::string&) {});
}

Geometry concatenate(const scene::Scene& s) {
    Geometry g;
    for (const scene::Mesh& m : s.meshes) {
        const uint32_t base = uint32_t(g.positions.size());
        g.positions.insert(g.positions.end(), m.positions.begin(), m.positions.end());
        for (uint32_t i : m.indices) g.indices.push_back(base + i);
    }
    return g;
}

std::optional<Geometry> loadGeometry(const std::string& name) {
    if (name == "1m" || name == "10m") {
        const scene::Mesh m = bench::bumpySphere(name == "1m" ? 1'000'000ull : 10'000'000ull);
        return Geometry{m.positions, m.indices};
    }
    const auto s = loadScene(name);
    if (!s) return std::nullopt;
    return concatenate(*s);
}

template <class F>
double medianMs(int runs, F&& f) {
    std::vector<double> t;
    for (int i = 0; i < runs; ++i) {
        const double t0 = raster::nowMs();
        f();
        t.push_back(raster::nowMs() - t0);
    }
    return bench::median(t);
}

// ---- Embree ---------------------------------------------------------------------------------

class EmbreeScene {
public:
    EmbreeScene(RTCDevice device, const Geometry& g, RTCBuildQuality quality, bool refittable)
        : vertices_(g.positions.size() + 1) {  // Embree reads 16 bytes at the last vertex: pad
        std::copy(g.positions.begin(), g.positions.end(), vertices_.begin());
        scene_ = rtcNewScene(device);
        rtcSetSceneBuildQuality(scene_, quality);
        if (refittable) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_DYNAMIC);
        geometry_ = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetSharedGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_.data(), 0,
                                   sizeof(glm::vec3), g.positions.size());
        rtcSetSharedGeometryBuffer(geometry_, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, g.indices.data(), 0,
                                   3 * sizeof(uint32_t), g.triangles());
        rtcSetGeometryBuildQuality(geometry_, refittable ? RTC_BUILD_QUALITY_REFIT : quality);
        rtcCommitGeometry(geometry_);
        rtcAttachGeometry(scene_, geometry_);
    }
    ~EmbreeScene() {
        rtcReleaseGeometry(geometry_);
        rtcReleaseScene(scene_);
    }
    void commit() { rtcCommitScene(scene_); }
    void update(const std::vector<glm::vec3>& positions) {
        std::copy(positions.begin(), positions.end(), vertices_.begin());
        rtcUpdateGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(geometry_);
        rtcCommitScene(scene_);
    }
    bool closest(const rt::Ray& r, uint32_t* triangle) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit h{};
        h.ray.org_x = r.origin.x, h.ray.org_y = r.origin.y, h.ray.org_z = r.origin.z;
        h.ray.dir_x = r.direction.x, h.ray.dir_y = r.direction.y, h.ray.dir_z = r.direction.z;
        h.ray.tnear = r.tMin, h.ray.tfar = r.tMax, h.ray.mask = ~0u;
        h.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &context, &h);
        *triangle = h.hit.primID;
        return h.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    bool occluded(const rt::Ray& r) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRay ray{};
        ray.org_x = r.origin.x, ray.org_y = r.origin.y, ray.org_z = r.origin.z;
        ray.dir_x = r.direction.x, ray.dir_y = r.direction.y, ray.dir_z = r.direction.z;
        ray.tnear = r.tMin, ray.tfar = r.tMax, ray.mask = ~0u;
        rtcOccluded1(scene_, &context, &ray);
        return ray.tfar < 0.0f;
    }

private:
    std::vector<glm::vec3> vertices_;
    RTCScene scene_;
    RTCGeometry geometry_;
};

/// A wave through the model: every vertex moves, neighbours together.
std::vector<glm::vec3> deformed(const Geometry& g, float amount) {
    rt::Aabb b;
    for (const glm::vec3& p : g.positions) b.grow(p);
    const float size = glm::length(b.extent());
    std::vector<glm::vec3> out(g.positions.size());
    for (size_t i = 0; i < out.size(); ++i) {
        const glm::vec3 p = g.positions[i];
        out[i] = p + amount * size * glm::vec3(std::sin(6.0f * p.y / size), std::sin(6.0f * p.z / size), std::sin(6.0f * p.x / size));
    }
    return out;
}

/// Camera-like rays at the model (closest hit) and shadow rays from points on it toward a light.
void makeRays(const Geometry& g, std::vector<rt::Ray>& primary, std::vector<rt::Ray>& shadow, size_t count) {
    rt::Aabb b;
    for (const glm::vec3& p : g.positions) b.grow(p);
    const glm::vec3 c = b.centre();
    const float r = 0.5f * glm::length(b.extent());
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const glm::vec3 light = glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f));
    for (size_t i = 0; i < count; ++i) {
        const glm::vec3 from = c + 2.5f * r * glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
        const glm::vec3 to = c + 0.5f * r * glm::vec3(unit(rng), unit(rng), unit(rng));
        const size_t t = rng() % g.triangles();
        float u = 0.5f * (unit(rng) + 1.0f), v = 0.5f * (unit(rng) + 1.0f);
        if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
        const glm::vec3 p0 = g.positions[g.indices[3 * t]], p1 = g.positions[g.indices[3 * t + 1]], p2 = g.positions[g.indices[3 * t + 2]];
        const glm::vec3 cross = glm::cross(p1 - p0, p2 - p0);
        if (!(glm::length(cross) > 0.0f)) {  // degenerate: no normal to leave it by
            --i;
            continue;
        }
        const glm::vec3 n = glm::normalize(cross);
        const glm::vec3 p = p0 + u * (p1 - p0) + v * (p2 - p0) + n * (1e-4f * r) * (glm::dot(n, light) >= 0 ? 1.0f : -1.0f);
        primary.push_back(rt::Ray{from, to - from});
        shadow.push_back(rt::Ray{p, light});
    }
}

template <class F>
double raysPerSecondM(size_t rays, F&& trace) {
    constexpr size_t kChunk = 4096;
    const double ms = medianMs(3, [&] {
        raster::parallelFor((rays + kChunk - 1) / kChunk, [&](size_t c) {
            for (size_t i = c * kChunk; i < std::min(rays, (c + 1) * kChunk); ++i) trace(i);
        });
    });
    return double(rays) / ms / 1000.0;
}

// ---- part 1b: coherent rays through the grid (Wald et al. 2006, Tables 1, 3 and 4) ----------

/// A 1024x1024 camera's primary rays at the model (its bounding sphere filling the view), one per
/// pixel centre, in square packets of `side` x `side` pixels, packets in scanline order.
std::vector<rt::Ray> cameraRays(const Geometry& g, int size, int side) {
    rt::Aabb b;
    for (const glm::vec3& p : g.positions) b.grow(p);
    const glm::vec3 c = b.centre();
    const float r = 0.5f * glm::length(b.extent());
    const glm::vec3 eye = c + 2.6f * r * glm::normalize(glm::vec3(0.4f, 0.3f, 1.0f));
    const glm::vec3 forward = glm::normalize(c - eye), right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
    const glm::vec3 up = glm::cross(right, forward);
    const float halfWidth = std::tan(glm::radians(20.0f));
    std::vector<rt::Ray> rays;
    rays.reserve(size_t(size) * size_t(size));
    for (int py = 0; py < size; py += side)
        for (int px = 0; px < size; px += side)
            for (int y = py; y < py + side; ++y)
                for (int x = px; x < px + side; ++x) {
                    const float sx = (2.0f * (float(x) + 0.5f) / float(size) - 1.0f) * halfWidth;
                    const float sy = (1.0f - 2.0f * (float(y) + 0.5f) / float(size)) * halfWidth;
                    rays.push_back(rt::Ray{eye, forward + sx * right + sy * up});
                }
    return rays;
}

/// Ambient occlusion rays (rt/ambient_occlusion.h) from the camera's hits: 8 a hit, cosine-weighted
/// about the normal facing the camera, turned per hit, reaching a tenth of the model's diagonal
/// (the renderer's default), any hit: short rays that start on the surface, where most of the
/// work is the nodes around their origin.
void benchOcclusionRays(const Geometry& g, const rt::Aabb& box, const rt::WideBvh& wide, const EmbreeScene& embree,
                        const std::vector<rt::Ray>& camera, const std::vector<rt::RayHit>& hits, float offset,
                        const std::string& name) {
    const float distance = rt::kDefaultOcclusionDistanceOfBounds * glm::length(box.extent());
    const std::vector<glm::vec3> directions = rt::occlusionDirections(8);
    std::vector<rt::Ray> rays;
    for (size_t i = 0; i < camera.size(); ++i) {
        if (!hits[i].hit()) continue;
        const uint32_t* v = &g.indices[3 * size_t(hits[i].triangle)];
        glm::vec3 n = glm::normalize(glm::cross(g.positions[v[1]] - g.positions[v[0]], g.positions[v[2]] - g.positions[v[0]]));
        if (glm::dot(n, camera[i].direction) > 0.0f) n = -n;
        const rt::Surface surface{camera[i].origin + camera[i].direction * hits[i].t, n};
        rt::openShare(surface, directions, rt::occlusionTurnRadians(int(i), 0), distance, offset, [&](const rt::Ray& r) {
            rays.push_back(r);
            return false;
        });
    }
    std::vector<uint8_t> ours(rays.size()), theirs(rays.size());
    const double wideRate = raysPerSecondM(rays.size(), [&](size_t i) { ours[i] = rt::anyHit(wide, rays[i]); });
    const double embreeRate = raysPerSecondM(rays.size(), [&](size_t i) { theirs[i] = embree.occluded(rays[i]); });
    size_t occluded = 0, differ = 0;
    for (size_t i = 0; i < rays.size(); ++i) occluded += ours[i], differ += ours[i] != theirs[i];
    std::printf("%-9s ambient occlusion rays from the camera's hits (8 a hit, reach %.3g, %.1f%% occluded), any hit, M rays/s: "
                "wide BVH %.2f, Embree %.2f | unlike Embree: %zu of %zu\n",
                name.c_str(), distance, 100.0 * double(occluded) / double(std::max<size_t>(rays.size(), 1)), wideRate, embreeRate,
                differ, rays.size());
}

void benchCoherentRays(RTCDevice device, const std::string& name, const Geometry& g, const rt::Bvh& sah, const rt::WideBvh& wide,
                       const rt::UniformGrid& grid) {
    constexpr int kSize = 1024;
    const size_t count = size_t(kSize) * kSize;
    EmbreeScene embree(device, g, RTC_BUILD_QUALITY_MEDIUM, false);
    embree.commit();
    std::vector<rt::RayHit> reference(count);
    const std::vector<rt::Ray> single = cameraRays(g, kSize, 8);
    raster::parallelFor(count, [&](size_t i) { reference[i] = rt::closestHit(sah, g.view(), single[i]); });
    size_t hitCount = 0;
    for (const rt::RayHit& h : reference) hitCount += h.hit();
    std::printf("%-9s camera 1024x1024, %.0f%% of rays hit; M rays/s, and per ray: cells visited, triangle tests; hits unlike the BVH's\n",
                name.c_str(), 100.0 * double(hitCount) / double(count));
    auto report = [&](const char* what, double mrays, const rt::GridCounters& counters, size_t differ) {
        std::printf("%-9s   %-26s %6.2f M/s | cells %6.2f  triangle tests %7.2f | %zu\n", name.c_str(), what, mrays,
                    double(counters.cellsVisited) / double(count), double(counters.trianglesTested) / double(count), differ);
    };
    auto differing = [&](const std::vector<rt::RayHit>& hits) {
        size_t d = 0;
        for (size_t i = 0; i < count; ++i) d += hits[i].triangle != reference[i].triangle || hits[i].t != reference[i].t;
        return d;
    };
    std::vector<rt::RayHit> hits(count);
    {
        const double mrays = raysPerSecondM(count, [&](size_t i) { hits[i] = rt::closestHit(sah, g.view(), single[i]); });
        report("BVH, single rays", mrays, {}, differing(hits));
    }
    {
        const double mrays = raysPerSecondM(count, [&](size_t i) { hits[i] = rt::closestHit(wide, single[i]); });
        report("wide BVH, single rays", mrays, {}, differing(hits));
    }
    {
        // The same rays as 8x8 packets through the wide tree (closestHits): one packet a tile.
        const size_t packets = count / 64;
        const double ms = medianMs(3, [&] {
            raster::parallelFor(packets, [&](size_t p) {
                rt::closestHits(wide, std::span(single).subspan(p * 64, 64), std::span(hits).subspan(p * 64, 64));
            });
        });
        report("wide BVH, 8x8 packets", double(count) / ms / 1000.0, {}, differing(hits));
    }
    {
        std::vector<uint8_t> hit(count);
        const double mrays = raysPerSecondM(count, [&](size_t i) {
            uint32_t t;
            hit[i] = embree.closest(single[i], &t);
        });
        size_t disagree = 0;
        for (size_t i = 0; i < count; ++i) disagree += bool(hit[i]) != reference[i].hit();
        std::printf("%-9s   %-26s %6.2f M/s | hit or miss unlike ours: %zu\n", name.c_str(), "Embree, rtcIntersect1", mrays, disagree);
    }
    {
        rt::GridCounters counters;
        const double mrays = raysPerSecondM(count, [&](size_t i) { hits[i] = rt::closestHit(grid, g.view(), single[i]); });
        for (size_t i = 0; i < count; i += 97) rt::closestHit(grid, g.view(), single[i], &counters);  // a sample, scaled
        counters.cellsVisited *= 97, counters.trianglesTested *= 97;
        report("grid, single rays (3D-DDA)", mrays, counters, differing(hits));
    }
    for (const int side : {4, 8}) {
        const std::vector<rt::Ray> rays = cameraRays(g, kSize, side);
        const size_t perPacket = size_t(side) * size_t(side), packets = count / perPacket;
        std::vector<rt::RayHit> packetHits(count);
        const double ms = medianMs(3, [&] {
            raster::parallelFor(packets, [&](size_t p) {
                rt::closestHits(grid, g.view(), std::span(rays).subspan(p * perPacket, perPacket),
                                std::span(packetHits).subspan(p * perPacket, perPacket));
            });
        });
        rt::GridCounters counters;
        for (size_t p = 0; p < packets; ++p)
            rt::closestHits(grid, g.view(), std::span(rays).subspan(p * perPacket, perPacket), std::span(hits).subspan(p * perPacket, perPacket),
                            &counters);
        // The single rays are in 8x8 packet order: the same order as side 8's packets, not side 4's.
        size_t differ = 0;
        if (side == 8) differ = differing(packetHits);
        else
            for (size_t i = 0; i < count; ++i) {  // recompute the reference for this packet order
                const rt::RayHit expected = rt::closestHit(sah, g.view(), rays[i]);
                differ += packetHits[i].triangle != expected.triangle || packetHits[i].t != expected.t;
            }
        char what[64];
        std::snprintf(what, sizeof what, "grid, %dx%d packets", side, side);
        report(what, double(count) / ms / 1000.0, counters, differ);
    }

    // Shadow rays toward one directional light from the camera's hits (the paper's shadow packets):
    // each 8x8 tile's hits leave their surface by 1e-4 of the model's size along the normal's
    // side that faces the light, as one packet.
    rt::Aabb box;
    for (const glm::vec3& p : g.positions) box.grow(p);
    const float offset = 1e-4f * glm::length(box.extent());
    const glm::vec3 light = glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f));
    std::vector<rt::Ray> shadow;
    std::vector<size_t> tileStart{0};
    for (size_t tile = 0; tile < count / 64; ++tile) {
        for (size_t i = tile * 64; i < tile * 64 + 64; ++i) {
            if (!reference[i].hit()) continue;
            const rt::Ray& r = single[i];
            const glm::vec3 p0 = g.positions[g.indices[3 * reference[i].triangle]], p1 = g.positions[g.indices[3 * reference[i].triangle + 1]],
                            p2 = g.positions[g.indices[3 * reference[i].triangle + 2]];
            const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
            const glm::vec3 p = r.origin + r.direction * reference[i].t + n * (offset * (glm::dot(n, light) >= 0.0f ? 1.0f : -1.0f));
            shadow.push_back(rt::Ray{p, light});
        }
        tileStart.push_back(shadow.size());
    }
    const size_t shadowCount = shadow.size();
    std::vector<uint8_t> bvhOccluded(shadowCount), occluded(shadowCount);
    const double bvhRate = raysPerSecondM(shadowCount, [&](size_t i) { bvhOccluded[i] = rt::anyHit(sah, g.view(), shadow[i]); });
    const double embreeRate = raysPerSecondM(shadowCount, [&](size_t i) { occluded[i] = embree.occluded(shadow[i]); });
    const double wideRate = raysPerSecondM(shadowCount, [&](size_t i) { occluded[i] = rt::anyHit(wide, shadow[i]); });
    size_t wideDiffer = 0;
    for (size_t i = 0; i < shadowCount; ++i) wideDiffer += occluded[i] != bvhOccluded[i];
    const double gridRate = raysPerSecondM(shadowCount, [&](size_t i) { occluded[i] = rt::anyHit(grid, g.view(), shadow[i]); });
    const double packetMs = medianMs(3, [&] {
        raster::parallelFor(tileStart.size() - 1, [&](size_t t) {
            const size_t first = tileStart[t], n = tileStart[t + 1] - first;
            rt::anyHits(grid, g.view(), std::span(shadow).subspan(first, n), std::span(occluded).subspan(first, n));
        });
    });
    size_t differ = 0;
    for (size_t i = 0; i < shadowCount; ++i) differ += occluded[i] != bvhOccluded[i];
    const double widePacketMs = medianMs(3, [&] {
        raster::parallelFor(tileStart.size() - 1, [&](size_t t) {
            const size_t first = tileStart[t], n = tileStart[t + 1] - first;
            rt::anyHits(wide, std::span(shadow).subspan(first, n), std::span(occluded).subspan(first, n));
        });
    });
    size_t widePacketDiffer = 0;
    for (size_t i = 0; i < shadowCount; ++i) widePacketDiffer += occluded[i] != bvhOccluded[i];
    std::printf("%-9s shadow rays from the camera's %zu hits, any hit, M rays/s: BVH %.2f, wide BVH %.2f, wide BVH packets (a tile's "
                "hits) %.2f, Embree %.2f, grid single %.2f, grid packets %.2f | wide BVH, its packets and the grid's unlike the "
                "BVH: %zu, %zu, %zu\n",
                name.c_str(), shadowCount, bvhRate, wideRate, double(shadowCount) / widePacketMs / 1000.0, embreeRate, gridRate,
                double(shadowCount) / packetMs / 1000.0, wideDiffer, widePacketDiffer, differ);
    benchOcclusionRays(g, box, wide, embree, single, reference, offset, name);
}

void benchModel(RTCDevice device, const std::string& name) {
    const std::optional<Geometry> g = loadGeometry(name);
    if (!g) {
        std::printf("%-9s skipped: not found\n", name.c_str());
        return;
    }
    const double mtri = double(g->triangles()) / 1e6;
    rt::Bvh sah, median;
    const double sahMs = medianMs(3, [&] { sah = rt::buildBvh(g->view(), {.method = rt::BvhBuildMethod::BinnedSah}); });
    const double medianMsValue = medianMs(3, [&] { median = rt::buildBvh(g->view(), {.method = rt::BvhBuildMethod::SpatialMedian}); });
    const double embreeMs = medianMs(3, [&] { EmbreeScene e(device, *g, RTC_BUILD_QUALITY_MEDIUM, false); e.commit(); });
    const double embreeLowMs = medianMs(3, [&] { EmbreeScene e(device, *g, RTC_BUILD_QUALITY_LOW, false); e.commit(); });

    // Refit after a deformation.
    Geometry moved = *g;
    moved.positions = deformed(*g, 0.01f);
    rt::Bvh refitted = sah;
    double degradation = 0.0;
    const double refitMs = medianMs(3, [&] { degradation = rt::refitBvh(refitted, moved.view()); });
    rt::Bvh lazyTree = sah;
    rt::LazyRefit lazy(lazyTree);
    const double lazyMs = medianMs(3, [&] { lazy.update(moved.view()); });
    EmbreeScene dynamic(device, *g, RTC_BUILD_QUALITY_REFIT, true);
    dynamic.commit();
    const double embreeRefitMs = medianMs(3, [&] { dynamic.update(moved.positions); });

    // Rays against the undeformed model.
    std::vector<rt::Ray> primary, shadow;
    const size_t rayCount = 1'000'000;
    makeRays(*g, primary, shadow, rayCount);
    EmbreeScene embree(device, *g, RTC_BUILD_QUALITY_MEDIUM, false);
    embree.commit();
    std::vector<uint8_t> ours(rayCount), theirs(rayCount);
    const double oursClosest = raysPerSecondM(rayCount, [&](size_t i) { ours[i] = rt::closestHit(sah, g->view(), primary[i]).hit(); });
    const double embreeClosest = raysPerSecondM(rayCount, [&](size_t i) {
        uint32_t t;
        theirs[i] = embree.closest(primary[i], &t);
    });
    size_t agree = 0;
    for (size_t i = 0; i < rayCount; ++i) agree += ours[i] == theirs[i];
    const double oursShadow = raysPerSecondM(rayCount, [&](size_t i) { ours[i] = rt::anyHit(sah, g->view(), shadow[i]); });
    const double embreeShadow = raysPerSecondM(rayCount, [&](size_t i) { theirs[i] = embree.occluded(shadow[i]); });
    for (size_t i = 0; i < rayCount; ++i) agree += ours[i] == theirs[i];

    std::printf("%-9s %7.2f | %8.1f %8.1f %6.2f | %8.1f %8.1f %6.2f | %7.1f %7.1f %7.1f %6.2f %6.3f | %6.2f %6.2f %5.2f | %6.2f %6.2f %5.2f | %7.4f\n",
                name.c_str(), mtri, sahMs, embreeMs, sahMs / embreeMs, medianMsValue, embreeLowMs, medianMsValue / embreeLowMs,
                refitMs, lazyMs, embreeRefitMs, refitMs / embreeRefitMs, degradation, oursClosest, embreeClosest,
                embreeClosest / oursClosest, oursShadow, embreeShadow, embreeShadow / oursShadow,
                double(agree) / double(2 * rayCount));

    // Wald et al.'s uniform grid (rt/uniform_grid.h), rebuilt from scratch as every frame of an
    // animation would, walked one ray at a time (the 3D-DDA baseline of the paper's packets) over
    // the same rays; its hits must be the BVH's, bit for bit.
    rt::UniformGrid grid;
    const double gridMs = medianMs(3, [&] { grid = rt::buildUniformGrid(g->view()); });
    std::vector<rt::RayHit> fromGrid(rayCount), fromBvh(rayCount);
    const double gridClosest = raysPerSecondM(rayCount, [&](size_t i) { fromGrid[i] = rt::closestHit(grid, g->view(), primary[i]); });
    raster::parallelFor(rayCount, [&](size_t i) { fromBvh[i] = rt::closestHit(sah, g->view(), primary[i]); });
    size_t differ = 0;
    for (size_t i = 0; i < rayCount; ++i)
        differ += fromGrid[i].triangle != fromBvh[i].triangle || (fromBvh[i].hit() && fromGrid[i].t != fromBvh[i].t);
    const double gridShadow = raysPerSecondM(rayCount, [&](size_t i) { ours[i] = rt::anyHit(grid, g->view(), shadow[i]); });
    std::printf("%-9s grid %dx%dx%d, %zu references: build %.1f ms (SAH BVH %.1f: %.2fx) | closest %.2f M/s (BVH %.2f, "
                "Embree %.2f: %.2fx slower) | shadow %.2f M/s (BVH %.2f, Embree %.2f: %.2fx slower) | hits unlike the BVH's: %zu\n",
                name.c_str(), grid.cells.x, grid.cells.y, grid.cells.z, grid.triangleRefs.size(), gridMs, sahMs, sahMs / gridMs,
                gridClosest, oursClosest, embreeClosest, embreeClosest / gridClosest, gridShadow, oursShadow, embreeShadow,
                embreeShadow / gridShadow, differ);

    // The eight-wide tree collapsed from the SAH one (rt/wide_bvh.h): single rays, a vector slab
    // test per node; its hits must be the binary tree's, bit for bit.
    rt::WideBvh wide;
    const double collapseMs = medianMs(3, [&] { wide = rt::collapseToWideBvh(sah); });
    std::vector<rt::RayHit> fromWide(rayCount);
    const double wideClosest = raysPerSecondM(rayCount, [&](size_t i) { fromWide[i] = rt::closestHit(wide, primary[i]); });
    size_t wideDiffer = 0;
    for (size_t i = 0; i < rayCount; ++i)
        wideDiffer += fromWide[i].triangle != fromBvh[i].triangle || fromWide[i].t != fromBvh[i].t ||
                      fromWide[i].u != fromBvh[i].u || fromWide[i].v != fromBvh[i].v;
    std::vector<uint8_t> wideOccluded(rayCount), bvhOccluded(rayCount);
    const double wideShadow = raysPerSecondM(rayCount, [&](size_t i) { wideOccluded[i] = rt::anyHit(wide, shadow[i]); });
    raster::parallelFor(rayCount, [&](size_t i) { bvhOccluded[i] = rt::anyHit(sah, g->view(), shadow[i]); });
    for (size_t i = 0; i < rayCount; ++i) wideDiffer += wideOccluded[i] != bvhOccluded[i];
    std::printf("%-9s wide BVH (%d children, %zu nodes, %zu triangle groups with %.0f%% of lanes used, collapse %.1f ms) | closest %.2f M/s (binary %.2f: %.2fx, Embree %.2f: "
                "%.2fx slower) | shadow %.2f M/s (binary %.2f: %.2fx, Embree %.2f: %.2fx slower) | answers unlike the binary tree's: %zu\n",
                name.c_str(), rt::kWideBvhWidth, wide.nodes.size(), wide.triangleGroups.size(),
                100.0 * double(g->triangles()) / double(rt::kTriangleGroupWidth * wide.triangleGroups.size()), collapseMs, wideClosest, oursClosest, wideClosest / oursClosest, embreeClosest,
                embreeClosest / wideClosest, wideShadow, oursShadow, wideShadow / oursShadow, embreeShadow, embreeShadow / wideShadow,
                wideDiffer);
    benchCoherentRays(device, name, *g, sah, wide, grid);
}

// ---- part 2: a skinned animation ------------------------------------------------------------

void benchAnimation(RTCDevice device, const std::string& name, int frames) {
    std::vector<Geometry> poses;
    for (int f = 0; f < frames; ++f) {
        const auto s = loadScene(name, 0.1f * float(f));
        if (!s) {
            std::printf("%s skipped: not found\n", name.c_str());
            return;
        }
        poses.push_back(concatenate(*s));
    }
    std::printf("\n# animation %s: %zu triangles, %d frames 0.1 s apart; ms per frame (median), degradation max\n",
                name.c_str(), poses[0].triangles(), frames);
    rt::Bvh refitted = rt::buildBvh(poses[0].view()), lazyTree = refitted;
    rt::WideBvh wide = rt::collapseToWideBvh(refitted);
    rt::LazyRefit lazy(lazyTree);
    std::vector<double> refit, refresh, lazyUpdate, rebuild, collapse, gridRebuild, embreeRefit, embreeRebuild;
    double worst = 0.0;
    EmbreeScene dynamic(device, poses[0], RTC_BUILD_QUALITY_REFIT, true);
    dynamic.commit();
    for (int f = 1; f < frames; ++f) {
        double t0 = raster::nowMs();
        worst = std::max(worst, rt::refitBvh(refitted, poses[size_t(f)].view()));
        refit.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        rt::refreshWideBvh(wide, refitted);
        refresh.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        lazy.update(poses[size_t(f)].view());
        lazyUpdate.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        const rt::Bvh fresh = rt::buildBvh(poses[size_t(f)].view());
        rebuild.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        const rt::WideBvh freshWide = rt::collapseToWideBvh(fresh);
        collapse.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        const rt::UniformGrid grid = rt::buildUniformGrid(poses[size_t(f)].view());
        gridRebuild.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        dynamic.update(poses[size_t(f)].positions);
        embreeRefit.push_back(raster::nowMs() - t0);
        t0 = raster::nowMs();
        EmbreeScene full(device, poses[size_t(f)], RTC_BUILD_QUALITY_MEDIUM, false);
        full.commit();
        embreeRebuild.push_back(raster::nowMs() - t0);
    }
    std::printf("refit %.2f (+ wide refresh %.2f)  lazy %.3f  rebuild %.2f (+ wide collapse %.2f)  grid rebuild %.2f | embree refit "
                "%.2f  rebuild %.2f | refit/embree %.2f  rebuild/embree %.2f | degradation max %.3f (rebuild past 0.4)\n",
                bench::median(refit), bench::median(refresh), bench::median(lazyUpdate), bench::median(rebuild), bench::median(collapse),
                bench::median(gridRebuild), bench::median(embreeRefit),
                bench::median(embreeRebuild), bench::median(refit) / bench::median(embreeRefit),
                bench::median(rebuild) / bench::median(embreeRebuild), worst);
}

// ---- part 3: shadow modes --------------------------------------------------------------------

/// A ground quad under the scene's meshes (scans float in space otherwise).
void addGround(scene::Scene& s) {
    scene::Bounds b = scene::boundsOf(s.meshes);
    const glm::vec3 c = 0.5f * (b.min + b.max);
    const float r = glm::length(b.max - b.min);
    scene::Mesh ground;
    ground.positions = {{c.x - r, b.min.y, c.z - r}, {c.x + r, b.min.y, c.z - r}, {c.x + r, b.min.y, c.z + r}, {c.x - r, b.min.y, c.z + r}};
    ground.normals.assign(4, glm::vec3(0, 1, 0));
    ground.indices = {0, 2, 1, 0, 3, 2};
    ground.doubleSided = true;
    s.meshes.push_back(std::move(ground));
}

void benchShadows(const std::string& name, int width, int height, const std::vector<int>& mapSizes, const std::string& penumbrae) {
    std::optional<scene::Scene> s = loadScene(name, name == "brainstem" ? 1.0f : 0.0f);
    if (!s) {
        std::printf("%s skipped: not found\n", name.c_str());
        return;
    }
    if (name != "vc") addGround(*s);
    struct Run {
        std::string label;
        rt::ShadowOptions options;
    };
    std::vector<Run> runs;
    for (const bool soft : {false, true}) {
        if (penumbrae.find(soft ? "soft" : "hard") == std::string::npos) continue;
        rt::ShadowOptions base;
        base.soft = soft;
        base.lightRadius = 0.02f;
        base.softSamplesPerSide = 4;
        base.mode = rt::ShadowMode::RayTraced;
        runs.push_back({"raytraced", base});
        for (const int size : mapSizes)
            for (const rt::ShadowMode mode : {rt::ShadowMode::Map, rt::ShadowMode::Hybrid}) {
                rt::ShadowOptions o = base;
                o.mode = mode;
                o.mapSizeTexels = size;
                runs.push_back({std::string(render::shadowModeName(mode)) + " " + std::to_string(size), o});
            }
    }
    std::printf("\n# shadows on %s (%zu triangles), %dx%d: stage ms (median of 3; BVH build and edge adjacency once, not included), share "
                "of receiver pixels differing from ray traced, share traced; 'x ref -S': map and mask against the reference's mask, "
                "the visibility buffer both pay left out\n",
                name.c_str(), s->triangleCount(), width, height);
    std::printf("%-5s %-15s %9s %8s %8s %10s %9s %9s %9s %9s %9s %9s\n", "soft", "mode", "ms", "x ref", "x ref -S", "differ", "traced",
                "bvh ms", "adj ms", "surf ms", "map ms", "mask ms");
    std::vector<float> reference;
    double referenceMs = 0.0, referenceMaskMs = 0.0;
    for (const Run& run : runs) {
        render::SceneShadows shadows(*s, run.options);
        std::vector<float> mask;
        render::ShadowFrameStats stats;
        std::vector<double> surfacesMs, mapMs, maskMs;  // the stage's parts, medians apart
        const double ms = medianMs(3, [&] {
            const raster::Lighting lit = shadows.run(*s, width, height, stats);
            surfacesMs.push_back(stats.surfacesMs);
            mapMs.push_back(stats.shadows.mapMs);
            maskMs.push_back(stats.shadows.maskMs);
            mask.assign(lit.lights[0].visibility, lit.lights[0].visibility + size_t(width) * height);
        });
        // What the stage costs beyond the visibility buffer, which a deferred frame would share with
        // its own pass: the map and the mask, against the reference's mask (its rays).
        const double ownMs = bench::median(mapMs) + bench::median(maskMs);
        if (run.options.mode == rt::ShadowMode::RayTraced) reference = mask, referenceMs = ms, referenceMaskMs = ownMs;
        size_t differ = 0;
        for (size_t i = 0; i < mask.size(); ++i) differ += mask[i] != reference[i];
        const double receivers = double(std::max<uint64_t>(1, stats.shadows.receiverPixels));
        std::printf("%-5s %-15s %9.1f %8.2f %8.2f %9.4f%% %8.2f%% %9.1f %9.1f %9.1f %9.1f %9.1f\n", run.options.soft ? "soft" : "hard",
                    run.label.c_str(), ms, ms / referenceMs, ownMs / referenceMaskMs, 100.0 * double(differ) / receivers,
                    100.0 * double(stats.shadows.markedPixels) / receivers, stats.bvhBuildMs, stats.adjacencyMs, bench::median(surfacesMs),
                    bench::median(mapMs), bench::median(maskMs));
        if (run.options.mode == rt::ShadowMode::RayTraced && run.options.soft) {
            // What a perfect penumbra estimate would trace: the receivers in partial shadow.
            size_t partial = 0;
            for (const float v : mask) partial += v > 0.0f && v < 1.0f;
            std::printf("      (%.2f%% of receivers in partial shadow)\n", 100.0 * double(partial) / receivers);
        }
    }
}

}  // namespace

// ---- part 4: the renderer's camera rays beside Embree --------------------------------------

/// The camera-ray stage of `render --renderer raytrace` (rt::PrimaryRayHierarchy: the kept BVH,
/// the view's culled triangles skipped, 8x8 packets, one sample at each pixel centre) on a scene's
/// default frame, and Embree's rtcIntersect1 with the same rays over the same opaque draws'
/// triangles in world space, in the same run. Embree culls nothing: where a draw is back-face
/// culled, it may report a hit on a face ours skips (the hit counts say how often).
void benchFrames(RTCDevice device, const std::string& name, int width, int height) {
    const std::optional<scene::Scene> s = loadScene(name, name == "brainstem" ? 1.0f : 0.0f);
    if (!s) {
        std::printf("%s skipped: not found\n", name.c_str());
        return;
    }
    raster::Pipeline pipeline;
    raster::FramebufferDesc desc;
    desc.widthPixels = width, desc.heightPixels = height;
    pipeline.beginDeferredFrame(desc);
    const float aspect = float(width) / float(height);
    s->draw(pipeline, aspect);
    const std::vector<raster::DrawCall> draws(pipeline.recordedDraws().begin(), pipeline.recordedDraws().end());
    std::vector<uint8_t> traced(draws.size());
    Geometry world;
    for (size_t d = 0; d < draws.size(); ++d) {
        traced[d] = draws[d].state.depthWrite;
        if (!traced[d]) continue;
        const uint32_t base = uint32_t(world.positions.size());
        for (const glm::vec3& p : draws[d].positions) world.positions.push_back(glm::vec3(draws[d].worldFromObject * glm::vec4(p, 1.0f)));
        if (draws[d].indices.empty())
            for (uint32_t i = 0; i < draws[d].positions.size(); ++i) world.indices.push_back(base + i);
        else
            for (uint32_t i : draws[d].indices) world.indices.push_back(base + i);
    }
    rt::PrimaryRayCamera camera;
    camera.worldFromClip = glm::inverse(glm::dmat4(s->camera.clipFromWorld(aspect)));
    camera.reversedDepth = s->camera.reversedDepth;
    camera.orthographic = s->camera.orthographic;
    camera.eye = s->camera.position;
    camera.viewDirection = glm::normalize(s->camera.target - s->camera.position);
    rt::PrimaryRayHierarchy hierarchy(draws, traced, rt::BvhUpdateMethod::Refit);
    raster::VisibilityBuffer seen;
    std::vector<double> oursMs;
    rt::PrimaryRayStats ours;
    for (int run = 0; run < 3; ++run) {
        seen.reset(width, height, 1);
        ours = hierarchy.trace(draws, camera, seen);
        oursMs.push_back(ours.traceMs);
    }
    EmbreeScene embree(device, world, RTC_BUILD_QUALITY_MEDIUM, false);
    embree.commit();
    // Each ray made as the renderer makes it (rt::primaryRay, in double), inside the timing as
    // the renderer's trace includes its own.
    const size_t n = size_t(width) * size_t(height);
    std::vector<uint8_t> hit(n);
    const double embreeMs = medianMs(3, [&] {
        raster::parallelFor(n, [&](size_t i) {
            uint32_t triangle;
            const rt::Ray ray = rt::primaryRay(camera, double(i % size_t(width)) + 0.5, double(i / size_t(width)) + 0.5, width, height);
            hit[i] = embree.closest(ray, &triangle);
        });
    });
    size_t embreeHits = 0;
    for (uint8_t h : hit) embreeHits += h;
    const double oursMedian = bench::median(oursMs);
    std::printf("%-10s %9zu triangles, %dx%d camera rays: renderer's trace %7.1f ms (%zu hits) | Embree rtcIntersect1 %7.1f ms (%zu "
                "hits) | ours %.2fx Embree's speed\n",
                name.c_str(), world.triangles(), width, height, oursMedian, size_t(ours.hits), embreeMs, embreeHits, embreeMs / oursMedian);
}

int main(int argc, char** argv) {
    CLI::App app{"BVH build, refit and rays against Embree; shadow modes against ray-traced shadows"};
    std::string models = "bunny,horse,dragon,1m", animation = "brainstem", shadowScenes = "vc,dragon,brainstem",
                frameScenes = "vc,helmet,brainstem,dragon", sizes = "1024,2048,4096", penumbrae = "hard,soft";
    int frames = 12, width = 1280, height = 720;
    app.add_option("--models", models, "bunny, horse, dragon, 1m, 10m (bumpy spheres)")->capture_default_str();
    app.add_option("--animation", animation, "A skinned glTF (brainstem, cesiumman)")->capture_default_str();
    app.add_option("--frames", frames, "Animation frames (at least 2: the first pose is the one refitted from)")->check(CLI::Range(2, 100000))->capture_default_str();
    app.add_option("--shadow-scenes", shadowScenes, "vc (Virtual City), a scan on a ground plane, brainstem")->capture_default_str();
    app.add_option("--frame-scenes", frameScenes, "Scenes whose camera rays the renderer traces beside Embree (vc, brainstem, helmet, a scan)")
        ->capture_default_str();
    app.add_option("--map-sizes", sizes, "Shadow map sizes")->capture_default_str();
    app.add_option("--shadows", penumbrae, "hard, soft or both")->capture_default_str();
    app.add_option("--width", width)->capture_default_str();
    app.add_option("--height", height)->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    const int threads = raster::hardwareThreads();
    const std::string config = "threads=" + std::to_string(threads);
    RTCDevice device = rtcNewDevice(config.c_str());
    std::printf("# %d threads; Embree %s; build ms (ratio ours/Embree), refit ms, rays in millions a second (ratio "
                "Embree/ours), agreement of hit/miss between the two\n",
                threads, RTC_VERSION_STRING);
    std::printf("%-9s %7s | %8s %8s %6s | %8s %8s %6s | %7s %7s %7s %6s %6s | %6s %6s %5s | %6s %6s %5s | %7s\n", "model",
                "Mtri", "SAH", "embree", "ratio", "median", "emb.low", "ratio", "refit", "lazy", "emb.ref", "ratio",
                "degr", "closest", "embree", "x", "shadow", "embree", "x", "agree");
    for (const std::string& m : bench::splitList(models)) benchModel(device, m);
    if (!animation.empty()) benchAnimation(device, animation, frames);
    std::vector<int> mapSizes;
    for (const std::string& s : bench::splitList(sizes)) mapSizes.push_back(std::stoi(s));
    for (const std::string& s : bench::splitList(shadowScenes)) benchShadows(s, width, height, mapSizes, penumbrae);
    if (!frameScenes.empty()) std::printf("\n# the renderer's camera rays beside Embree's (median of 3, trace only: builds not included)\n");
    for (const std::string& s : bench::splitList(frameScenes)) benchFrames(device, s, width, height);
    rtcReleaseDevice(device);
    return 0;
}
