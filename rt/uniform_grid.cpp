#include "rt/uniform_grid.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstring>
#include <cmath>
#include <optional>

#include <tbb/parallel_for.h>

#include "rt/packet_triangle_lanes.h"
#include "rt/ray_query.h"

namespace cuberille::rt {
namespace {

struct CellRange {
    glm::ivec3 lo, hi;  // inclusive
};

// What the build and the walk share: where a coordinate falls.
struct GridFrame {
    glm::vec3 origin, inverseCellSize;
    glm::ivec3 last;  // cells - 1

    explicit GridFrame(const UniformGrid& g) : origin(g.bounds.lo), last(g.cells - 1) {
        for (int a = 0; a < 3; ++a) inverseCellSize[a] = g.cellSize[a] > 0.0f ? 1.0f / g.cellSize[a] : 0.0f;
    }
    glm::ivec3 cellOf(const glm::vec3& p) const {
        glm::ivec3 c;
        for (int a = 0; a < 3; ++a) {
            const float f = std::floor((p[a] - origin[a]) * inverseCellSize[a]);
            c[a] = f >= float(last[a]) ? last[a] : f > 0.0f ? int(f) : 0;  // NaN lands in cell 0
        }
        return c;
    }
};

// kGridInsertionMargin per axis, with its floor of 16 ulps of the grid's largest coordinate: what
// the build grows each triangle's box by, and the packets each ray's stretch box.
glm::vec3 insertionMargin(const UniformGrid& g) {
    const glm::vec3 lo = glm::abs(g.bounds.lo), hi = glm::abs(g.bounds.hi);
    const float ulpFloor = 16.0f * std::max({lo.x, lo.y, lo.z, hi.x, hi.y, hi.z}) * std::numeric_limits<float>::epsilon();
    return glm::max(g.cellSize * kGridInsertionMargin, glm::vec3(ulpFloor));
}

// The cells a triangle is listed in: those its bounding box, grown by the margin, overlaps.
CellRange cellsOfTriangle(const GridFrame& frame, const glm::vec3& margin, const TriangleMeshView& mesh, size_t triangle) {
    const Aabb b = mesh.triangleBounds(triangle);
    return {frame.cellOf(b.lo - margin), frame.cellOf(b.hi + margin)};
}

// Mailbox (Wald et al. §2): a triangle listed in several cells is tested once a ray (or a packet
// slice). Skipping the retest is exact: it could only be rejected again, the best t having shrunk
// since. A direct-mapped cache of the last N ids; a collision only costs a retest.
template <int N>
struct Mailbox {
    static_assert((N & (N - 1)) == 0, "a power of two");
    uint32_t slots[N];
    Mailbox() { std::fill(std::begin(slots), std::end(slots), RayHit::kNone); }
    /// Whether `triangle` was tested already; marks it tested.
    bool seen(uint32_t triangle) {
        uint32_t& slot = slots[triangle & (N - 1)];
        if (slot == triangle) return true;
        slot = triangle;
        return false;
    }
};

// Where face `index` of axis a lies: the grid's corner plus whole cells, from the index each time
// (never accumulated; the header's argument), so the walk's cell steps, its macrocell steps and
// the packets' slices put a face at the same float.
float faceAt(const UniformGrid& grid, int a, int index) { return grid.bounds.lo[a] + float(index) * grid.cellSize[a]; }

// The first of three faces (face faceIndex[a] on axis a) a ray crosses, and where. A zero
// direction component gives an infinite or NaN crossing on its axis, which never wins.
struct FaceCrossing {
    int axis = 0;
    float t = std::numeric_limits<float>::infinity();
};
// Inlined: called out of line from the walk's every step, single rays ran 10% slower.
[[gnu::always_inline]] inline FaceCrossing firstCrossing(const UniformGrid& grid, const Ray& ray, const glm::vec3& inverseDirection, const glm::ivec3& faceIndex) {
    FaceCrossing first;
    for (int a = 0; a < 3; ++a) {
        const float t = (faceAt(grid, a, faceIndex[a]) - ray.origin[a]) * inverseDirection[a];
        if (t < first.t) first = {a, t};
    }
    return first;
}

template <class Body>
void forEachCell(const CellRange& r, Body&& body) {
    for (int z = r.lo.z; z <= r.hi.z; ++z)
        for (int y = r.lo.y; y <= r.hi.y; ++y)
            for (int x = r.lo.x; x <= r.hi.x; ++x) body(x, y, z);
}

// The walk's step out of the empty macrocell holding `cell`: false when the walk ends there (the
// best hit lies before the exit, or the ray leaves the grid), else `cell` becomes the cell past
// the exit face — on the exit axis the macrocell's neighbour's first cell, on the others the
// exit point's cell, kept inside the macrocell's range against rounding.
bool leaveEmptyMacrocell(const UniformGrid& grid, const GridFrame& frame, const Ray& ray, const glm::ivec3& step,
                         const glm::vec3& inverseDirection, float bestT, glm::ivec3& cell) {
    constexpr int M = kGridMacrocellCells;
    const glm::ivec3 first = cell / M * M, last = glm::min(first + (M - 1), frame.last);
    glm::ivec3 exitFaces;
    for (int a = 0; a < 3; ++a) exitFaces[a] = step[a] > 0 ? last[a] + 1 : first[a];
    const FaceCrossing exit = firstCrossing(grid, ray, inverseDirection, exitFaces);
    if (bestT * detail::kEntrySlack < exit.t) return false;
    const glm::ivec3 at = frame.cellOf(ray.origin + ray.direction * exit.t);
    for (int a = 0; a < 3; ++a) cell[a] = std::clamp(at[a], first[a], last[a]);
    cell[exit.axis] = step[exit.axis] > 0 ? last[exit.axis] + 1 : first[exit.axis] - 1;
    return cell[exit.axis] >= 0 && cell[exit.axis] <= frame.last[exit.axis];
}

// The walk (header comment): test each cell's triangles, then stop once the best hit lies
// before the next cell's entry, else step into the cell whose face the ray crosses first.
template <bool kAnyHit>
RayHit walk(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters,
            const HitFilter* filter = nullptr) {
    RayHit best;
    best.t = ray.tMax;
    float entry = 0.0f;
    if (grid.empty() || !RayBoxTest(ray).hits(grid.bounds.lo, grid.bounds.hi, ray.tMin, ray.tMax, &entry)) {
        best.t = std::numeric_limits<float>::infinity();
        return best;
    }
    const GridFrame frame(grid);
    const WatertightRay triangleTest(ray);
    glm::ivec3 cell = frame.cellOf(ray.origin + ray.direction * std::max(entry, ray.tMin));
    glm::ivec3 step;
    glm::vec3 inverseDirection;
    for (int a = 0; a < 3; ++a) {
        step[a] = std::signbit(ray.direction[a]) ? -1 : 1;
        inverseDirection[a] = 1.0f / ray.direction[a];  // +-inf for a zero component: that axis never steps
    }
    Mailbox<16> mailbox;
    for (;;) {
        // Macrocells (§2.4): an empty one is left in one step. No hit lies in it (a hit point's
        // cell, and with the margin every cell within it, lists the triangle), so the walk goes on
        // from the cell past the face where the ray leaves it.
        // (Carrying the macrocell along instead of dividing each step was measured no faster.)
        const glm::ivec3 macrocell = cell / kGridMacrocellCells;
        if (!grid.macrocellOccupied[grid.macrocellIndex(macrocell.x, macrocell.y, macrocell.z)]) {
            if (counters) ++counters->macrocellsSkipped;
            if (!leaveEmptyMacrocell(grid, frame, ray, step, inverseDirection, best.t, cell)) break;
            continue;
        }
        if (counters) ++counters->cellsVisited;
        const size_t c = grid.cellIndex(cell.x, cell.y, cell.z);
        for (uint32_t i = grid.cellStart[c]; i < grid.cellStart[c + 1]; ++i) {
            const uint32_t triangle = grid.triangleRefs[i];
            if (mailbox.seen(triangle)) continue;
            if (counters) ++counters->trianglesTested;
            if (offerHit(triangleTest, mesh.vertex(triangle, 0), mesh.vertex(triangle, 1), mesh.vertex(triangle, 2), triangle,
                         ray.tMin, best, filter, &ray) &&
                kAnyHit)
                return best;
        }
        glm::ivec3 exitFaces;
        for (int a = 0; a < 3; ++a) exitFaces[a] = cell[a] + (step[a] > 0 ? 1 : 0);
        const FaceCrossing exit = firstCrossing(grid, ray, inverseDirection, exitFaces);
        // A triangle first listed in a later cell has its hit past that cell's face plus the margin.
        if (best.t * detail::kEntrySlack < exit.t) break;
        const int axis = exit.axis;
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] > frame.last[axis]) break;
    }
    if (!best.hit()) best.t = std::numeric_limits<float>::infinity();
    return best;
}

