#include "raster/vertex.h"

#include "raster/vertex_lanes.h"

namespace cuberille::raster {
namespace {

void writeVaryings(const DrawCall& draw, const VaryingLayout& layout, size_t begin, size_t end, float* out) {
    const glm::vec3 base(draw.state.constantColor);
    for (size_t i = begin; i < end; ++i) {
        float* v = out + i * layout.count;
        if (layout.normal >= 0) {
            const glm::vec3 n = draw.normals.size() <= i ? glm::vec3(0.0f, 0.0f, 1.0f)
                                                         : draw.worldFromObjectNormals * draw.normals[i];
            v[layout.normal] = n.x, v[layout.normal + 1] = n.y, v[layout.normal + 2] = n.z;
        }
        if (layout.color >= 0) {
            const glm::vec3 c = draw.vertexColors.size() <= i ? base : base * draw.vertexColors[i];
            v[layout.color] = c.x, v[layout.color + 1] = c.y, v[layout.color + 2] = c.z;
        }
        if (layout.alpha >= 0) v[layout.alpha] = draw.state.constantColor.a * draw.vertexAlphas[i];
        if (layout.texCoord >= 0) v[layout.texCoord] = draw.texCoords[i].x, v[layout.texCoord + 1] = draw.texCoords[i].y;
        if (layout.position >= 0) {
            const glm::vec3 p = draw.space == PositionSpace::Window
                                    ? draw.positions[i]
                                    : glm::vec3(draw.worldFromObject * glm::vec4(draw.positions[i], 1.0f));
            v[layout.position] = p.x, v[layout.position + 1] = p.y, v[layout.position + 2] = p.z;
        }
        if (layout.tangent >= 0) {
            const glm::vec3 t = draw.worldFromObjectNormals * glm::vec3(draw.tangents[i]);
            v[layout.tangent] = t.x, v[layout.tangent + 1] = t.y, v[layout.tangent + 2] = t.z;
            v[layout.tangent + 3] = draw.tangents[i].w;
        }
    }
}

}  // namespace

void VertexStageOutput::resize(size_t vertices, const VaryingLayout& varyingLayout) {
    layout = varyingLayout;
    clipPositions.resize(vertices);
    outcodes.resize(vertices);
    window.resize(vertices);
    varyings.resize(vertices * varyingLayout.count);
}

VaryingLayout varyingLayoutFor(const DrawCall& draw) {
    const DrawState& state = draw.state;
    VaryingLayout l;
    if (state.shading == ShadingModel::ConstantColor) return l;
    auto take = [&](int floats) {
        const int at = l.count;
        l.count += floats;
        return at;
    };
    const size_t vertices = draw.positions.size();
    const bool lit = state.shading != ShadingModel::Unlit;
    bool pointOrSpot = false;
    for (int i = 0; i < state.lighting.lightCount; ++i)
        pointOrSpot = pointOrSpot || state.lighting.lights[i].type != LightType::Directional;
    const bool textured = state.textures.any() && draw.texCoords.size() == vertices;
    if (lit) l.normal = take(3);
    // Without vertex colours the albedo is the draw's constant: nothing to interpolate.
    if (draw.vertexColors.size() == vertices && vertices > 0) l.color = take(3);
    if (draw.vertexAlphas.size() == vertices && vertices > 0) l.alpha = take(1);
    if (textured) l.texCoord = take(2);
    if (state.shading == ShadingModel::MetallicRoughness || (lit && pointOrSpot)) l.position = take(3);
    const bool normalMapped = state.textures.normal || (state.brdf.clearcoat > 0.0f && state.textures.clearcoatNormal);
    if (lit && textured && normalMapped && draw.tangents.size() == vertices) l.tangent = take(4);
    return l;
}

void runVertexStage(const DrawCall& draw, const ClipVolume& volume, const SetupContext& viewport,
                    size_t begin, size_t end, VertexStageOutput& out) {
    transformAndProjectVertices(draw.positions, draw.space, draw.clipFromObject, volume, viewport, begin, end,
                                out.clipPositions.data(), out.outcodes.data(), out.window.data());
    if (out.layout.count > 0) writeVaryings(draw, out.layout, begin, end, out.varyings.data());
}

}  // namespace cuberille::raster
