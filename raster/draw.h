#pragma once
// What a caller hands the software GPU: one draw call = geometry + pipeline state.
//
// Conventions (DESIGN.md, raster conventions):
// - Clip space as in Direct3D/Vulkan: visible when -w <= x, y <= w and 0 <= z <= w; NDC y
//   points up and the viewport flips it, so window y points down.
// - Window space: pixels, origin top-left, pixel (x, y) covers [x, x+1) x [y, y+1).
// - Front faces are counter-clockwise as seen on screen (glTF's convention).
// The spans must stay valid until Pipeline::endFrame() returns (draws are recorded, like a
// GPU command buffer, and executed in flushes).

#include <cstdint>
#include <limits>
#include <span>

#include <glm/glm.hpp>

namespace cuberille::raster {

enum class PositionSpace : uint8_t {
    Clip,    // positions are object space, transformed by clipFromObject
    Window,  // positions are already (x, y) in pixels and z in [0, 1]: no transform, w = 1
};

enum class CullMode : uint8_t { None, Back, Front };

/// Lighting models, each a compile-time specialisation of the shade stage (raster/shade.h), so a
/// draw pays only for what its model reads: ConstantColor interpolates nothing, Unlit no normal,
/// Lambert no position or view vector. Textures multiply in whenever they are bound.
enum class ShadingModel : uint8_t {
    ConstantColor,      // one colour per triangle (or per draw); no interpolation
    Unlit,              // the interpolated colour alone (KHR_materials_unlit)
    Lambert,            // albedo x (ambient + sum of lights' irradiance x max(0, n.l))
    MetallicRoughness,  // glTF's metallic-roughness BRDF (raster/shade.h, docs/conventions.md)
};

class Texture;
class EnvironmentLight;

enum class LightType : uint8_t { Directional, Point, Spot };

/// A punctual light (KHR_lights_punctual). Units: `intensity` is what a white Lambertian
/// surface facing the light shows (for point and spot lights, at distance 1), i.e. pi times
/// the irradiance of glTF's convention — so Lambert needs no 1/pi and the BRDF scales by pi.
struct Light {
    LightType type = LightType::Directional;
    glm::vec3 position{0.0f};                 // world space; Point and Spot
    glm::vec3 direction{0.0f, -1.0f, 0.0f};   // world space, normalised, the way light travels
    glm::vec3 intensity{1.0f};                // linear RGB
    float range = 0.0f;                       // Point and Spot; 0: unlimited
    float cosInnerCone = 1.0f, cosOuterCone = 0.70710678f;  // Spot
    /// A screen-space shadow mask, like the one a deferred GPU renderer reads: the fraction of
    /// the light reaching the surface seen at each pixel of the target (row-major, the target's
    /// width; 1 = lit). Null: unshadowed. Computed before the frame by rt/shadows.h; the shade
    /// stage only multiplies it in, so raster/ knows nothing of how shadows are found.
    const float* visibility = nullptr;
    /// The share of the light's specular term the shade stage adds (1: all of it). 0 for a light
    /// that stands in for an environment's dominant direction, whose reflection the environment's
    /// own specular levels already hold (raster/environment_light.h).
    float specular = 1.0f;
};

inline constexpr int kMaxLights = 8;

struct Lighting {
    glm::vec3 ambient{0.0f};  // linear RGB, added unshadowed (times occlusion)
    Light lights[kMaxLights];
    int lightCount = 0;
    /// Image-based lighting (raster/environment_light.h), added unshadowed (times occlusion) to
    /// the lit models besides the ambient term; null: none. Must outlive the frame.
    const EnvironmentLight* environment = nullptr;
    /// Per pixel (y x width + x), a factor on the ambient and environment terms, multiplied in
    /// where a material's occlusion texture is: the ambient occlusion the ray stage found
    /// (rt/ambient_occlusion.h). Null: none. Must outlive the frame.
    const float* ambientVisibility = nullptr;
    /// With an environment: a light of `lights` stands for its dominant direction, so the shade
    /// stage takes the irradiance without it (EnvironmentLight::shIrradianceLessDominant).
    bool environmentLessDominantLight = false;

