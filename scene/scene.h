#pragma once
// A renderable scene: meshes, a camera, lights and a background, whatever produced it (a
// built-in procedural scene, a glTF, PLY or OBJ file).

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "scene/camera.h"
#include "scene/load_stats.h"
#include "scene/mesh.h"

namespace cuberille::scene {

struct Scene {
    std::string name;
    std::vector<Mesh> meshes;
    Camera camera;
    raster::Lighting lighting;  // the scene's lights and ambient term
    glm::vec4 background{0.0f, 0.0f, 0.0f, 1.0f};
    raster::CullMode cull = raster::CullMode::Back;
    LoadStats loadStats;

    size_t triangleCount() const;
    /// Submits every mesh as one depth-tested draw: opaque and alpha-tested meshes in order,
    /// then blended ones back to front (by the distance from the camera to their bounds'
    /// centre, ties by mesh order, so the order is deterministic), without depth writes. The
    /// scene must outlive the frame (Pipeline::draw records). `shadowedLighting`, when given,
    /// replaces `lighting` for the opaque and alpha-tested meshes: the same lights carrying
    /// screen-space shadow masks (render/scene_shadows.h). The masks describe the opaque surface
    /// at each pixel, so blended meshes in front of it keep the unshadowed lights.
    void draw(raster::Pipeline& pipeline, float aspect, const raster::Lighting* shadowedLighting = nullptr) const;
};

}  // namespace cuberille::scene
