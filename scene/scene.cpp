#include "scene/scene.h"

#include <algorithm>

namespace cuberille::scene {

size_t Scene::triangleCount() const {
    size_t n = 0;
    for (const Mesh& m : meshes) n += m.triangleCount();
    return n;
}

void Scene::draw(raster::Pipeline& pipeline, float aspect, const raster::Lighting* shadowedLighting) const {
    const glm::mat4 clipFromWorld = camera.clipFromWorld(aspect);
    std::vector<size_t> order, blended;
    for (size_t i = 0; i < meshes.size(); ++i)
        (meshes[i].seeThrough() ? blended : order).push_back(i);
    std::vector<float> distance(meshes.size(), 0.0f);
    for (size_t i : blended) {
        const Bounds b = boundsOf(meshes[i]);
        distance[i] = b.empty() ? 0.0f : glm::distance(camera.position, 0.5f * (b.min + b.max));
    }
    std::stable_sort(blended.begin(), blended.end(), [&](size_t a, size_t b) { return distance[a] > distance[b]; });
    order.insert(order.end(), blended.begin(), blended.end());
    for (size_t index : order) {
        const Mesh& m = meshes[index];
        raster::DrawCall d;
        d.space = raster::PositionSpace::Clip;
        d.clipFromObject = clipFromWorld;
        // A mesh's triangles are its indices (Mesh::triangleCount): one without any draws nothing,
        // where a draw of no indices would take its vertices as an unindexed list. The draw is
        // still recorded, so the draws stay one per mesh in order (render::SceneShadows::seenDraws).
        if (!m.indices.empty()) d.positions = m.positions;
        d.normals = m.normals;
        d.vertexColors = m.colors;
        d.vertexAlphas = m.alphas;
        d.indices = m.indices;
        using raster::ShadingModel;
        d.state.shading = m.unlit ? ShadingModel::Unlit
                                  : (m.metallicRoughness ? ShadingModel::MetallicRoughness : ShadingModel::Lambert);
        // An unlit mesh of one colour (no vertex colours or alphas, no textures) is a flat
        // draw: the bare pipeline, nothing interpolated.
        const bool textured = m.texCoords.size() == m.positions.size() &&
                              (m.textures.baseColor || m.textures.emissive || m.textures.normal);
        if (m.unlit && m.colors.empty() && m.alphas.empty() && !textured) d.state.shading = ShadingModel::ConstantColor;
        d.texCoords = m.texCoords;
        d.tangents = m.tangents;
        auto bind = [](const MeshTexture& t) { return raster::TextureBinding{t.texture.get(), t.transform}; };
        d.state.textures = {bind(m.textures.baseColor), bind(m.textures.metallicRoughness), bind(m.textures.normal),
                            bind(m.textures.occlusion), bind(m.textures.emissive), bind(m.textures.specular),
                            bind(m.textures.specularColor), bind(m.textures.clearcoat), bind(m.textures.clearcoatRoughness),
                            bind(m.textures.clearcoatNormal), bind(m.textures.sheenColor), bind(m.textures.sheenRoughness),
                            bind(m.textures.transmission), bind(m.textures.thickness)};
        d.state.cull = m.doubleSided ? raster::CullMode::None : cull;
        d.state.constantColor = glm::vec4(m.color, m.alpha);
        d.state.alphaMode = m.alphaMode;
        d.state.alphaCutoff = m.alphaCutoff;
        d.state.depthWrite = !m.seeThrough();
        d.state.lighting = shadowedLighting && !m.seeThrough() ? *shadowedLighting : lighting;
        d.state.metallic = m.metallic;
        d.state.roughness = m.roughness;
        d.state.dielectricF0 = dielectricReflectance(m.ior);
        d.state.brdf = m.brdf;
        d.state.emissive = m.emissive;
        d.state.normalScale = m.normalScale;
        d.state.occlusionStrength = m.occlusionStrength;
        d.state.cameraPosition = camera.position;
        pipeline.draw(d);
    }
}

}  // namespace cuberille::scene