static_assert(kMaxGridPacketRays <= kPacketTriangleLanesRays, "a packet's rays fit the triangle test's lanes");

// The packet's rays as the slices go by, in structure-of-arrays form: the per-slice pass over
// the rays (where each crosses the slice) is a loop the compiler vectorises across them, which
// the profile showed was most of a packet's time when written a ray at a time.
struct PacketRays {
    std::optional<WatertightRay> test[kMaxGridPacketRays];  // set for every ray of the packet
    float origin[3][kMaxGridPacketRays], direction[3][kMaxGridPacketRays];
    float entry[kMaxGridPacketRays];     // where it enters the grid's box
    float inverseK[kMaxGridPacketRays];  // 1 / its direction's major component
    float bestT[kMaxGridPacketRays];     // hits[i].t, kept here for the vector pass
    float looking[kMaxGridPacketRays];  // 1 while the ray is active, else 0 (the bit mask's copy; a float, so
                                        // the vector pass selects on float compares alone, which GCC vectorises)
};

// Each looking ray's stretch in one slice (or in a slab of slices: the macrocells), between its
// crossings of the slice's near and far faces (clamped to where it enters the grid and to its
// best hit so far): its box, grown by the margin, holds every hit the ray can have in the slice
// (exactness: the header). crosses[i] = 0 for a ray not in the slice, whose box means nothing.
// farT[i]: where the ray leaves the slice.
struct SliceStretches {
    float lo[3][kMaxGridPacketRays], hi[3][kMaxGridPacketRays];
    float farT[kMaxGridPacketRays];
    int32_t crosses[kMaxGridPacketRays];
};

