#include "rt/ambient_occlusion.h"

#include <cmath>

#include "raster/clock.h"
#include "raster/parallel.h"

namespace cuberille::rt {

void computeAmbientOcclusion(const ScreenSurfaces& surfaces, const CasterRays& casters, float distance, float rayOffset,
                             const AmbientOcclusionOptions& options, std::vector<float>& mask,
                             AmbientOcclusionStats& stats) {
    const double t0 = raster::nowMs();
    stats = {};
    stats.raysPerPixel = options.raysPerPixel;
    stats.distance = distance;
    mask.assign(size_t(surfaces.width) * surfaces.height, 1.0f);
    const std::vector<glm::vec3> directions = occlusionDirections(options.raysPerPixel);
    // Pixels counted per row and summed in row order: the totals do not depend on the schedule.
    std::vector<uint64_t> rowPixels(size_t(surfaces.height), 0);
    raster::parallelFor(size_t(surfaces.height), [&](size_t y) {
        surfaces.forEachSurfaceInRow(int(y), [&](int x, size_t i, const Surface& surface) {
            ++rowPixels[y];
            mask[i] = openShare(surface, directions, occlusionTurnRadians(x, int(y)), distance, rayOffset,
                                [&](const Ray& ray) { return casters.anyHit(ray); });
        });
    });
    for (const uint64_t p : rowPixels) stats.pixels += p;
    stats.rays = stats.pixels * directions.size();
    stats.ms = raster::nowMs() - t0;
}

// Malley's method: points spread evenly over the unit disk, lifted to the hemisphere, are
// distributed as cos(theta). The disk's points are a golden-ratio (Fibonacci) set: radius^2 =
// (i + 1/2) / N stratified, angle 2 pi frac(i phi), which covers the disk evenly for any N.
std::vector<glm::vec3> occlusionDirections(int count) {
    std::vector<glm::vec3> directions;
    directions.reserve(size_t(std::max(count, 0)));
    constexpr double kGoldenRatioFraction = 0.61803398874989484820;
    for (int i = 0; i < count; ++i) {
        const double radius2 = (i + 0.5) / count;
        const double angle = 2.0 * M_PI * (double(i) * kGoldenRatioFraction - std::floor(double(i) * kGoldenRatioFraction));
        const double radius = std::sqrt(radius2);
        directions.emplace_back(float(radius * std::cos(angle)), float(radius * std::sin(angle)), float(std::sqrt(1.0 - radius2)));
    }
    return directions;
}

// A 32-bit integer hash of the pixel (the finaliser of MurmurHash3), scaled to a turn.
float occlusionTurnRadians(int x, int y) {
    uint32_t h = uint32_t(x) * 0x9E3779B1u ^ uint32_t(y) * 0x85EBCA77u;
    h ^= h >> 16;
    h *= 0x85EBCA6Bu;
    h ^= h >> 13;
    h *= 0xC2B2AE35u;
    h ^= h >> 16;
    return float(double(h) * (2.0 * M_PI / 4294967296.0));
}

void tangentFrame(const glm::vec3& n, glm::vec3& u, glm::vec3& v) {
    u = glm::normalize(glm::cross(std::abs(n.x) > 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0), n));
    v = glm::cross(n, u);
}

}  // namespace cuberille::rt
