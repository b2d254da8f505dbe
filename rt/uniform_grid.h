#pragma once
// A uniform grid over triangles, rebuilt from scratch every frame (Wald, Ize, Kensler, Knoll and
// Parker 2006, "Ray Tracing Animated Scenes using Coherent Grid Traversal", section 3): no
// hierarchy to keep, so any animation works, at a build cost linear in the triangles.
//
// The grid has about lambda cells per triangle, cubical ones (§3: N_a = d_a cbrt(lambda N / V)),
// and each cell lists the triangles whose bounding box overlaps it (the paper's cheap insertion;
// an exact triangle-in-box test cut references by a third but intersection tests by only a few
// percent). Here each box is first grown by kGridInsertionMargin, which is what makes the
// traversal exact (below).
//
// Single rays walk the cells in order by the 3D-DDA (Amanatides and Woo 1987), the baseline the
// paper's packets are measured against. The answer is exactly that of testing every triangle
// (closestHitBruteForce): the same watertight test decides every hit, ties go to the lower id, and
// the walk stops only once the best hit lies before the next cell's entry.
//
// Why the margin: a hit point lies in its triangle's bounding box, so in every cell that box
// overlaps; but the walk computes its start cell and each crossing in float, so near a cell's face
// or corner it may visit the neighbour of the cell the exact ray is in. Each crossing is computed
// afresh from the cell's face (never accumulated), a few roundings of the coordinates, so the walk
// is never further than the margin from the exact path, and a triangle whose hit is near a face
// is listed on both sides of it. A point exactly on a face needs no margin — the walk and the
// insertion place it by the same floor, and a cell is tested before it is left — and the tests'
// hard cases (the lattice of faces, edges and vertices, flat and far scenes) pass without it too:
// it guards the rounding cases no test has found, at the cost of a few more references.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "rt/aabb.h"
#include "rt/ray.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// lambda, cells per triangle: Wald et al. found nearly every scene at its best around 5
/// (Figure 6), and used 5 throughout; for models of millions of triangles, where the build
/// outweighs the rays, 1 (§4.4).
inline constexpr float kGridCellsPerTriangle = 5.0f;

/// The most cells along one axis: a bound on memory for a scene of a few huge triangles and
/// many tiny ones (the teapot in a stadium, which §6 says a uniform grid suits poorly anyway).
inline constexpr int kGridMaxCellsPerAxis = 1024;

/// How far past its bounding box a triangle is listed, as a fraction of a cell: the walk's
/// crossings are a few float roundings from the exact ones, orders of magnitude below this.
/// Absolute floor: 16 ulps of the grid's largest coordinate, for scenes far from the origin.
inline constexpr float kGridInsertionMargin = 1.0f / 1024.0f;

/// Macrocells (Wald et al. §2.4): a coarser grid over the cells, each macrocell M x M x M cells
/// with a flag saying whether any of them lists a triangle, so a packet skips M empty slices in
/// one step. The paper found M = 6 consistently good.
inline constexpr int kGridMacrocellCells = 6;

struct UniformGrid {
    Aabb bounds;                      // the triangles' box; the cells tile it
    glm::ivec3 cells{0};              // resolution per axis; 0 for an empty grid
    glm::vec3 cellSize{0.0f};
    std::vector<uint32_t> cellStart;  // cell c's triangles: triangleRefs[cellStart[c] .. cellStart[c + 1])
    std::vector<uint32_t> triangleRefs;  // each cell's triangle ids, ascending
    glm::ivec3 macrocells{0};            // ceil(cells / kGridMacrocellCells) per axis
    std::vector<uint8_t> macrocellOccupied;  // 1 where a cell of the macrocell lists a triangle

    bool empty() const { return cells.x == 0; }
    size_t cellCount() const { return size_t(cells.x) * size_t(cells.y) * size_t(cells.z); }
    size_t cellIndex(int x, int y, int z) const { return (size_t(z) * size_t(cells.y) + size_t(y)) * size_t(cells.x) + size_t(x); }
    size_t macrocellIndex(int x, int y, int z) const {
        return (size_t(z) * size_t(macrocells.y) + size_t(y)) * size_t(macrocells.x) + size_t(x);
    }
};

/// The resolution Wald et al. choose for `triangles` triangles in `bounds`: cubical cells, about
/// `lambda` per triangle; an axis of zero extent (a flat scene) gets one cell.
glm::ivec3 gridResolution(const Aabb& bounds, size_t triangles, float lambda = kGridCellsPerTriangle);

/// Builds the grid from scratch, in parallel (counts, prefix sum, fill, each cell's list sorted):
/// the same grid at any thread count.
UniformGrid buildUniformGrid(const TriangleMeshView& mesh, float lambda = kGridCellsPerTriangle);

/// The work one walk did: cells visited and triangle tests (after the mailbox).
struct GridCounters {
    uint64_t cellsVisited = 0;
    uint64_t trianglesTested = 0;
    uint64_t slicesSkipped = 0;  // packets: slices stepped over in empty macrocells
    uint64_t macrocellsSkipped = 0;  // single rays: empty macrocells left in one step
};

/// Closest hit and any hit by the 3D-DDA, leaving an empty macrocell in one step; exactly
/// closestHitBruteForce's and anyHitBruteForce's answers (rt/ray_query.h).
/// `filter`: what the search leaves out (rt/ray.h, HitFilter).
RayHit closestHit(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters = nullptr,
                  const HitFilter* filter = nullptr);
bool anyHit(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray, GridCounters* counters = nullptr,
            const HitFilter* filter = nullptr);

/// The most rays one packet holds: 8x8, the paper's best size below 250k triangles (§4.1).
inline constexpr int kMaxGridPacketRays = 64;

/// Closest hits of a packet of rays traced together slice by slice (Wald et al. §2): along the
/// packet's major axis K, each slice of cells one cell thick is entered once for the whole
/// packet, and the rectangle of cells the packet's rays cross in it (from each ray's two points on
/// the slice's faces, grown by the margin) is tested against every ray still looking — one
/// traversal step for the packet where the 3D-DDA takes one per ray per cell. A ray retires once
/// its best hit lies before its exit from the slice. On entering each layer of macrocells the
/// packet takes its remaining slices in the layer as one slab: if no macrocell under the slab's
/// rectangle is occupied, it steps over them all (§2.4). The rays need not share an origin (a shadow
/// packet toward a light) but must all travel the same way along K; a packet that does not (a
/// wide camera's rays at 45°, rays parallel to every slice) is walked ray by ray instead.
/// hits[i] is exactly closestHit(rays[i]) (so brute force's), whatever the packet's size and
/// shape. More than kMaxGridPacketRays rays are traced as consecutive packets of that many.
void closestHits(const UniformGrid& grid, const TriangleMeshView& mesh, std::span<const Ray> rays, std::span<RayHit> hits,
                 GridCounters* counters = nullptr, const HitFilter* filter = nullptr);

/// Any hit for a packet (shadow rays toward one light, the paper's shadow packets): occluded[i] is
/// exactly anyHit(rays[i]); a ray retires at its first hit.
void anyHits(const UniformGrid& grid, const TriangleMeshView& mesh, std::span<const Ray> rays, std::span<uint8_t> occluded,
             GridCounters* counters = nullptr, const HitFilter* filter = nullptr);

}  // namespace cuberille::rt