// __restrict: without it GCC 12 needs more run-time alias checks than it will emit, and keeps the
// loop scalar.
void stretchesInSlice(const PacketRays& __restrict p, int n, int k, float nearFace, float farFace, const glm::vec3& margin,
                      SliceStretches& __restrict out) {
    constexpr float kSlack = detail::kEntrySlack;
    const float* originK = p.origin[k];
    for (int i = 0; i < n; ++i) {  // vectorised (-fopt-info-vec): no branch, every ray computed, the result selected
        const float farT = (farFace - originK[i]) * p.inverseK[i];
        const float nearT = (nearFace - originK[i]) * p.inverseK[i];
        const float t0 = nearT > p.entry[i] ? nearT : p.entry[i];
        const float t1 = (farT < p.bestT[i] ? farT : p.bestT[i]) * kSlack;
        // In the slice unless its stretch is empty (by more than the slack: a ray grazing the
        // face is kept; keeping a ray more only costs tests).
        const bool crosses = (p.looking[i] > 0.0f) & (t1 * kSlack >= t0);
        out.farT[i] = farT;
        out.crosses[i] = crosses;
        // Each axis written out (an inner loop, even a constant one, keeps the outer from
        // vectorising), and the box stored whether or not the ray crosses (selecting an empty
        // box as well was one condition too many for GCC 12's if-conversion).
        const auto axis = [&](int a) {
            const float x0 = p.origin[a][i] + p.direction[a][i] * t0, x1 = p.origin[a][i] + p.direction[a][i] * t1;
            out.lo[a][i] = (x0 < x1 ? x0 : x1) - margin[a];
            out.hi[a][i] = (x0 > x1 ? x0 : x1) + margin[a];
        };
        axis(0), axis(1), axis(2);
    }
}

