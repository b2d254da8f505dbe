#include "raster/vertex.h"

#include "raster/parallel.h"

namespace cuberille::raster {
namespace {

constexpr size_t kVerticesPerTask = 16384;

void transformPositions(const DrawCall& draw, size_t begin, size_t end, glm::vec4* out) {
    if (draw.space == PositionSpace::Window) {
        for (size_t i = begin; i < end; ++i) out[i] = glm::vec4(draw.positions[i], 1.0f);
        return;
    }
    const glm::mat4& m = draw.clipFromObject;
    for (size_t i = begin; i < end; ++i) out[i] = m * glm::vec4(draw.positions[i], 1.0f);
}

// Lambert varyings: world-space normal (3) then linear colour (3).
void lambertVaryings(const DrawCall& draw, size_t begin, size_t end, float* out) {
    const glm::vec3 base(draw.state.constantColor);
    for (size_t i = begin; i < end; ++i) {
        glm::vec3 n = draw.normals.empty() ? glm::vec3(0.0f, 0.0f, 1.0f)
                                           : draw.worldFromObjectNormals * draw.normals[i];
        glm::vec3 c = draw.vertexColors.empty() ? base : base * draw.vertexColors[i];
        float* v = out + i * 6;
        v[0] = n.x, v[1] = n.y, v[2] = n.z;
        v[3] = c.x, v[4] = c.y, v[5] = c.z;
    }
}

}  // namespace

int varyingCountFor(ShadingModel model) {
    switch (model) {
        case ShadingModel::ConstantColor: return 0;
        case ShadingModel::Lambert: return 6;
    }
    return 0;
}

void runVertexStage(const DrawCall& draw, VertexStageOutput& out) {
    const size_t count = draw.positions.size();
    out.varyingCount = varyingCountFor(draw.state.shading);
    out.clipPositions.resize(count);
    out.varyings.resize(count * out.varyingCount);
    const size_t tasks = (count + kVerticesPerTask - 1) / kVerticesPerTask;
    parallelFor(tasks, [&](size_t t) {
        const size_t begin = t * kVerticesPerTask;
        const size_t end = std::min(count, begin + kVerticesPerTask);
        transformPositions(draw, begin, end, out.clipPositions.data());
        if (draw.state.shading == ShadingModel::Lambert)
            lambertVaryings(draw, begin, end, out.varyings.data());
    });
}

}  // namespace cuberille::raster
