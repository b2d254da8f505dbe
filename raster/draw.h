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
#include <span>

#include <glm/glm.hpp>

namespace cuberille::raster {

enum class PositionSpace : uint8_t {
    Clip,    // positions are object space, transformed by clipFromObject
    Window,  // positions are already (x, y) in pixels and z in [0, 1]: no transform, w = 1
};

enum class CullMode : uint8_t { None, Back, Front };

/// Compile-time specialised shading models: the back end is instantiated once per model, so
/// a draw pays only for what its model reads (no varyings at all for ConstantColor).
enum class ShadingModel : uint8_t {
    ConstantColor,  // one colour per triangle (or per draw); no interpolation
    Lambert,        // interpolated normal and colour, one directional light plus ambient
    TexturedLambert,  // Lambert with albedo x baseColorTexture(uv), trilinear filtering
    Unlit,            // the interpolated colour alone, no lighting (KHR_materials_unlit)
    TexturedUnlit,    // Unlit with albedo x baseColorTexture(uv)
};

class Texture;

struct DirectionalLight {
    glm::vec3 directionToLight{0.0f, 1.0f, 0.0f};  // world space, normalised
    glm::vec3 radiance{1.0f};                       // linear RGB
    glm::vec3 ambient{0.0f};                        // linear RGB, added unshadowed
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

struct DrawState {
    ShadingModel shading = ShadingModel::ConstantColor;
    CullMode cull = CullMode::None;
    bool depthTest = true;  // LESS against the sample's stored depth
    bool depthWrite = true;
    uint8_t colorWriteMask = kWriteAll;
    /// Per-draw counter of samples that passed the depth test (an occlusion query slot);
    /// -1 for none. Slots are indices into PipelineStats::occlusionSamplesPassed.
    int occlusionSlot = -1;
    glm::vec4 constantColor{1.0f};  // used when there are no per-triangle or per-vertex colours
    DirectionalLight light;
    const Texture* baseColorTexture = nullptr;  // TexturedLambert; must outlive the frame
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;  // Mask
};

struct DrawCall {
    PositionSpace space = PositionSpace::Clip;
    glm::mat4 clipFromObject{1.0f};
    glm::mat3 worldFromObjectNormals{1.0f};  // for Lambert: normals to world (light) space

    std::span<const glm::vec3> positions;
    std::span<const uint32_t> indices;          // empty: non-indexed, three vertices a triangle
    std::span<const glm::vec3> normals;         // per vertex; Lambert needs them
    std::span<const glm::vec3> vertexColors;    // per vertex, linear RGB; optional
    std::span<const glm::vec4> triangleColors;  // per triangle, linear RGBA; ConstantColor only
    std::span<const glm::vec2> texCoords;       // per vertex; TexturedLambert

    DrawState state;

    size_t triangleCount() const {
        return indices.empty() ? positions.size() / 3 : indices.size() / 3;
    }
};

}  // namespace cuberille::raster