// Frustum culling (Wald et al. §2), per ray: bit i set when ray i's stretch box in this slice meets
// the triangle's box [lo, hi] — only such a ray can hit it here. Over the 8-ray words firstWord to
// lastWord: the box tests a vectorised loop into bytes, each word's eight bytes (0 or 1) gathered
// into eight bits by one multiplication (bit k of the top byte of w x 0x0102040810204080 is byte
// k's). Bits of rays not crossing the slice are meaningless; the caller masks them.
uint64_t raysMeetingBox(const SliceStretches& __restrict s, int firstWord, int lastWord, const glm::vec3& lo, const glm::vec3& hi) {
    alignas(8) uint8_t meets[kMaxGridPacketRays];
    const int first = 8 * firstWord, end = 8 * (lastWord + 1);
    const float loX = lo.x, loY = lo.y, loZ = lo.z, hiX = hi.x, hiY = hi.y, hiZ = hi.z;
    for (int i = first; i < end; ++i)
        meets[i] = uint8_t((s.lo[0][i] <= hiX) & (s.hi[0][i] >= loX) & (s.lo[1][i] <= hiY) & (s.hi[1][i] >= loY) &
                           (s.lo[2][i] <= hiZ) & (s.hi[2][i] >= loZ));
    uint64_t bits = 0;
    for (int word = firstWord; word <= lastWord; ++word) {
        uint64_t bytes;
        std::memcpy(&bytes, meets + 8 * word, 8);
        bits |= ((bytes * 0x0102040810204080ull) >> 56) << (8 * word);
    }
    return bits;
}

// Whether a macrocell of layer `layer` along axis k under the rectangle [lo, hi] (its u and v
// extent, mapped to cells as the slices map theirs) lists anything.
bool anyMacrocellOccupied(const UniformGrid& grid, const GridFrame& frame, int k, int layer, const glm::vec3& lo, const glm::vec3& hi) {
    constexpr int M = kGridMacrocellCells;
    const glm::ivec3 c0 = frame.cellOf(lo) / M, c1 = frame.cellOf(hi) / M;
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    glm::ivec3 m;
    m[k] = layer;
    for (m[v] = c0[v]; m[v] <= c1[v]; ++m[v])
        for (m[u] = c0[u]; m[u] <= c1[u]; ++m[u])
            if (grid.macrocellOccupied[grid.macrocellIndex(m.x, m.y, m.z)]) return true;
    return false;
}

