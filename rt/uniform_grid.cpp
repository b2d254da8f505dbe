#include "rt/uniform_grid.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <tbb/parallel_for.h>

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

// The cells a triangle is listed in: those its bounding box, grown by the margin, overlaps.
CellRange cellsOfTriangle(const GridFrame& frame, const glm::vec3& margin, const TriangleMeshView& mesh, size_t triangle) {
    const Aabb b = mesh.triangleBounds(triangle);
    return {frame.cellOf(b.lo - margin), frame.cellOf(b.hi + margin)};
}

template <class Body>
void forEachCell(const CellRange& r, Body&& body) {
    for (int z = r.lo.z; z <= r.hi.z; ++z)
        for (int y = r.lo.y; y <= r.hi.y; ++y)
            for (int x = r.lo.x; x <= r.hi.x; ++x) body(x, y, z);
}

// The walk (header comment): test each cell's triangles, then stop once the best hit lies
// before the next cell's entry, else step into the cell whose face the ray crosses first.
template <bool kAnyHit>
RayHit walk(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters) {
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
    // Mailbox (Wald et al. §2): a triangle listed in several cells is tested once a ray. Skipping
    // the retest is exact: it could only be rejected again, the best t having shrunk since.
    uint32_t mailbox[16];
    std::fill(std::begin(mailbox), std::end(mailbox), RayHit::kNone);
    for (;;) {
        if (counters) ++counters->cellsVisited;
        const size_t c = grid.cellIndex(cell.x, cell.y, cell.z);
        for (uint32_t i = grid.cellStart[c]; i < grid.cellStart[c + 1]; ++i) {
            const uint32_t triangle = grid.triangleRefs[i];
            if (mailbox[triangle & 15] == triangle) continue;
            mailbox[triangle & 15] = triangle;
            if (counters) ++counters->trianglesTested;
            RayHit candidate;
            if (!triangleTest.intersect(mesh.vertex(triangle, 0), mesh.vertex(triangle, 1), mesh.vertex(triangle, 2), ray.tMin,
                                        best.t, &candidate))
                continue;
            candidate.triangle = triangle;
            if (kAnyHit) return candidate;
            if (candidate.closerThan(best.t, best.triangle)) best = candidate;
        }
        // Each face's crossing from the face itself, not accumulated (the header's argument).
        int axis = 0;
        float exit = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
            const float face = grid.bounds.lo[a] + float(cell[a] + (step[a] > 0 ? 1 : 0)) * grid.cellSize[a];
            const float t = (face - ray.origin[a]) * inverseDirection[a];
            if (t < exit) exit = t, axis = a;  // NaN (a zero component on the face) never wins
        }
        // A triangle first listed in a later cell has its hit past that cell's face plus the margin.
        if (best.t * detail::kEntrySlack < exit) break;
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] > frame.last[axis]) break;
    }
    if (!best.hit()) best.t = std::numeric_limits<float>::infinity();
    return best;
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

UniformGrid buildUniformGrid(const TriangleMeshView& mesh, float lambda) {
    UniformGrid grid;
    const size_t n = mesh.triangleCount();
    for (size_t t = 0; t < n; ++t) grid.bounds.grow(mesh.triangleBounds(t));
    grid.cells = gridResolution(grid.bounds, n, lambda);
    if (grid.empty()) return grid;
    grid.cellSize = grid.bounds.extent() / glm::vec3(grid.cells);
    const glm::vec3 lo = glm::abs(grid.bounds.lo), hi = glm::abs(grid.bounds.hi);
    const float largest = std::max({lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
    const float ulpFloor = 16.0f * largest * std::numeric_limits<float>::epsilon();
    const glm::vec3 margin = glm::max(grid.cellSize * kGridInsertionMargin, glm::vec3(ulpFloor));
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
    return grid;
}

RayHit closestHit(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters) {
    return walk<false>(grid, mesh, ray, counters);
}

bool anyHit(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters) {
    return walk<true>(grid, mesh, ray, counters).hit();
}

}  // namespace cuberille::rt
