#include "rt/shadow_mode_choice.h"

#include <algorithm>

namespace cuberille::rt {
namespace {

// Per-unit costs in nanoseconds of wall time on the CI machine kind (2 cores, both working),
// measured by `shadow_bench` and `--stats` on Virtual City, the dragon, BrainStem and
// DamagedHelmet on their floors at 1280x720 (docs/ray_tracing.md, "--shadows auto"). Only their
// ratios decide: a machine with more cores scales them all alike.
constexpr double kRayNs = 65.0;                   // a ray-traced receiver's ray (44-110 over the four)
constexpr double kHardLookupNs = 18.0;            // hybrid, hard: locate, 3x3 test, thin texel
constexpr double kSoftLookupNs = 55.0;            // hybrid, soft: the above and the penumbra search
constexpr double kHardMarkedRayNs = 280.0;        // a marked receiver's ray passes by an edge (100-530)
constexpr double kSoftMarkedRayNs = 180.0;        // per ray of a marked soft receiver (75-250)
constexpr double kHardMarkedShare = 0.04;         // receivers hybrid marks, hard (1-10% over the four)
constexpr double kSoftMarkedShare = 0.16;         // soft, at the default light radius (9-19%)
constexpr double kMapTexelNs = 4.5;               // clear, draw, linear depth and marks, per texel
constexpr double kMapTriangleNs = 25.0;           // per caster triangle drawn into the map
constexpr double kAdjacencyTriangleNs = 130.0;    // hybrid's edge adjacency, per caster triangle

double hybridMs(const ShadowWorkload& w) {
    const double receivers = double(w.receivers), sequence = double(std::max(1, w.framesSharingMap));
    const double mapNs = (double(w.mapTexels) * kMapTexelNs + double(w.casterTriangles) * kMapTriangleNs) / sequence;
    const double adjacencyNs = double(w.casterTriangles) * kAdjacencyTriangleNs / sequence;
    const double lookupNs = receivers * (w.soft ? kSoftLookupNs : kHardLookupNs);
    const double raysNs = receivers * (w.soft ? kSoftMarkedShare : kHardMarkedShare) * double(w.raysPerReceiver) *
                          (w.soft ? kSoftMarkedRayNs : kHardMarkedRayNs);
    return 1e-6 * (mapNs + adjacencyNs + lookupNs + raysNs);
}

double rayTracedMs(const ShadowWorkload& w) { return 1e-6 * double(w.receivers) * double(w.raysPerReceiver) * kRayNs; }

}  // namespace

ShadowModeChoice chooseShadowMode(const ShadowWorkload& work) {
    ShadowModeChoice c;
    c.predictedHybridMs = hybridMs(work);
    c.predictedRayTracedMs = rayTracedMs(work);
    c.mode = c.predictedHybridMs < c.predictedRayTracedMs ? ShadowMode::Hybrid : ShadowMode::RayTraced;
    return c;
}

}  // namespace cuberille::rt
