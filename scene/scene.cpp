#include "scene/scene.h"

namespace cuberille::scene {

size_t Scene::triangleCount() const {
    size_t n = 0;
    for (const Mesh& m : meshes) n += m.triangleCount();
    return n;
}

void Scene::draw(raster::Pipeline& pipeline, float aspect) const {
    const glm::mat4 clipFromWorld = camera.clipFromWorld(aspect);
    for (const Mesh& m : meshes) {
        raster::DrawCall d;
        d.space = raster::PositionSpace::Clip;
        d.clipFromObject = clipFromWorld;
        d.positions = m.positions;
        d.normals = m.normals;
        d.vertexColors = m.colors;
        d.indices = m.indices;
        const bool textured = m.baseColorTexture && m.texCoords.size() == m.positions.size();
        using raster::ShadingModel;
        d.state.shading = m.unlit ? (textured ? ShadingModel::TexturedUnlit : ShadingModel::Unlit)
                                  : (textured ? ShadingModel::TexturedLambert : ShadingModel::Lambert);
        if (textured) {
            d.texCoords = m.texCoords;
            d.state.baseColorTexture = m.baseColorTexture.get();
        }
        d.state.cull = m.doubleSided ? raster::CullMode::None : cull;
        d.state.constantColor = glm::vec4(m.color, 1.0f);
        d.state.light = light;
        pipeline.draw(d);
    }
}

}  // namespace cuberille::scene