// closestHits and anyHits: a packet's rays slice by slice (the header). For any hit a ray retires
// at its first hit, as the walk returns at it.
template <bool kAnyHit>
void tracePacket(const UniformGrid& grid, const TriangleMeshView& mesh, std::span<const Ray> rays, std::span<RayHit> hits,
                 GridCounters* counters, const HitFilter* filter = nullptr) {
    if (rays.size() > size_t(kMaxGridPacketRays)) {  // more than a packet: packets of the most
        for (size_t first = 0; first < rays.size(); first += kMaxGridPacketRays) {
            const size_t count = std::min(rays.size() - first, size_t(kMaxGridPacketRays));
            tracePacket<kAnyHit>(grid, mesh, rays.subspan(first, count), hits.subspan(first, count), counters, filter);
        }
        return;
    }
    const int n = int(rays.size());
    for (int i = 0; i < n; ++i) hits[i] = RayHit{}, hits[i].t = rays[i].tMax;
    if (grid.empty() || n == 0) {
        for (int i = 0; i < n; ++i) hits[i].t = std::numeric_limits<float>::infinity();
        return;
    }
    // The major axis K of the packet's summed direction, and the way it is travelled.
    glm::vec3 sum(0.0f);
    for (const Ray& r : rays) sum += r.direction;
    const glm::vec3 magnitude = glm::abs(sum);
    const int k = magnitude.x >= magnitude.y && magnitude.x >= magnitude.z ? 0 : magnitude.y >= magnitude.z ? 1 : 2;
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    const int step = sum[k] < 0.0f ? -1 : 1;
    bool coherent = true;
    for (const Ray& r : rays) coherent = coherent && (step > 0 ? r.direction[k] > 0.0f : r.direction[k] < 0.0f);
    if (!coherent) {  // the 3D-DDA, ray by ray: the same answers
        for (int i = 0; i < n; ++i) hits[i] = walk<kAnyHit>(grid, mesh, rays[i], counters, filter);
        return;
    }
    const GridFrame frame(grid);
    const glm::vec3 margin = insertionMargin(grid);
    PacketRays packet;
    uint64_t active = 0;  // bit i: ray i is still looking
    int first = step > 0 ? frame.last[k] : 0;  // the first slice any ray enters
    for (int i = 0; i < n; ++i) {
        const Ray& r = rays[i];
        packet.test[i].emplace(r);
        for (int a = 0; a < 3; ++a) packet.origin[a][i] = r.origin[a], packet.direction[a][i] = r.direction[a];
        packet.inverseK[i] = 1.0f / r.direction[k];
        packet.bestT[i] = hits[i].t;
        packet.entry[i] = 0.0f;
        const bool inGrid = RayBoxTest(r).hits(grid.bounds.lo, grid.bounds.hi, r.tMin, r.tMax, &packet.entry[i]);
        packet.looking[i] = inGrid ? 1.0f : 0.0f;
        if (!inGrid) continue;
        active |= uint64_t(1) << i;
        const int slice = frame.cellOf(r.origin + r.direction * packet.entry[i])[k];
        first = step > 0 ? std::min(first, slice) : std::max(first, slice);
    }
    for (int i = n; i < kMaxGridPacketRays; ++i) packet.bestT[i] = 0.0f;  // read with their lanes' group, never wanted
    // The rays in the triangle test's lanes, when they share its axis permutation (a coherent
    // packet's nearly always do; else each candidate ray is tested on its own).
    PacketTriangleLanes lanes;
    bool inLanes;
    {
        const WatertightRay* tests[kMaxGridPacketRays];
        float tMins[kMaxGridPacketRays];
        for (int i = 0; i < n; ++i) tests[i] = &*packet.test[i], tMins[i] = rays[i].tMin;
        inLanes = lanes.set(tests, tMins, n);
    }
    auto retire = [&](int i) { active &= ~(uint64_t(1) << i), packet.looking[i] = 0.0f; };
    SliceStretches stretch{};  // zeroed: the cull reads whole 8-ray words, past the packet's last ray too
    // The near and far faces of slices `from` to `to` in the direction of travel; the crossing
    // rays' stretches between them (stretchesInSlice) and the rectangle their boxes' union spans.
    glm::vec3 rectLo, rectHi;
    uint64_t crossing = 0;
    const auto stretchesAndRectangle = [&](int from, int to) {
        stretchesInSlice(packet, n, k, faceAt(grid, k, from + (step > 0 ? 0 : 1)), faceAt(grid, k, to + (step > 0 ? 1 : 0)),
                         margin, stretch);
        rectLo = glm::vec3(std::numeric_limits<float>::max()), rectHi = glm::vec3(std::numeric_limits<float>::lowest());
        crossing = 0;
        for (int i = 0; i < n; ++i) crossing |= uint64_t(stretch.crosses[i] != 0) << i;
        for (uint64_t bits = crossing; bits; bits &= bits - 1) {
            const int i = std::countr_zero(bits);
            for (int a = 0; a < 3; ++a)
                rectLo[a] = std::min(rectLo[a], stretch.lo[a][i]), rectHi[a] = std::max(rectHi[a], stretch.hi[a][i]);
        }
    };
    constexpr int M = kGridMacrocellCells;
    int macrocellLayerChecked = -1;
    for (int slice = first; active && slice >= 0 && slice <= frame.last[k]; slice += step) {
        // Macrocells (§2.4), on entering a layer of them: the slices the packet has left in the
        // layer as one slab; if no macrocell the slab's rectangle touches is occupied, no ray can
        // hit anything in it (each slice's rectangle lies in the slab's, whose stretches contain
        // the slices'), and the packet steps past the layer.
        bool stretchesAreThisSlice = false;
        if (slice / M != macrocellLayerChecked) {
            macrocellLayerChecked = slice / M;
            const int slabEnd = step > 0 ? std::min(slice / M * M + M - 1, frame.last[k]) : slice / M * M;
            stretchesAndRectangle(slice, slabEnd);
            if (!crossing || !anyMacrocellOccupied(grid, frame, k, macrocellLayerChecked, rectLo, rectHi)) {
                if (counters) counters->slicesSkipped += uint64_t(std::abs(slabEnd - slice) + 1);
                slice = slabEnd;
                continue;
            }
            stretchesAreThisSlice = slabEnd == slice;  // a slab of one slice (the grid's last layer may end so)
        }
        if (!stretchesAreThisSlice) stretchesAndRectangle(slice, slice);
        if (crossing) {
            // The 8-ray words the crossing rays lie in, for the cull below.
            const int firstWord = std::countr_zero(crossing) / 8, lastWord = (63 - std::countl_zero(crossing)) / 8;
            glm::vec3 a = rectLo, b = rectHi;
            a[k] = b[k] = grid.bounds.lo[k] + (float(slice) + 0.5f) * grid.cellSize[k];
            const glm::ivec3 c0 = frame.cellOf(a), c1 = frame.cellOf(b);
            // A triangle listed in several cells of the slice is tested once in it. Across slices
            // it may be tested again: a ray's stretch in one slice says nothing of its next one.
            Mailbox<64> mailbox;
            glm::ivec3 cell;
            cell[k] = slice;
            for (cell[v] = c0[v]; cell[v] <= c1[v]; ++cell[v])
                for (cell[u] = c0[u]; cell[u] <= c1[u]; ++cell[u]) {
                    if (counters) ++counters->cellsVisited;
                    const size_t c = grid.cellIndex(cell.x, cell.y, cell.z);
                    for (uint32_t j = grid.cellStart[c]; j < grid.cellStart[c + 1]; ++j) {
                        const uint32_t triangle = grid.triangleRefs[j];
                        if (mailbox.seen(triangle)) continue;
                        // The box from the vertices, each time: keeping the build's boxes in the
                        // grid (24 bytes a triangle) was measured slower, build and packets alike
                        // (the dragon's build 118 -> 161-207 ms, its 8x8 packets no faster).
                        const glm::vec3 p0 = mesh.vertex(triangle, 0), p1 = mesh.vertex(triangle, 1), p2 = mesh.vertex(triangle, 2);
                        const glm::vec3 triLo = glm::min(p0, glm::min(p1, p2)), triHi = glm::max(p0, glm::max(p1, p2));
                        if (glm::any(glm::greaterThan(triLo, rectHi)) || glm::any(glm::lessThan(triHi, rectLo))) continue;
                        // Frustum culling (Wald et al. §2), per ray: only a ray whose stretch box
                        // meets the triangle's box can hit it in this slice.
                        uint64_t candidates = raysMeetingBox(stretch, firstWord, lastWord, triLo, triHi) & crossing;
                        if (kAnyHit) candidates &= active;  // a ray with a hit is done
                        if (counters) counters->trianglesTested += uint64_t(std::popcount(candidates));
                        // The watertight test across the candidate rays in lanes, then the scalar
                        // test for those it does not reject (the same arithmetic, so the same hits;
                        // rt/packet_triangle_lanes.h). A lone candidate goes straight to the scalar.
                        if (inLanes && (candidates & (candidates - 1)))
                            candidates = raysTheTriangleMayHit(lanes, packet.bestT, candidates, p0, p1, p2);
                        for (; candidates; candidates &= candidates - 1) {
                            const int i = std::countr_zero(candidates);
                            if (!offerHit(*packet.test[i], p0, p1, p2, triangle, rays[i].tMin, hits[i], filter, &rays[i])) continue;
                            packet.bestT[i] = hits[i].t;
                            if (kAnyHit) retire(i);
                        }
                    }
                }
        }
        // Retire the rays whose best hit lies before their exit from this slice (as the walk stops).
        for (int i = 0; i < n; ++i)
            if ((active >> i & 1) && hits[i].t * detail::kEntrySlack < stretch.farT[i]) retire(i);
    }
    for (int i = 0; i < n; ++i)
        if (!hits[i].hit()) hits[i].t = std::numeric_limits<float>::infinity();
}

}  // namespace

