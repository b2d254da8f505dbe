#pragma once
// The vertex stage's position work in vector lanes: transform, clip outcode and projection to
// the snapped window position for a chunk of vertices at once.
//
// One vertex at a time, this was three calls per vertex (outcode(), projectToWindow(),
// snapToSubpixels()), each seven or more dependent scalar steps: on a 2048^3 voxel frame the
// post-transform was 12% of the process's samples and the vertex stage a sixth of the frame
// (perf record, `render --zoom 3`). Here the chunk's positions go into structure-of-arrays
// lanes and each step is a loop the compiler vectorises for each instruction set (compiled once
// per set like the back end, raster/instruction_set.h).
//
// The same bits as the scalar functions (VertexLanes.MatchScalarVertexStageOnRandomAndHardPositions,
// per instruction set): the transform is glm's mat4 * vec4 in its order of operations,
// (m0 x + m1 y) + (m2 z + m3 w); each plane distance is clip.cpp's planeDistance(); the divide,
// viewport transform, snap and clamp are projectToWindow()'s; finiteness is tested on the
// exponent bits, which is what std::isfinite answers. No contraction (-ffp-contract=off), so a
// lane rounds every operation as a scalar register does.

#include <cstddef>
#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "raster/clip.h"
#include "raster/draw.h"
#include "raster/setup.h"
#include "raster/vertex.h"

namespace cuberille::raster {

/// Vertices per chunk: the chunk's lanes (about 20 floats a vertex) stay in the first-level cache.
inline constexpr int kVertexChunkVertices = 256;

/// What the lanes read of a draw and its viewport, as plain floats.
struct VertexTransform {
    bool window;  // window-space positions: clip = (p, 1)
    float m[4][4];  // clipFromObject, column-major as glm stores it: m[column][row]
    float plane[ClipVolume::kPlaneCount][4];
    float scaleX, scaleY, offsetX, offsetY;  // SetupContext's viewport transform
};

/// Vertices [begin, end) of positions: their clip positions (clipFromObject * (p, 1), or (p, 1)
/// for window-space draws), their outcodes against `volume` (kInvalidVertex where a coordinate
/// is not finite) and, where the outcode is 0, their window positions (projectToWindow(); an
/// outcode of kInvalidVertex where that is not finite). Window entries of other vertices are
/// left as they were.
void transformAndProjectVertices(std::span<const glm::vec3> positions, PositionSpace space, const glm::mat4& clipFromObject,
                                 const ClipVolume& volume, const SetupContext& viewport, size_t begin, size_t end,
                                 glm::vec4* clipPositions, uint8_t* outcodes, WindowVertex* window);

}  // namespace cuberille::raster
