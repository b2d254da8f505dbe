#pragma once
// The deferred shade stage's per-frame tables (raster/visibility_shade.h), shared by its two
// halves: the front half (visibility_shade.cpp: which triangles are seen, their vertex stage and
// set-ups, compiled once) and the per-tile shade stage (visibility_shade_tile.cpp, compiled once
// per instruction set as the forward back end is, raster/instruction_set.h). Not part of the API.

#include <cstdint>
#include <span>
#include <vector>

#include "raster/draw.h"
#include "raster/framebuffer.h"
#include "raster/setup.h"
#include "raster/stats.h"
#include "raster/vertex.h"
#include "raster/visibility_shade.h"

namespace cuberille::raster::seen {

inline constexpr uint32_t kNone = VisibilityBuffer::kNone;
/// The seen triangles of a draw are set up in chunks of this many, one task each.
inline constexpr size_t kSeenTrianglesPerChunk = 4096;

/// The set-ups one seen triangle became: one, or a fan where a clip plane cut it, or none where
/// it has zero area once snapped. Indices into its chunk's set-ups.
struct SeenPieces {
    uint32_t first = 0;
    uint32_t count = 0;
};

struct SetupChunk {
    std::vector<TriangleSetup> setups;
    std::vector<float> varyings;  // three vertices' a set-up, in set-up order (TriangleSetup::varyingOffset)
};

/// What the frame knows of one draw: which of its triangles the buffer names, their set-ups,
/// and its vertex stage's outputs.
struct SeenDraw {
    std::vector<uint32_t> slotOf;    // per triangle of the draw: its slot among the seen ones, or kNone
    std::vector<uint32_t> seen;      // per slot: the triangle, ascending
    std::vector<SeenPieces> pieces;  // per slot
    std::vector<SetupChunk> chunks;  // slot / kSeenTrianglesPerChunk
    VertexStageOutput vertices;
};

/// The shade stage and output merge of one tile's seen samples, on the instruction set chosen at
/// run time; adds its work to `counters` and the samples whose triangle has no set-up to
/// `withoutSetUp`.
void shadeTile(std::span<const DrawCall> draws, const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& buffer,
               int tile, Framebuffer& fb, StageCounters& counters, uint64_t& withoutSetUp);

}  // namespace cuberille::raster::seen