glm::ivec3 gridResolution(const Aabb& bounds, size_t triangles, float lambda) {
    if (triangles == 0 || bounds.empty()) return glm::ivec3(0);
    const glm::vec3 e = bounds.extent();
    const float longest = std::max({e.x, e.y, e.z});
    if (!(longest > 0.0f)) return glm::ivec3(1);
    // §3's formula over the axes with extent (a flat scene is a 2D grid of square cells).
    double volume = 1.0;
    int dimensions = 0;
    for (int a = 0; a < 3; ++a)
        if (e[a] > longest * 1e-6f) volume *= e[a], ++dimensions;
    const double cellsPerUnit = std::pow(double(lambda) * double(triangles) / volume, 1.0 / dimensions);
    glm::ivec3 cells;
    for (int a = 0; a < 3; ++a)
        cells[a] = e[a] > longest * 1e-6f ? int(std::clamp(std::lround(e[a] * cellsPerUnit), 1L, long(kGridMaxCellsPerAxis))) : 1;
    return cells;
}

// Each macrocell's flag from its cells' lists, a macrocell layer per task.
static void markOccupiedMacrocells(UniformGrid& grid) {
    constexpr int M = kGridMacrocellCells;
    grid.macrocells = (grid.cells + (M - 1)) / M;
    grid.macrocellOccupied.assign(size_t(grid.macrocells.x) * size_t(grid.macrocells.y) * size_t(grid.macrocells.z), 0);
    tbb::parallel_for(0, grid.macrocells.z, [&](int mz) {
        for (int z = mz * M; z < std::min((mz + 1) * M, grid.cells.z); ++z)
            for (int y = 0; y < grid.cells.y; ++y)
                for (int x = 0; x < grid.cells.x; ++x) {
                    const size_t c = grid.cellIndex(x, y, z);
                    if (grid.cellStart[c + 1] > grid.cellStart[c]) grid.macrocellOccupied[grid.macrocellIndex(x / M, y / M, mz)] = 1;
                }
    });
}

