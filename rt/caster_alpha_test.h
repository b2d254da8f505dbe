#pragma once
// Alpha-tested casters for the shadow stage's rays: a shadow or occlusion ray that meets an
// alpha-tested caster (a leaf, a fence, glTF's alphaMode MASK) is blocked only where the
// material's alpha there passes its cutoff, so light goes through the holes — an any-hit
// shader's work, given to every traversal through rt::HitFilter (rt/ray.h), so the grid, both
// BVHs, their packets and brute force still answer alike.
//
// The alpha is the frame's (rt::CasterAlphaTest): the base colour factor's alpha, times the
// vertex alphas interpolated at the hit, times the base colour texture's alpha at the hit's
// texture coordinates. A shadow ray has no pixel footprint to choose a level of detail from, so
// the texture is read at its finest level, through its own magnification filter (what a GPU
// any-hit shader without ray cones reads: kShadowRayTextureLod). The camera sees the same holes
// at the level of detail of its pixel (rt/primary_rays.h); the two agree wherever the texture's
// finest level and the level a pixel reads agree about the cutoff.
//
// A shadow map draws the range through the rasterizer's alpha test at each texel's level of
// detail (rt/shadow_map.h), which need not be the finest: hybrid shadows stay the ray-traced
// image because each alpha-tested triangle marks every texel it covers as a thin caster does
// (rt/shadows.cpp), and the receivers behind it take rays.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "raster/draw.h"
#include "rt/ray.h"

namespace cuberille::rt {

/// What the rasterizer's alpha test reads of an alpha-tested range (raster::AlphaMode::Mask): the
/// alpha is the factor times the vertex alphas (when present), times the base colour texture's
/// alpha, against the cutoff. The visibility buffer (rt/screen_surfaces.h) and the shadow maps
/// (rt/shadow_map.h) draw the range through the shade stage's own alpha test, at each pixel's or
/// texel's level of detail; shadow rays test it at their hits (CasterAlphaFilter, below).
struct CasterAlphaTest {
    float cutoff = 0.5f;
    float factor = 1.0f;                   // the base colour factor's alpha
    std::span<const float> vertexAlphas;   // per vertex of the range; empty: none
    std::span<const glm::vec2> texCoords;  // per vertex of the range; empty: no texture
    /// The base colour texture with its colour set to white (alphaTestTexture): its alpha, the
    /// same bits as the material's, and a colour that leaves the drawn id untouched.
    raster::TextureBinding alphaOnly;
};

/// A run of caster triangles drawn as one draw call (one mesh of the scene), with its culling.
struct CasterRange {
    uint32_t firstTriangle = 0, triangleCount = 0;
    uint32_t firstVertex = 0, vertexCount = 0;  // the vertices its triangles use
    raster::CullMode cull = raster::CullMode::None;
    std::optional<CasterAlphaTest> alphaTest;  // an alpha-tested range: its holes are seen and lit through
};

/// Whether any of the ranges is alpha-tested (else the casters are drawn and traced as opaque).
bool anyAlphaTested(std::span<const CasterRange> ranges);

/// The draw state that runs an alpha-tested range through the shade stage's alpha test and no
/// more: Unlit and white (the factor's alpha kept), its white-coloured texture where the range has
/// coordinates, cut at the cutoff. The caller sets the culling and colour writes.
raster::DrawState alphaTestedState(const CasterAlphaTest& test);

/// The level of detail a shadow ray's alpha test reads the base colour texture at: the finest.
inline constexpr float kShadowRayTextureLod = 0.0f;

class CasterAlphaFilter {
public:
    CasterAlphaFilter() = default;
    // The filter it hands out points back at it.
    CasterAlphaFilter(const CasterAlphaFilter&) = delete;
    CasterAlphaFilter& operator=(const CasterAlphaFilter&) = delete;

    /// The casters as the stage concatenates them: `ranges` over `indices` (three a triangle,
    /// into the casters' vertex array). Both must outlive the filter's use.
    void reset(std::span<const CasterRange> ranges, std::span<const uint32_t> indices);

    /// The rays' filter; null when no caster is alpha tested (the rays then test nothing more).
    const HitFilter* filter() const { return alphaTested_ ? &filter_ : nullptr; }
    /// Whether caster triangle t is alpha tested (false for every t when filter() is null).
    bool alphaTested(uint32_t t) const { return alphaTested_ && filter_.alphaTests(t); }

    /// Whether the material's alpha at weights (u, v) of triangle t's second and third vertices
    /// passes its range's cutoff.
    bool passes(uint32_t triangle, float u, float v) const;

private:
    static bool passesFilter(const void* self, uint32_t triangle, const Ray&, float u, float v) {
        return static_cast<const CasterAlphaFilter*>(self)->passes(triangle, u, v);
    }

    std::span<const CasterRange> ranges_;
    std::span<const uint32_t> indices_;
    std::vector<uint8_t> entries_;  // per caster triangle: HitFilter::kKept or kAlphaTested
    bool alphaTested_ = false;
    HitFilter filter_;
};

}  // namespace cuberille::rt
