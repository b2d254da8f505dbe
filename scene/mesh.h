#pragma once
// A triangle mesh as scenes hand it to the rasterizer: world-space positions, per-vertex
// normals (computed when a file has none), optional per-vertex linear colours, alphas, texture
// coordinates and tangents, and one material for the whole mesh.

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/texture.h"

namespace cuberille::scene {

/// A texture and the UV transform it is read through (KHR_texture_transform).
struct MeshTexture {
    std::shared_ptr<const raster::Texture> texture;
    raster::UvTransform transform;
    explicit operator bool() const { return texture != nullptr; }
};

/// glTF's material texture slots; all read the mesh's texCoords.
struct MeshTextures {
    MeshTexture baseColor;          // multiplies the albedo and alpha
    MeshTexture metallicRoughness;  // B: metallic, G: roughness (specular-glossiness: RGB specular, A glossiness)
    MeshTexture normal;             // tangent space; needs tangents
    MeshTexture occlusion;          // R
    MeshTexture emissive;           // multiplies the emissive factor
    MeshTexture specular;           // A: KHR_materials_specular's strength
    MeshTexture specularColor;      // RGB: KHR_materials_specular's F0 colour
    MeshTexture clearcoat;          // R: KHR_materials_clearcoat's weight
    MeshTexture clearcoatRoughness; // G: KHR_materials_clearcoat's roughness
    MeshTexture clearcoatNormal;    // KHR_materials_clearcoat's own normal map; needs tangents
    MeshTexture sheenColor;         // RGB: KHR_materials_sheen's colour
    MeshTexture sheenRoughness;     // A: KHR_materials_sheen's roughness
    MeshTexture transmission;       // R: KHR_materials_transmission's share
    MeshTexture thickness;          // G: KHR_materials_volume's thickness
};

/// The reflectance of a dielectric at normal incidence against air, F0 = ((ior - 1) / (ior + 1))²
/// (KHR_materials_ior), in double and rounded once: glTF's default 1.5 gives exactly the 0.04f
/// the BRDF had fixed before, so a material without the extension shades to the same bits.
inline float dielectricReflectance(float ior) {
    const double r = (double(ior) - 1.0) / (double(ior) + 1.0);
    return float(r * r);
}

struct Mesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;  // one per position
    std::vector<glm::vec3> colors;   // linear RGB per position; empty when the mesh has none
    std::vector<uint32_t> indices;   // three per triangle
    glm::vec3 color{0.8f};           // linear albedo, multiplied with vertex colours
    bool doubleSided = false;        // never culled, whatever the scene's cull mode
    bool unlit = false;              // colour without lighting (KHR_materials_unlit)
    bool metallicRoughness = false;  // glTF's BRDF with the factors below; Lambert otherwise
    float alpha = 1.0f;              // material alpha, times vertex and texture alpha
    raster::AlphaMode alphaMode = raster::AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    float metallic = 1.0f, roughness = 1.0f;
    float ior = 1.5f;  // KHR_materials_ior: the dielectric part's index of refraction (0: F0 = 1)
    /// KHR_materials_pbrSpecularGlossiness (color and alpha are then the diffuse factor,
    /// textures.baseColor the diffuse texture, textures.metallicRoughness the specular-glossiness
    /// texture), KHR_materials_specular, KHR_materials_clearcoat, KHR_materials_sheen,
    /// KHR_materials_transmission and KHR_materials_volume.
    raster::BrdfExtensions brdf;
    glm::vec3 emissive{0.0f};  // linear RGB factor
    float normalScale = 1.0f, occlusionStrength = 1.0f;
    std::vector<float> alphas;         // per position, when vertex colours carry alpha
    std::vector<glm::vec2> texCoords;  // per position, when the mesh is textured
    std::vector<glm::vec4> tangents;   // per position (xyz, handedness w), with a normal map
    MeshTextures textures;

    size_t triangleCount() const { return indices.size() / 3; }
    /// Drawn after the opaque meshes, back to front, without depth writes, and left out of shadow
    /// casters and receivers: blended, or transmitting light (KHR_materials_transmission).
    bool seeThrough() const { return alphaMode == raster::AlphaMode::Blend || (metallicRoughness && !unlit && brdf.transmission > 0.0f); }
};

/// Area-weighted vertex normals from the triangles (the cross product's length is twice the
/// area, so summing unnormalised face normals weights them by area). Vertices no triangle
/// uses get (0, 0, 1).
void computeVertexNormals(Mesh& mesh);

/// Per-vertex tangents from the texture coordinates (area-weighted sums of each triangle's
/// dP/du, handedness from dP/dv), for normal maps on meshes that carry none. Vertices whose
/// UVs are degenerate get a tangent perpendicular to their normal.
void computeVertexTangents(Mesh& mesh);

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
