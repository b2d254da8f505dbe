// The grid packets' triangle test in lanes (rt/packet_triangle_lanes.h) is a filter that never
// rejects a ray the scalar watertight test hits, at the edge of its interval too, leaves a zero
// edge weight to the scalar test, and rejects nearly every ray the scalar test misses. The grid's
// packets against brute force (uniform_grid_test.cpp) check it inside the traversal; ctest runs
// both once per instruction set.

#include <gtest/gtest.h>

#include <bit>
#include <random>

#include "rt/packet_triangle_lanes.h"

namespace cuberille::rt {
namespace {

/// A packet of `count` rays from a small patch toward +z (a shared permutation), fanned by up to
/// `spread` in x and y, and their prepared tests.
struct Packet {
    std::vector<Ray> rays;
    std::vector<WatertightRay> tests;
    PacketTriangleLanes lanes;

    Packet(std::mt19937& rng, int count, float spread) {
        std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
        const glm::vec3 origin(jitter(rng), jitter(rng), -3.0f);
        for (int i = 0; i < count; ++i) {
            Ray r;
            r.origin = origin + 0.05f * glm::vec3(jitter(rng), jitter(rng), jitter(rng));
            r.direction = glm::vec3(spread * jitter(rng), spread * jitter(rng), 1.0f);
            r.tMin = i % 5 == 0 ? 0.5f : 0.0f;
            rays.push_back(r);
        }
        for (const Ray& r : rays) tests.emplace_back(r);
        std::vector<const WatertightRay*> pointers;
        std::vector<float> tMins;
        for (int i = 0; i < count; ++i) pointers.push_back(&tests[size_t(i)]), tMins.push_back(rays[size_t(i)].tMin);
        EXPECT_TRUE(lanes.set(pointers.data(), tMins.data(), count));
    }
};

TEST(PacketTriangleLanes, NeverRejectARayTheScalarTestHitsEvenAtTheEndOfItsInterval) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> place(-1.0f, 1.0f), size(-0.8f, 0.8f);
    uint64_t scalarHits = 0, scalarMisses = 0, missesKept = 0;
    for (int packetIndex = 0; packetIndex < 320; ++packetIndex) {
        const int count = 1 + packetIndex % kPacketTriangleLanesRays;
        Packet packet(rng, count, 0.4f);
        for (int triangle = 0; triangle < 40; ++triangle) {
            const glm::vec3 centre(place(rng), place(rng), place(rng));
            const glm::vec3 a = centre + glm::vec3(size(rng), size(rng), size(rng));
            const glm::vec3 b = centre + glm::vec3(size(rng), size(rng), size(rng));
            const glm::vec3 c = centre + glm::vec3(size(rng), size(rng), size(rng));
            // Each ray's interval ends at its own hit (exactly: the ray still hits at tMax == t),
            // else at random.
            float bestT[kPacketTriangleLanesRays] = {};
            for (int i = 0; i < count; ++i) {
                RayHit hit;
                const bool hits = packet.tests[size_t(i)].intersect(a, b, c, packet.rays[size_t(i)].tMin,
                                                                    std::numeric_limits<float>::infinity(), &hit);
                bestT[i] = hits && i % 2 == 0 ? hit.t : std::uniform_real_distribution<float>(0.5f, 8.0f)(rng);
            }
            const uint64_t all = count == 64 ? ~uint64_t(0) : (uint64_t(1) << count) - 1;
            const uint64_t kept = raysTheTriangleMayHit(packet.lanes, bestT, all, a, b, c);
            ASSERT_EQ(kept & ~all, 0u) << "a lane outside the candidates was kept";
            for (int i = 0; i < count; ++i) {
                RayHit hit;
                const bool hits = packet.tests[size_t(i)].intersect(a, b, c, packet.rays[size_t(i)].tMin, bestT[i], &hit);
                const bool keptRay = kept >> i & 1;
                if (hits) {
                    ++scalarHits;
                    ASSERT_TRUE(keptRay) << "packet " << packetIndex << " triangle " << triangle << " ray " << i;
                } else {
                    ++scalarMisses, missesKept += keptRay;
                }
            }
            // Candidates are respected: only the odd rays asked, only odd rays kept.
            const uint64_t odd = all & 0xAAAAAAAAAAAAAAAAull;
            ASSERT_EQ(raysTheTriangleMayHit(packet.lanes, bestT, odd, a, b, c), kept & odd);
        }
    }
    EXPECT_GT(scalarHits, 5000u);
    // What the filter is for: it rejects every miss of the scalar test but those decided after
    // the lanes' part (a zero edge weight, a hit outside the triangle's own box). Random float
    // scenes have neither: none of the 407,462 misses here was kept, on every instruction set
    // (the lanes compute the same bits on each).
    EXPECT_EQ(missesKept, 0u) << "of " << scalarMisses << " misses";
}

TEST(PacketTriangleLanes, AZeroEdgeWeightIsLeftToTheScalarTest) {
    // The triangle (0,0) (1,0) (0,1) at z = 0, rays straight down +z through points of its
    // edges' lines: exactly zero edge weights, which the scalar test recomputes in double.
    const glm::vec3 a(0.0f, 0.0f, 0.0f), b(1.0f, 0.0f, 0.0f), c(0.0f, 1.0f, 0.0f);
    const glm::vec2 through[] = {{0.5f, 0.0f}, {2.0f, 0.0f}, {-1.0f, 0.0f}, {0.0f, 3.0f}, {0.25f, 0.25f}, {2.0f, 2.0f}};
    std::vector<Ray> rays;
    for (const glm::vec2& p : through) {
        Ray r;
        r.origin = glm::vec3(p, -1.0f);
        rays.push_back(r);
    }
    std::vector<WatertightRay> tests(rays.begin(), rays.end());
    std::vector<const WatertightRay*> pointers;
    std::vector<float> tMins(rays.size(), 0.0f);
    for (const WatertightRay& t : tests) pointers.push_back(&t);
    PacketTriangleLanes lanes;
    ASSERT_TRUE(lanes.set(pointers.data(), tMins.data(), int(rays.size())));
    float bestT[kPacketTriangleLanesRays];
    std::fill(std::begin(bestT), std::end(bestT), std::numeric_limits<float>::infinity());
    const uint64_t kept = raysTheTriangleMayHit(lanes, bestT, 0b111111, a, b, c);
    // On an edge: kept (and hit). On an edge's line outside the triangle: kept for the scalar
    // test, which misses. Inside: kept. Outside, no weight zero: rejected.
    EXPECT_EQ(kept, 0b011111u);
    for (size_t i = 0; i < rays.size(); ++i) {
        RayHit hit;
        EXPECT_EQ(tests[i].intersect(a, b, c, 0.0f, bestT[0], &hit), i == 0 || i == 4) << i;
    }
}

TEST(PacketTriangleLanes, RaysOfDifferentPermutationsAreNotPutInLanes) {
    Ray along, across;
    across.direction = glm::vec3(1.0f, 0.1f, 0.1f);
    const WatertightRay a(along), b(across);
    const WatertightRay* pointers[2] = {&a, &b};
    const float tMins[2] = {0.0f, 0.0f};
    PacketTriangleLanes lanes;
    EXPECT_FALSE(lanes.set(pointers, tMins, 2));
    EXPECT_TRUE(lanes.set(pointers, tMins, 1));
    EXPECT_FALSE(lanes.set(pointers, tMins, kPacketTriangleLanesRays + 1));
}

}  // namespace
}  // namespace cuberille::rt
