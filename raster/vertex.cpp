#include "raster/vertex.h"

#include <algorithm>

#include "raster/vertex_lanes.h"

namespace cuberille::raster {
namespace {

/// The varyings of vertices [begin, end), one attribute at a time: each pass is a straight loop
/// over the vertices with the same expression for every one (the per-vertex layout tests, taken
/// once per vertex for each attribute, were most of this stage's scalar time on voxel frames,
/// whose faces bring four vertices each). The values are those of glm's products in their order.
void writeVaryings(const DrawCall& draw, const VaryingLayout& layout, size_t begin, size_t end, float* out) {
    const size_t stride = size_t(layout.count);
    // Vertices [begin, end) of which the first `have` - begin carry the attribute (an array
    // shorter than the positions leaves the rest to a default).
    auto present = [&](size_t size) { return std::clamp(size, begin, end); };
    if (layout.normal >= 0) {
        const glm::mat3& m = draw.worldFromObjectNormals;
        const size_t have = present(draw.normals.size());
        float* v = out + begin * stride + size_t(layout.normal);
        for (size_t i = begin; i < have; ++i, v += stride) {
            const glm::vec3 n = m * draw.normals[i];
            v[0] = n.x, v[1] = n.y, v[2] = n.z;
        }
        for (size_t i = have; i < end; ++i, v += stride) v[0] = 0.0f, v[1] = 0.0f, v[2] = 1.0f;
    }
    if (layout.color >= 0) {
        const glm::vec3 base(draw.state.constantColor);
        const size_t have = present(draw.vertexColors.size());
        float* v = out + begin * stride + size_t(layout.color);
        for (size_t i = begin; i < have; ++i, v += stride) {
            const glm::vec3 c = base * draw.vertexColors[i];
            v[0] = c.x, v[1] = c.y, v[2] = c.z;
        }
        for (size_t i = have; i < end; ++i, v += stride) v[0] = base.x, v[1] = base.y, v[2] = base.z;
    }
    if (layout.alpha >= 0) {
        float* v = out + begin * stride + size_t(layout.alpha);
        for (size_t i = begin; i < end; ++i, v += stride) v[0] = draw.state.constantColor.a * draw.vertexAlphas[i];
    }
    if (layout.texCoord >= 0) {
        float* v = out + begin * stride + size_t(layout.texCoord);
        for (size_t i = begin; i < end; ++i, v += stride) v[0] = draw.texCoords[i].x, v[1] = draw.texCoords[i].y;
    }
    if (layout.position >= 0) {
        float* v = out + begin * stride + size_t(layout.position);
        if (draw.space == PositionSpace::Window) {
            for (size_t i = begin; i < end; ++i, v += stride) v[0] = draw.positions[i].x, v[1] = draw.positions[i].y, v[2] = draw.positions[i].z;
        } else {
            const glm::mat4& m = draw.worldFromObject;
            for (size_t i = begin; i < end; ++i, v += stride) {
                const glm::vec3 p(m * glm::vec4(draw.positions[i], 1.0f));
                v[0] = p.x, v[1] = p.y, v[2] = p.z;
            }
        }
    }
    if (layout.tangent >= 0) {
        const glm::mat3& m = draw.worldFromObjectNormals;
        float* v = out + begin * stride + size_t(layout.tangent);
        for (size_t i = begin; i < end; ++i, v += stride) {
            const glm::vec3 t = m * glm::vec3(draw.tangents[i]);
            v[0] = t.x, v[1] = t.y, v[2] = t.z, v[3] = draw.tangents[i].w;
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
