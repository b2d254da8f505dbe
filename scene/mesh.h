#pragma once
// A triangle mesh as scenes hand it to the rasterizer: world-space positions, per-vertex
// normals (computed when a file has none), optional per-vertex linear colours, and one
// material colour for the whole mesh.

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/texture.h"

namespace cuberille::scene {

struct Mesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;  // one per position
    std::vector<glm::vec3> colors;   // linear RGB per position; empty when the mesh has none
    std::vector<uint32_t> indices;   // three per triangle
    glm::vec3 color{0.8f};           // linear albedo, multiplied with vertex colours
    bool doubleSided = false;        // never culled, whatever the scene's cull mode
    bool unlit = false;              // colour without lighting (KHR_materials_unlit)
    float alpha = 1.0f;              // material alpha, times the texture's
    raster::AlphaMode alphaMode = raster::AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    std::vector<glm::vec2> texCoords;  // per position, when the mesh is textured
    std::shared_ptr<const raster::Texture> baseColorTexture;  // multiplies the albedo

    size_t triangleCount() const { return indices.size() / 3; }
};

/// Area-weighted vertex normals from the triangles (the cross product's length is twice the
/// area, so summing unnormalised face normals weights them by area). Vertices no triangle
/// uses get (0, 0, 1).
void computeVertexNormals(Mesh& mesh);

struct Bounds {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{std::numeric_limits<float>::lowest()};

    void extend(const glm::vec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    bool empty() const { return min.x > max.x; }
};

Bounds boundsOf(const Mesh& mesh);
Bounds boundsOf(const std::vector<Mesh>& meshes);

/// 8-bit sRGB to linear, for colours stored in files.
float srgbToLinear(float encoded);

}  // namespace cuberille::scene
