#pragma once
// Vertex stage: object-space vertices in; per vertex out:
// - the clip-space position and the varyings the draw's shading reads (VaryingLayout: none
//   for ConstantColor), so nothing is computed or interpolated that no later stage consumes;
// - the post-transform data every triangle sharing the vertex would otherwise recompute: its
//   clip outcode and, when it lies inside the clip volume, its snapped window position.
// Thread-safety: runs in parallel over fixed vertex ranges; output depends on input alone.

#include <algorithm>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "raster/clip.h"
#include "raster/draw.h"
#include "raster/setup.h"
#include "raster/uninitialized_allocator.h"

namespace cuberille::raster {

/// Outcode bit of a vertex whose position is not finite (or projects to a non-finite point):
/// every triangle using it is dropped and counted.
inline constexpr uint8_t kInvalidVertex = 0x80;
static_assert(ClipVolume::kPlaneCount < 8);

/// Where each attribute sits among a vertex's varyings, derived from what the draw's shading
/// reads and what its mesh carries; -1 for an attribute that is not interpolated at all.
struct VaryingLayout {
    int normal = -1;    // 3: world-space normal; Lambert, MetallicRoughness
    int color = -1;     // 3: linear albedo, base colour factor x vertex colour; only with vertex colours
    int alpha = -1;     // 1: factor alpha x vertex alpha; only when the mesh has vertex alphas
    int texCoord = -1;  // 2: only when a texture is bound and the mesh has texture coordinates
    int position = -1;  // 3: world position; MetallicRoughness, and Lambert with point or spot lights
    int tangent = -1;   // 4: world tangent and handedness; only for a usable normal map
    int count = 0;
};
static_assert(3 + 3 + 1 + 2 + 3 + 4 <= kMaxVaryings);

struct VertexStageOutput {
    // Written for every vertex by the stage's threads; sized without a zero-fill before them.
    UninitializedVector<glm::vec4> clipPositions;
    UninitializedVector<uint8_t> outcodes;   // planes the vertex is outside of, or kInvalidVertex
    UninitializedVector<WindowVertex> window;  // valid (and written) only where the outcode is 0
    UninitializedVector<float> varyings;     // vertex-major, layout.count floats per vertex
    VaryingLayout layout;                // the draw's, derived once per flush

    void resize(size_t vertices, const VaryingLayout& varyingLayout);
    size_t capacityBytes() const {
        return clipPositions.capacity() * sizeof(glm::vec4) + outcodes.capacity() + window.capacity() * sizeof(WindowVertex) +
               varyings.capacity() * sizeof(float);
    }
};

VaryingLayout varyingLayoutFor(const DrawCall& draw);

/// Vertices are processed in tasks of this many.
inline constexpr size_t kVerticesPerTask = 16384;

/// Shades vertices [begin, end) of the draw into `out`, already sized by
/// out.resize(vertexCount, varyingLayoutFor(draw)).
void runVertexStage(const DrawCall& draw, const ClipVolume& volume, const SetupContext& viewport,
                    size_t begin, size_t end, VertexStageOutput& out);

/// The front end's path for a triangle that crosses clip planes (bits `crossedPlanes` of its
/// vertices' outcodes): clipped in homogeneous space, every polygon vertex projected to the window,
/// then piece(window[3], varyings[3]) for each triangle of its fan, in order. False, with no piece,
/// when a polygon vertex does not project (not finite). The forward front end (pipeline.cpp) and
/// the deferred shade's set-up (visibility_shade.cpp) both clip through it.
template <class Piece>
bool clipAndProjectFan(const VertexStageOutput& vertices, const ClipVolume& volume, const SetupContext& viewport,
                       const size_t (&index)[3], uint32_t crossedPlanes, Piece&& piece) {
    const auto clipVertex = [&](size_t i) {
        ClipVertex c;
        c.position = vertices.clipPositions[i];
        std::copy_n(vertices.varyings.data() + i * vertices.layout.count, vertices.layout.count, c.varyings.data());
        return c;
    };
    ClippedPolygon polygon;
    clipTriangle(volume, crossedPlanes, clipVertex(index[0]), clipVertex(index[1]), clipVertex(index[2]), vertices.layout.count,
                 polygon);
    WindowVertex window[kMaxClippedVertices];
    for (int i = 0; i < polygon.count; ++i)
        if (!projectToWindow(polygon.vertices[i].position, viewport, window[i])) return false;
    for (int i = 2; i < polygon.count; ++i) {
        const WindowVertex w[3] = {window[0], window[i - 1], window[i]};
        const float* const v[3] = {polygon.vertices[0].varyings.data(), polygon.vertices[i - 1].varyings.data(),
                                   polygon.vertices[i].varyings.data()};
        piece(w, v);
    }
    return true;
}

}  // namespace cuberille::raster
