#include "raster/vertex.h"

#include <cmath>

namespace cuberille::raster {
namespace {

void transformPositions(const DrawCall& draw, size_t begin, size_t end, glm::vec4* out) {
    if (draw.space == PositionSpace::Window) {
        for (size_t i = begin; i < end; ++i) out[i] = glm::vec4(draw.positions[i], 1.0f);
        return;
    }
    const glm::mat4& m = draw.clipFromObject;
    for (size_t i = begin; i < end; ++i) out[i] = m * glm::vec4(draw.positions[i], 1.0f);
}

// Lambert varyings: world-space normal (3) then linear colour (3); TexturedLambert adds the
// texture coordinates (2).
void lambertVaryings(const DrawCall& draw, size_t begin, size_t end, int stride, float* out) {
    const glm::vec3 base(draw.state.constantColor);
    for (size_t i = begin; i < end; ++i) {
        glm::vec3 n = draw.normals.size() <= i ? glm::vec3(0.0f, 0.0f, 1.0f)
                                               : draw.worldFromObjectNormals * draw.normals[i];
        glm::vec3 c = draw.vertexColors.size() <= i ? base : base * draw.vertexColors[i];
        float* v = out + i * stride;
        v[0] = n.x, v[1] = n.y, v[2] = n.z;
        v[3] = c.x, v[4] = c.y, v[5] = c.z;
        if (stride == 8) {
            const glm::vec2 uv = draw.texCoords.size() > i ? draw.texCoords[i] : glm::vec2(0.0f);
            v[6] = uv.x, v[7] = uv.y;
        }
    }
}

void postTransform(const ClipVolume& volume, const SetupContext& viewport, size_t begin,
                   size_t end, VertexStageOutput& out) {
    for (size_t i = begin; i < end; ++i) {
        const glm::vec4& p = out.clipPositions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(p.w)) {
            out.outcodes[i] = kInvalidVertex;
            continue;
        }
        const uint32_t code = outcode(volume, p);
        out.outcodes[i] = uint8_t(code);
        if (code == 0 && !projectToWindow(p, viewport, out.window[i]))
            out.outcodes[i] = kInvalidVertex;
    }
}

}  // namespace

void VertexStageOutput::resize(size_t vertices, int varyingsPerVertex) {
    varyingCount = varyingsPerVertex;
    clipPositions.resize(vertices);
    outcodes.resize(vertices);
    window.resize(vertices);
    varyings.resize(vertices * varyingsPerVertex);
}

int varyingCountFor(ShadingModel model) {
    switch (model) {
        case ShadingModel::ConstantColor: return 0;
        case ShadingModel::Lambert: return 6;
        case ShadingModel::TexturedLambert: return 8;
        case ShadingModel::Unlit: return 6;
        case ShadingModel::TexturedUnlit: return 8;
    }
    return 0;
}

void runVertexStage(const DrawCall& draw, const ClipVolume& volume, const SetupContext& viewport,
                    size_t begin, size_t end, VertexStageOutput& out) {
    transformPositions(draw, begin, end, out.clipPositions.data());
    if (draw.state.shading != ShadingModel::ConstantColor)
        lambertVaryings(draw, begin, end, out.varyingCount, out.varyings.data());
    postTransform(volume, viewport, begin, end, out);
}

}  // namespace cuberille::raster