UniformGrid buildUniformGrid(const TriangleMeshView& mesh, float lambda) {
    UniformGrid grid;
    const size_t n = mesh.triangleCount();
    for (size_t t = 0; t < n; ++t) grid.bounds.grow(mesh.triangleBounds(t));
    grid.cells = gridResolution(grid.bounds, n, lambda);
    if (grid.empty()) return grid;
    grid.cellSize = grid.bounds.extent() / glm::vec3(grid.cells);
    const glm::vec3 margin = insertionMargin(grid);
    const GridFrame frame(grid);

    // Counts, then offsets, then the fill; the fill's order depends on scheduling, so each cell's
    // list is sorted after it: the same grid at any thread count.
    std::vector<uint32_t> counts(grid.cellCount() + 1, 0);
    tbb::parallel_for(size_t(0), n, [&](size_t t) {
        forEachCell(cellsOfTriangle(frame, margin, mesh, t), [&](int x, int y, int z) {
            std::atomic_ref<uint32_t>(counts[grid.cellIndex(x, y, z)]).fetch_add(1, std::memory_order_relaxed);
        });
    });
    grid.cellStart.resize(grid.cellCount() + 1);
    uint32_t total = 0;
    for (size_t c = 0; c < grid.cellCount(); ++c) grid.cellStart[c] = total, total += counts[c];
    grid.cellStart[grid.cellCount()] = total;
    grid.triangleRefs.resize(total);
    std::copy(grid.cellStart.begin(), grid.cellStart.end(), counts.begin());  // now each cell's cursor
    tbb::parallel_for(size_t(0), n, [&](size_t t) {
        forEachCell(cellsOfTriangle(frame, margin, mesh, t), [&](int x, int y, int z) {
            const uint32_t slot = std::atomic_ref<uint32_t>(counts[grid.cellIndex(x, y, z)]).fetch_add(1, std::memory_order_relaxed);
            grid.triangleRefs[slot] = uint32_t(t);
        });
    });
    tbb::parallel_for(size_t(0), grid.cellCount(), [&](size_t c) {
        std::sort(grid.triangleRefs.begin() + grid.cellStart[c], grid.triangleRefs.begin() + grid.cellStart[c + 1]);
    });
    markOccupiedMacrocells(grid);
    return grid;
}

RayHit closestHit(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters,
                  const HitFilter* filter) {
    return walk<false>(grid, mesh, ray, counters, filter);
}

bool anyHit(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters,
            const HitFilter* filter) {
    return walk<true>(grid, mesh, ray, counters, filter).hit();
}

void closestHits(const UniformGrid& grid, const TriangleMeshView& mesh, std::span<const Ray> rays, std::span<RayHit> hits,
                 GridCounters* counters, const HitFilter* filter) {
    tracePacket<false>(grid, mesh, rays, hits, counters, filter);
}

void anyHits(const UniformGrid& grid, const TriangleMeshView& mesh, std::span<const Ray> rays, std::span<uint8_t> occluded,
             GridCounters* counters, const HitFilter* filter) {
    RayHit hits[kMaxGridPacketRays];
    for (size_t first = 0; first < rays.size(); first += kMaxGridPacketRays) {
        const size_t count = std::min(rays.size() - first, size_t(kMaxGridPacketRays));
        tracePacket<true>(grid, mesh, rays.subspan(first, count), std::span(hits, count), counters, filter);
        for (size_t i = 0; i < count; ++i) occluded[first + i] = hits[i].hit();
    }
}

}  // namespace cuberille::rt