    static Lighting directional(const glm::vec3& directionToLight, const glm::vec3& intensity,
                                const glm::vec3& ambient) {
        Lighting l;
        l.ambient = ambient;
        l.lights[0].direction = -directionToLight;
        l.lights[0].intensity = intensity;
        l.lightCount = 1;
        return l;
    }
};

/// An affine map applied to texture coordinates before sampling (KHR_texture_transform):
/// uv' = linear * uv + offset.
struct UvTransform {
    glm::mat2 linear{1.0f};
    glm::vec2 offset{0.0f};
    glm::vec2 apply(const glm::vec2& uv) const { return linear * uv + offset; }
    bool isIdentity() const { return linear == glm::mat2(1.0f) && offset == glm::vec2(0.0f); }
};

struct TextureBinding {
    const Texture* texture = nullptr;  // must outlive the frame; null: unbound
    UvTransform transform;
    explicit operator bool() const { return texture != nullptr; }
};

/// glTF's material texture slots. All read the draw's one set of texture coordinates.
struct MaterialTextures {
    TextureBinding baseColor;          // colour, fetched as linear RGBA (an image's sRGB decoded by the texture), x albedo
    TextureBinding metallicRoughness;  // B: metallic, G: roughness, x the factors (specular-glossiness: RGB specular, A glossiness)
    TextureBinding normal;             // tangent space, needs tangents
    TextureBinding occlusion;          // R: ambient occlusion
    TextureBinding emissive;           // linear RGB, x the emissive factor
    TextureBinding specular;           // A: the dielectric specular strength, x BrdfExtensions::specularStrength
    TextureBinding specularColor;      // linear RGB (sRGB decoded): the dielectric F0 colour, x specularColor
    TextureBinding clearcoat;          // R: the clear coat's weight, x BrdfExtensions::clearcoat
    TextureBinding clearcoatRoughness; // G: the clear coat's roughness, x BrdfExtensions::clearcoatRoughness
    TextureBinding clearcoatNormal;    // the clear coat's own normal map (tangent space, needs tangents)
    TextureBinding sheenColor;         // linear RGB (sRGB decoded): the sheen's colour, x BrdfExtensions::sheenColor
    TextureBinding sheenRoughness;     // A: the sheen's roughness, x BrdfExtensions::sheenRoughness
    TextureBinding transmission;       // R: the share transmitted, x BrdfExtensions::transmission
    TextureBinding thickness;          // G: the volume's thickness, x BrdfExtensions::thickness
    bool any() const {
        return baseColor || metallicRoughness || normal || occlusion || emissive || specular || specularColor || clearcoat ||
               clearcoatRoughness || clearcoatNormal || sheenColor || sheenRoughness || transmission || thickness;
    }
};

/// Per-channel colour write mask; a visibility-only draw (occlusion test) writes none.
enum ColorWriteBits : uint8_t {
    kWriteRed = 1,
    kWriteGreen = 2,
    kWriteBlue = 4,
    kWriteAlpha = 8,
    kWriteAll = 15,
};

/// How a draw's alpha (material alpha x texture alpha) is used (glTF's alphaMode).
enum class AlphaMode : uint8_t {
    Opaque,  // ignored
    Mask,    // a pixel whose alpha is below alphaCutoff is discarded: no colour, no depth
    Blend,   // over-blended onto the target: src * a + dst * (1 - a)
};

/// How glTF's material extensions change the MetallicRoughness BRDF (raster/shade.h). A scene
/// mesh holds one (scene::Mesh::brdf) and a draw copies it; the defaults change nothing.
struct BrdfExtensions {
    /// The BRDF fed from the specular-glossiness material model instead
    /// (KHR_materials_pbrSpecularGlossiness): c_diff = diffuse (1 - max(specular)), F0 =
    /// specular, alpha = (1 - glossiness)²; the metallicRoughness slot then holds the
    /// specular-glossiness texture (RGB specular, A glossiness), and metallic, roughness and
    /// dielectricF0 are not read.
    bool specularGlossiness = false;
    glm::vec3 specularFactor{1.0f};
    float glossiness = 1.0f;
    /// KHR_materials_specular: the dielectric part's F0 becomes min(dielectricF0 x specularColor,
    /// 1) x specularStrength and its F90 specularStrength (times the specular and specularColor
    /// textures where bound); F90 = mix(that, 1, metallic).
    bool dielectricSpecular = false;
    float specularStrength = 1.0f;
    glm::vec3 specularColor{1.0f};
    /// KHR_materials_clearcoat (> 0): a GGX layer of this weight and roughness over the whole
    /// material, emission included, following its own normal map, or the surface's normal
    /// before normal mapping.
    float clearcoat = 0.0f, clearcoatRoughness = 0.0f;
    float clearcoatNormalScale = 1.0f;
    /// KHR_materials_sheen (a colour > 0): a microfibre layer of this colour and roughness over
    /// the material, which it dims by its albedo (raster/sheen_lobe.h), under any clear coat.
    glm::vec3 sheenColor{0.0f};
    float sheenRoughness = 0.0f;
    /// KHR_materials_transmission (> 0): this share of the dielectric's diffuse lobe is light
    /// passed straight through instead: the draw's pixels multiply what is behind them by their
    /// transmittance t (1 - F) c_diff and add their own light (output merge's transmitColor).
    /// Seen straight through — no refraction, no blur by roughness (docs/formats.md).
    float transmission = 0.0f;
    /// KHR_materials_volume, with transmission: over a thickness > 0 (world units, times the
    /// thickness texture), the light is attenuated to attenuationColor every attenuationDistance
    /// (Beer-Lambert); 0 is thin-walled.
    float thickness = 0.0f;
    glm::vec3 attenuationColor{1.0f};
    float attenuationDistance = std::numeric_limits<float>::infinity();
};

struct DrawState {
    ShadingModel shading = ShadingModel::ConstantColor;
    CullMode cull = CullMode::None;
    bool depthTest = true;  // LESS against the sample's stored depth
    bool depthWrite = true;
    uint8_t colorWriteMask = kWriteAll;
    /// Per-draw counter of samples that passed the depth test (an occlusion query slot);
    /// -1 for none. Slots are indices into PipelineStats::occlusionSamplesPassed.
    int occlusionSlot = -1;
    glm::vec4 constantColor{1.0f};  // base colour factor; times per-vertex colours when present
    Lighting lighting;              // Lambert and MetallicRoughness
    MaterialTextures textures;      // bound slots need texCoords (normal also tangents)
    float metallic = 1.0f, roughness = 1.0f;  // MetallicRoughness factors
    /// MetallicRoughness: the reflectance of the dielectric part at normal incidence, F0 =
    /// ((ior - 1) / (ior + 1))² (glTF's 1.5 gives 0.04; KHR_materials_ior sets others).
    float dielectricF0 = 0.04f;
    BrdfExtensions brdf;  // MetallicRoughness: inputs from other material models, and a clear coat
    glm::vec3 emissive{0.0f};                 // linear RGB factor; Lambert and MetallicRoughness
    float normalScale = 1.0f, occlusionStrength = 1.0f;
    glm::vec3 cameraPosition{0.0f};  // world space: the view vector of MetallicRoughness
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;  // Mask
    /// Whether output merge composes the draw's pixels over what is behind them through a
    /// per-channel transmittance (KHR_materials_transmission on the metallic-roughness model).
    bool transmits() const { return shading == ShadingModel::MetallicRoughness && brdf.transmission > 0.0f; }
};

struct DrawCall {
    PositionSpace space = PositionSpace::Clip;
    glm::mat4 clipFromObject{1.0f};
    glm::mat4 worldFromObject{1.0f};         // positions to world (light) space, for lighting
    glm::mat3 worldFromObjectNormals{1.0f};  // normals (and tangents' xyz) to world space

    std::span<const glm::vec3> positions;
    std::span<const uint32_t> indices;          // empty: non-indexed, three vertices a triangle
    std::span<const glm::vec3> normals;         // per vertex; Lambert needs them
    std::span<const glm::vec3> vertexColors;    // per vertex, linear RGB; optional
    std::span<const float> vertexAlphas;        // per vertex; optional
    std::span<const glm::vec4> triangleColors;  // per triangle, linear RGBA; ConstantColor only
    std::span<const glm::vec2> texCoords;       // per vertex; needed by bound textures
    std::span<const glm::vec4> tangents;        // per vertex, xyz + handedness w; normal maps

    DrawState state;

    size_t triangleCount() const {
        return indices.empty() ? positions.size() / 3 : indices.size() / 3;
    }
};

}  // namespace cuberille::raster
