#pragma once
// Vertex stage: object-space vertices in, clip-space positions and varyings out.
// Varyings are what the shading model reads (none for ConstantColor; world normal and colour
// for Lambert), so nothing is computed that no later stage consumes.
// Thread-safety: runs in parallel over fixed vertex ranges; output depends on input alone.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"

namespace cuberille::raster {

struct VertexStageOutput {
    std::vector<glm::vec4> clipPositions;
    std::vector<float> varyings;  // vertex-major, varyingCount floats per vertex
    int varyingCount = 0;
};

/// Floats a shading model interpolates per vertex.
int varyingCountFor(ShadingModel model);

void runVertexStage(const DrawCall& draw, VertexStageOutput& out);

}  // namespace cuberille::raster
